"""The report's findings page (findings.html): how often the top finding names the bug, from a
saved `tools/bench_findings.py --json` run (the confusion table of wrapper renderers that
each have one known bug)."""
from __future__ import annotations

import json
from html import escape
from pathlib import Path

from .html import page


class FindingsFileError(ValueError):
    """Not a findings benchmark file (the message says why)."""


def read_findings(path: Path) -> dict:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict) or not isinstance(data.get("rows"), list) or \
                not all(_row(r) for r in data["rows"]) or \
                not all(isinstance(data.get(k, 0), int) for k in ("named", "total")):
            raise ValueError("no rows of defect, failing, named and seen, or counts that are "
                             "not integers")
    except (OSError, ValueError) as e:
        raise FindingsFileError(f"{path}: not a tools/bench_findings.py --json file ({e})"
                                ) from None
    return data


def _row(r) -> bool:
    """A row as the benchmark writes it: counts as ints, seen as code -> int."""
    return isinstance(r, dict) and isinstance(r.get("defect"), str) and \
        all(isinstance(r.get(k), int) and not isinstance(r.get(k), bool)
            for k in ("failing", "named")) and isinstance(r.get("seen"), dict) and \
        all(isinstance(n, int) for n in r["seen"].values())


def findings_page(data: dict) -> str:
    rows = []
    for r in data["rows"]:
        seen = ", ".join(f"{escape(str(code))} {n}" for code, n in r["seen"].items())
        if r["defect"] == "none":
            rows.append(f"<tr class=\"pass\"><td>none (the tracer)</td><td>{r['failing']}</td>"
                        f"<td>-</td><td>{seen or 'no finding, no failure'}</td></tr>")
            continue
        share = f"{r['named']}/{r['failing']} ({r['named'] / r['failing']:.0%})" \
            if r["failing"] else "0/0"
        rows.append(f"<tr><td>{escape(r['defect'])}</td><td>{r['failing']}</td>"
                    f"<td>{share}</td><td>{seen}</td></tr>")
    total = data.get("total") or 0
    summary = (f"{data.get('named', 0)}/{total} top findings name their defect "
               f"({data.get('named', 0) / total:.1%})" if total else "no failing kinds")
    return page("raycheck findings", (
        "<h1>Findings: which bug does the top finding name?</h1><p>Renderers that each have "
        "exactly one known bug (tests/wrappers), checked against the tracer on the bundled "
        f"scenes at {data.get('size', '?')}x{data.get('size', '?')} in the features the bug "
        "breaks: per bug, its failing image kinds, how many have a top finding that names it, "
        f"and the top findings seen (\"-\": none). {summary}; the tracer itself: "
        f"{data.get('tracer_findings', '?')} findings. Run of {escape(str(data.get('date')))}"
        ". <a href=\"index.html\">Comparison report</a>.</p><table><thead><tr><th>bug</th>"
        "<th>failing kinds</th><th>top finding names it</th><th>top findings seen</th></tr>"
        "</thead><tbody>" + "".join(rows) + "</tbody></table>"))


def write_findings_page(data: dict, folder: Path) -> Path:
    path = folder / "findings.html"
    path.write_text(findings_page(data), encoding="utf-8")
    return path
