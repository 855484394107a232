"""Requirement or quirk (harness/diagnosis/quirks.py): a renderer that follows the handouts where
the course program has a quirk (here: it mirrors every material, where the course program only
mirrors one whose |ks| > 0.1) passes with a note, and gets full points in grade; with
--strict it fails. The tracer in course mode (byte for byte the course program on the bundled
scenes: tests/tracer/test_course_program.py) passes both ways, without a note."""
from __future__ import annotations

import csv
import io
import json
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from raycheck.harness.cli.check import main as check_main
from raycheck.harness.cli.grade import main as grade_main

REPO = Path(__file__).resolve().parents[2]
BOUNCES = REPO / "scenes" / "features" / "bounces.txt"  # a mirror with |ks| < 0.1 beside others
TRACER = f"{sys.executable} -m raycheck.tracer"
HANDOUT = f"{TRACER} --mistake reflection_gate=0"  # mirrors every material


def check(renderer: str, out: Path, *extra: str) -> tuple[int, list[dict]]:
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
        code = check_main(["--renderer", renderer, str(BOUNCES), "--features", "bounces",
                           "--size", "24", "24", "--out", str(out), "-j", "1", "--quiet",
                           *extra])
    return code, json.loads((out / "check.json").read_text())["cases"]


@pytest.mark.parametrize("strict", [False, True])
def test_a_program_that_follows_the_handouts_passes_unless_strict(tmp_path, strict):
    code, cases = check(HANDOUT, tmp_path / "out", *(["--strict"] if strict else []))
    color = next(c for c in cases if c["kind"] == "color")
    assert color["quirks"] == ["mirror_gate"]
    assert color["findings"][0]["code"] == "quirk:mirror_gate"
    assert "only mirrors a material whose specular color has a Euclidean length above " \
           "0.1" in color["findings"][0]["message"]
    if strict:
        assert (code, color["verdict"]) == (1, "fail")
        assert "with --strict it counts" in color["findings"][0]["message"]
    else:
        assert (code, color["verdict"], color["failures"]) == (0, "pass", [])
        assert "it is not counted" in color["findings"][0]["message"]


@pytest.mark.parametrize("strict", [False, True])
def test_the_course_program_passes_both_ways_without_a_note(tmp_path, strict):
    code, cases = check(TRACER, tmp_path / "out", *(["--strict"] if strict else []))
    assert code == 0
    assert [(c["kind"], c["verdict"], c["findings"]) for c in cases] == \
        [("color", "pass", [])]
    assert cases[0]["quirks"] == ["mirror_gate"]  # quirk-sensitive all the same


def test_a_quirk_does_not_excuse_a_mistake_beside_it(tmp_path):
    """The cause search names both, and says which of them is the quirk."""
    code, cases = check(f"{HANDOUT} --mistake reflection_unweighted", tmp_path / "out")
    assert code == 1 and cases[0]["verdict"] == "fail"
    first, second = cases[0]["findings"][:2]
    assert (first["code"], second["code"]) == ("cause:reflection_unweighted",
                                               "cause:reflection_gate")
    assert "together with reflection_gate=0 (a quirk of the course program's)" in \
        first["message"]
    assert "The handouts do not ask for this: not counted unless --strict" in \
        second["message"]


def test_grade_scores_what_the_handouts_require_and_lists_the_quirks(tmp_path):
    rows = {}
    for strict in (False, True):
        out = tmp_path / f"class-{strict}"
        with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
            assert grade_main([f"handout={HANDOUT}", f"course={TRACER}", "--scenes",
                               str(BOUNCES), "--features", "bounces", "--size", "24", "24",
                               "--out", str(out), "-j", "1", "--quiet", "--sandbox", "off",
                               *(["--strict"] if strict else [])]) == 0
        grades = json.loads((out / "grades.json").read_text())["submissions"]
        rows[strict] = {g["name"]: (g["score"], g["quirks"]) for g in grades}
        assert next(csv.DictReader(io.StringIO((out / "grades.csv").read_text())))
    assert rows[False] == {"handout": (15.0, ["mirror_gate"]), "course": (15.0, [])}
    assert rows[True] == {"handout": (0.0, ["mirror_gate"]), "course": (15.0, [])}
