"""The report's findings page from a saved findings benchmark (tools/bench_findings.py
--json): its rows as the benchmark counted them, and files that are not one refused."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from raycheck.harness.pages.findingspage import FindingsFileError, findings_page, read_findings

RUN = {"rows": [{"defect": "gamma", "failing": 32, "named": 31,
                 "seen": {"gamma_encoded": 31, "term_scaled:ambient": 1}},
                {"defect": "none", "failing": 0, "named": 0, "seen": {}}],
       "named": 31, "total": 32, "target": 0.9, "tracer_findings": 0, "size": 24,
       "seconds": 3.0, "date": "2026-12-01"}


def test_the_page_has_each_bug_with_its_share_and_the_tracer_row(tmp_path: Path):
    path = tmp_path / "f.json"
    path.write_text(json.dumps(RUN))
    html = findings_page(read_findings(path))
    assert "<tr><td>gamma</td><td>32</td><td>31/32 (97%)</td><td>gamma_encoded 31, " \
           "term_scaled:ambient 1</td></tr>" in html
    assert "<td>none (the tracer)</td><td>0</td><td>-</td><td>no finding, no failure</td>" in html
    assert "31/32 top findings name their defect (96.9%); the tracer itself: 0 findings" in html
    assert "at 24x24" in html


ROW = '{"defect": "x", "failing": 1, "named": %s, "seen": %s}'


@pytest.mark.parametrize("text", [
    "{}", "[1]", '{"rows": [{"defect": "x"}]}', "not json",
    '{"rows": [%s]}' % (ROW % ('"1"', "{}")), '{"rows": [%s]}' % (ROW % ("1", "[]")),
    '{"rows": [], "total": "3"}'])
def test_other_files_are_refused_with_their_name(tmp_path: Path, text: str):
    path = tmp_path / "f.json"
    path.write_text(text)
    with pytest.raises(FindingsFileError, match="f.json: not a tools/bench_findings.py --json"):
        read_findings(path)
