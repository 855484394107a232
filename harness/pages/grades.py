"""The class page of `raycheck grade`: a histogram of the scores, then one sortable row per
submission (score, how its build went, cases passed per feature family with the top finding
of the family's failing cases, crashes, timeouts, a link to its report), with the index's
table script; then the mistakes found in the class, each with the submissions that make it."""
from __future__ import annotations

from html import escape

from ..records import ClassMistake, GradeRow
from .html import INDEX_JS, num_cell, page, provenance_block

MISTAKES_JS = """
const mt=document.getElementById('mistakes');
if(mt){const body=mt.tBodies[0];let col=-1,dir=1;
mt.tHead.querySelectorAll('th').forEach((th,i)=>th.addEventListener('click',()=>{
  dir=(col===i)?-dir:1;col=i;
  const key=r=>{const c=r.cells[i];return c.dataset.v!==undefined?parseFloat(c.dataset.v)
:c.textContent;};
  [...body.rows].sort((a,b)=>{const x=key(a),y=key(b);
    return (typeof x==='number'?x-y:String(x).localeCompare(String(y)))*dir;})
  .forEach(r=>body.appendChild(r));}));}
"""


def mistakes_table(mistakes: tuple[ClassMistake, ...], reports: dict[str, str]) -> str:
    """Which submissions make which mistake: a sortable row per mistake, its submissions
    linked to their reports (reports: name -> report)."""
    if not mistakes:
        return ('<h2>Mistakes in the class</h2><p id="no-mistakes">No known mistake found in '
                "any submission.</p>")
    rows = "".join(
        f"<tr><td><code>{escape(m.mistake)}</code></td><td>{escape(m.function)}</td>"
        f"<td>{escape(m.description)}</td>" + num_cell(len(m.submissions), "{:d}")
        + "<td>" + ", ".join(f'<a href="{escape(reports.get(n, ""))}">{escape(n)}</a>'
                             for n in m.submissions) + "</td></tr>" for m in mistakes)
    return ("<h2>Mistakes in the class</h2><p>Each mistake raycheck found (its cause search: "
            "the reference with the mistake reproduces the submission's images), with the "
            "submissions that make it. A header sorts.</p>"
            '<table id="mistakes"><thead><tr><th>mistake</th><th>function</th><th>what the '
            "program does</th><th>submissions</th><th>who</th></tr></thead>"
            f"<tbody>{rows}</tbody></table>")


def grades_page(rows: list[GradeRow], points: dict[str, float], prov: dict[str, str],
                mistakes: tuple[ClassMistake, ...] = ()) -> str:
    families = [f for f in points if any(r.families[f].total for r in rows)]
    head = ("<tr><th>submission</th><th>score</th><th>build</th>"
            + "".join(f'<th title="{points[f]:g} points">{escape(f)}</th>' for f in families)
            + "<th>cases passed</th><th>crashes</th><th>timeouts</th><th>errors</th></tr>")
    body = []
    for r in rows:
        cells = []
        for f in families:
            fam = r.families[f]
            share = fam.passed / fam.total if fam.total else float("nan")
            cause = r.causes.get(f)
            note = f'<br><small class="cause">{escape(cause)}</small>' if cause else ""
            cells.append(f'<td class="num" data-v="{share!r}">{fam.passed}/{fam.total}{note}'
                         "</td>")
        status = "pass" if r.passed == r.cases else "error" if r.errors or r.build_error \
            else "fail"
        build = escape(r.build) if r.build_log is None else \
            f'<a href="{escape(r.build_log)}" title="{escape(r.build_error)}">{escape(r.build)}</a>'
        body.append(
            f'<tr class="{status}"><td><a href="{escape(r.report)}">{escape(r.name)}</a>'
            "</td>" + num_cell(r.score, "{:g}") + f"<td>{build}</td>" + "".join(cells)
            + num_cell(r.passed, "{:d}") + num_cell(r.crashes, "{:d}")
            + num_cell(r.timeouts, "{:d}") + num_cell(r.errors, "{:d}") + "</tr>")
    weights = ", ".join(f"{escape(f)} {points[f]:g}" for f in families)
    max_score = max((r.max_score for r in rows), default=0)
    html_body = (
        "<h1>raycheck grade</h1>"
        f"<p id=\"summary\">{len(rows)} submissions, each checked on every case; score out of "
        f"{max_score:g} points: per feature family its points times the share of its cases "
        f"that pass ({weights}). A case passes when every image kind of it does. A column "
        "header sorts; a name opens that submission's report, a build its log; under a "
        "family's count, the top finding of its failing cases. "
        '<a href="grades.csv">grades.csv</a>, <a href="grades.json">grades.json</a>.</p>'
        + score_histogram([r.score for r in rows], max_score) +
        '<div class="filters"><input id="text" placeholder="search"> <span id="count"></span>'
        f'</div><table id="cases"><thead>{head}</thead><tbody>{"".join(body)}</tbody></table>'
        + mistakes_table(mistakes, {r.name: r.report for r in rows})
        + provenance_block(prov))
    return page("raycheck grade", html_body, INDEX_JS + MISTAKES_JS)


HISTOGRAM_BINS = 10


def score_histogram(scores: list[float], max_score: float) -> str:
    """An SVG bar chart: how many submissions scored in each tenth of max_score (the last bin
    holds full marks)."""
    if not scores or max_score <= 0:
        return ""
    counts = [0] * HISTOGRAM_BINS
    for score in scores:
        counts[min(HISTOGRAM_BINS - 1, int(HISTOGRAM_BINS * score / max_score))] += 1
    width, height, bar = 40 * HISTOGRAM_BINS, 120, 36
    top = max(counts)
    parts = []
    for k, n in enumerate(counts):
        h = round(90 * n / top)
        low = max_score * k / HISTOGRAM_BINS
        parts.append(f'<rect x="{40 * k + 2}" y="{100 - h}" width="{bar}" height="{h}" '
                     f'fill="#4a78b5"><title>{low:g} to {low + max_score / HISTOGRAM_BINS:g}:'
                     f" {n}</title></rect>"
                     + (f'<text x="{40 * k + 20}" y="{96 - h}" text-anchor="middle" '
                        f'font-size="11">{n}</text>' if n else "")
                     + f'<text x="{40 * k + 2}" y="114" font-size="10">{low:g}</text>')
    return (f'<figure id="histogram"><svg width="{width}" height="{height}" role="img" '
            f'aria-label="scores">{"".join(parts)}</svg><figcaption>scores of '
            f"{len(scores)} submissions, out of {max_score:g}</figcaption></figure>")
