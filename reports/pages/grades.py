"""The class page of `raycheck grade`: one sortable row per submission (score, cases passed
per feature family, crashes, timeouts, a link to its report), with the index's table script."""
from __future__ import annotations

from html import escape

from ..records import GradeRow
from .html import INDEX_JS, _num, page, provenance_block


def grades_page(rows: list[GradeRow], points: dict[str, float], prov: dict[str, str]) -> str:
    families = [f for f in points if any(r.families[f].total for r in rows)]
    head = ("<tr><th>submission</th><th>score</th>"
            + "".join(f'<th title="{points[f]:g} points">{escape(f)}</th>' for f in families)
            + "<th>cases passed</th><th>crashes</th><th>timeouts</th><th>errors</th></tr>")
    body = []
    for r in rows:
        cells = []
        for f in families:
            fam = r.families[f]
            share = fam.passed / fam.total if fam.total else float("nan")
            cells.append(f'<td class="num" data-v="{share!r}">{fam.passed}/{fam.total}</td>')
        status = "pass" if r.passed == r.cases else "error" if r.errors else "fail"
        body.append(
            f'<tr class="{status}"><td><a href="{escape(r.report)}">{escape(r.name)}</a>'
            "</td>" + _num(r.score, "{:g}") + "".join(cells)
            + _num(r.passed, "{:d}") + _num(r.crashes, "{:d}")
            + _num(r.timeouts, "{:d}") + _num(r.errors, "{:d}") + "</tr>")
    weights = ", ".join(f"{escape(f)} {points[f]:g}" for f in families)
    max_score = max((r.max_score for r in rows), default=0)
    html_body = (
        "<h1>raycheck grade</h1>"
        f"<p id=\"summary\">{len(rows)} submissions, each checked on every case; score out of "
        f"{max_score:g} points: per feature family its points times the share of its cases "
        f"that pass ({weights}). A case passes when every image kind of it does. A column "
        "header sorts; a name opens that submission's report. "
        '<a href="grades.csv">grades.csv</a>, <a href="grades.json">grades.json</a>.</p>'
        '<div class="filters"><input id="text" placeholder="search"> <span id="count"></span>'
        f'</div><table id="cases"><thead>{head}</thead><tbody>{"".join(body)}</tbody></table>'
        + provenance_block(prov))
    return page("raycheck grade", html_body, INDEX_JS)
