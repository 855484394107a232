"""Static, self-contained HTML pages (no CDN; works from file://): the index and one page per
case. Every piece of scene-derived text goes through html.escape."""
from __future__ import annotations

import json
from dataclasses import dataclass
from html import escape

from ..records import (
    CaseRecord,
    ImageMetrics,
    JitterRecord,
    KindRecord,
    Role,
    SkipRecord,
    Verdict,
    to_json,
)
from .imaging import colormap_css

STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;font-size:13px}th,td{border:1px solid #ccc;padding:3px 6px}
th{background:#f3f3f3;cursor:pointer;position:sticky;top:0}td.num{text-align:right}
tr.fail td{background:#fde8e8}tr.error td{background:#fdf0d8}tr.skip td{color:#777}
.pass{color:#137333}.fail{color:#b3261e}.error{color:#a15c00}
table.matrix td{vertical-align:top;text-align:center;min-width:90px}
table.matrix td.pass{background:#e6f4ea}table.matrix td.fail{background:#fde8e8}
table.matrix td.error{background:#fdf0d8}table.matrix td.none{background:#fafafa;color:#999}
table.matrix img{width:44px;height:44px;image-rendering:pixelated;object-fit:contain}
table.matrix a{color:inherit;text-decoration:none;display:block}
.panels{display:flex;gap:10px;flex-wrap:wrap}.panel{display:flex;flex-direction:column}
.view{width:260px;height:260px;overflow:auto;border:1px solid #aaa;background:#777}
.view img{image-rendering:pixelated;display:block}
.bar{height:10px;width:260px}.scale{display:flex;justify-content:space-between;width:260px;font-size:11px}
.filters select,.filters input{margin-right:8px}code{background:#f5f5f5;padding:1px 3px}
.findings{border-left:4px solid #b3261e;padding:2px 10px;background:#fff5f5;margin:6px 0}
dl.prov{display:grid;grid-template-columns:max-content auto;gap:2px 12px;font-size:13px}
.panels.row{flex-wrap:nowrap;margin-bottom:8px}.panels.row .panel>b{min-height:4.2em}
.panel{width:262px;overflow-wrap:anywhere}
.scroll{overflow-x:auto;max-width:100%}#cases td:last-child{min-width:14em}
.explanation,#diagnosis{border-left:4px solid #1a73e8;padding:2px 12px;background:#f3f7fe;
margin:8px 0}.explanation h2,#diagnosis h2{font-size:18px}
#diagnosis li,.explanation li{margin:4px 0}code{overflow-wrap:anywhere}
table.numbers{margin:6px 0}details#output{margin:12px 0}
"""

INDEX_JS = """
const table=document.getElementById('cases');
const rows=[...table.tBodies[0].rows];
function applyFilters(){
  const f={};document.querySelectorAll('.filters select').forEach(s=>f[s.dataset.col]=s.value);
  const text=document.getElementById('text').value.toLowerCase();
  let shown=0;
  rows.forEach(r=>{let ok=true;
    for(const c in f){if(f[c]&&r.dataset[c]!==f[c])ok=false;}
    if(text&&!r.textContent.toLowerCase().includes(text))ok=false;
    r.style.display=ok?'':'none';if(ok)shown++;});
  document.getElementById('count').textContent=shown+' of '+rows.length+' rows';
}
document.querySelectorAll('.filters select, #text')\
.forEach(e=>e.addEventListener('input',applyFilters));
let sortCol=-1,sortDir=1;
table.tHead.querySelectorAll('th').forEach((th,i)=>th.addEventListener('click',()=>{
  sortDir=(sortCol===i)?-sortDir:1;sortCol=i;
  const key=r=>{const c=r.cells[i];const v=c.dataset.v;\
return v!==undefined?parseFloat(v):c.textContent;};
  rows.sort((a,b)=>{const x=key(a),y=key(b);
    if(typeof x==='number'&&typeof y==='number'){return (isNaN(x)?1:isNaN(y)?-1:x-y)*sortDir;}
    return String(x).localeCompare(String(y))*sortDir;});
  rows.forEach(r=>table.tBodies[0].appendChild(r));}));
applyFilters();
"""

CASE_JS = """
const zoom=document.getElementById('zoom');
function setZoom(){document.querySelectorAll('.view img').forEach(img=>{
  img.style.width=(img.naturalWidth*zoom.value)+'px';img.style.height=(img.naturalHeight*zoom.value)+'px';});}
zoom.addEventListener('input',setZoom);
document.querySelectorAll('.view img').forEach(img=>img.complete?setZoom()\
:img.addEventListener('load',setZoom));
let syncing=false;
document.querySelectorAll('.view').forEach(v=>v.addEventListener('scroll',()=>{
  if(syncing)return;syncing=true;
  document.querySelectorAll('.view').forEach(o=>{if(o!==v){o.scrollLeft=v.scrollLeft;o.scrollTop=v.scrollTop;}});
  syncing=false;}));
function flip(section){const img=section.querySelector('img.flip');
  const next=img.dataset.showing==='candidate'?'reference':'candidate';
  img.src=img.dataset[next];img.dataset.showing=next;
  section.querySelector('.flipname').textContent=img.dataset[next+'Label'];}
document.querySelectorAll('button.flipbtn').forEach(b=>b.addEventListener('click',()=>flip(b.closest('section'))));
document.querySelectorAll('img.flip').forEach(i=>i.addEventListener('click',()=>flip(i.closest('section'))));
document.addEventListener('keydown',e=>{if(e.key==='f'){document.querySelectorAll('section.kind').forEach(flip);}});
"""


def num_cell(v: float | int | None, fmt: str = "{:.4f}") -> str:
    """A table cell of a number, sortable by its value (data-v); a dash for none."""
    if v is None:
        return '<td class="num" data-v="NaN">–</td>'
    return f'<td class="num" data-v="{float(v)!r}">{escape(fmt.format(v))}</td>'


def _metric(metrics: ImageMetrics | None, name: str) -> float | None:
    """A metric of a kind's comparison; none where the image is missing."""
    return None if metrics is None else getattr(metrics, name)


def page(title: str, body: str, script: str = "") -> str:
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{escape(title)}</title><style>{STYLE}</style></head><body>{body}"
            + (f"<script>{script}</script>" if script else "") + "</body></html>\n")


def provenance_block(prov: dict[str, str]) -> str:
    items = "".join(f"<dt>{escape(k)}</dt><dd>{escape(v)}</dd>" for k, v in prov.items())
    return f"<h2>Provenance</h2><dl class=\"prov\">{items}</dl>"


@dataclass(frozen=True)
class OverviewCell:
    """A case in the overview matrix."""

    verdict: str
    page: str
    title: str  # the tooltip: the first failure and the top finding
    thumbs: tuple[tuple[str, str], ...] = ()  # (picture, alt): the candidate and its difference
    note: str = ""  # what the column's family does not say: the case's bounce count


def overview(cells: dict[tuple[str, str], OverviewCell], scenes: list[str],
             families: list[str], skipped: dict[tuple[str, str], str]) -> str:
    """The scenes x feature families matrix: each cell coloured by its case's verdict, with
    thumbnails of the candidate and its difference image, the bounce count where the family
    has one, the top failure as its tooltip; a cell without a case says why (skipped: (scene,
    family) -> reason); scenes with failures or errors first."""
    rank = {"error": 0, "fail": 1, "pass": 2}

    def worst(scene: str) -> int:
        return min((rank[c.verdict] for (s, _), c in cells.items() if s == scene), default=3)

    head = "<tr><th>scene</th>" + "".join(f"<th>{escape(f)}</th>" for f in families) + "</tr>"
    trs = []
    for scene in sorted(scenes, key=lambda s: (worst(s), s)):
        tds = []
        for family in families:
            c = cells.get((scene, family))
            if c is None:
                why = skipped.get((scene, family), "not exercised by this scene")
                tds.append(f'<td class="none" title="{escape(why)}">–</td>')
                continue
            thumbs = "".join(f'<img src="{escape(src)}" alt="{escape(alt)}">'
                             for src, alt in c.thumbs)
            note = f'<br><small>{escape(c.note)}</small>' if c.note else ""
            tds.append(f'<td class="{escape(c.verdict)}" title="{escape(c.title)}">'
                       f'<a href="{escape(c.page)}">{thumbs}<br>{escape(c.verdict)}{note}</a>'
                       f'</td>')
        trs.append(f"<tr><th>{escape(scene)}</th>{''.join(tds)}</tr>")
    return (f'<table class="matrix" id="overview"><thead>{head}</thead>'
            f"<tbody>{''.join(trs)}</tbody></table>")


def summary_line(n: int, counts: dict[str, int], n_skipped: int) -> str:
    """"N comparisons, F failed, E errors, S skipped", the failed count green when zero."""
    failed, errors = counts.get("fail", 0), counts.get("error", 0)
    cls = "pass" if failed == 0 else "fail"
    ecls = "pass" if errors == 0 else "error"
    return (f'{n} comparisons, <span class="{cls}">{failed} failed</span>, '
            f'<span class="{ecls}">{errors} errors</span>, {n_skipped} skipped')


def check_intro(candidate: str, reference: str, tolerance: str, realisations: int,
                jitter_test: str, junit: bool) -> str:
    """The paragraph above a check's matrix: what is compared and how it is judged."""
    return (f"Candidate <b>{escape(candidate)}</b> against the reference "
            f"<b>{escape(reference)}</b>; deterministic images pass within {escape(tolerance)}; "
            f"jittered images by a statistical test against {realisations} realisations of the "
            "reference (per-pixel z, bias, noise level, correlation; "
            f"{escape(jitter_test)}). "
            'A cell opens its case. <a href="check.json">All numbers as JSON</a>'
            + (', <a href="junit.xml">JUnit</a>.' if junit else "."))


def index_page(rows: list[CaseRecord], skips: list[SkipRecord], labels: dict[Role, str],
               intro: str, prov: dict[str, str], title: str, matrix: str = "",
               extra: str = "", opening: str = "") -> str:
    """The index of a check or report: `opening` (a check's diagnosis of the program), the
    counts, the overview matrix, then one sortable, filterable row per case and image kind
    (and per skipped one)."""
    entries = [(row, k) for row in rows for k in row.kinds]
    cols = ("scene", "feature", "kind", "status")  # what the filters select on
    keys = [(r.scene, r.feature, k.kind, str(k.verdict)) for r, k in entries] \
        + [(s.scene, s.feature, s.kind, "skip") for s in skips]

    def data(key: tuple[str, ...]) -> str:
        return "".join(f' data-{c}="{escape(v)}"' for c, v in zip(cols, key))

    filters = "".join(
        f'<label>{c} <select data-col="{c}"><option value="">all</option>'
        + "".join(f'<option value="{escape(v)}">{escape(v)}</option>'
                  for v in sorted({key[i] for key in keys}))
        + "</select></label>" for i, c in enumerate(cols))
    cand, ref = escape(labels[Role.CANDIDATE]), escape(labels[Role.REFERENCE])
    head = ("<tr><th>scene</th><th>feature</th><th>kind</th><th>status</th><th>SSIM</th>"
            "<th>PSNR dB</th><th>within tolerance</th><th>max levels</th><th>mean abs</th>"
            "<th>brightness Δ%</th><th>FLIP</th>"
            f'<th title="{cand}">candidate cold s</th><th title="{cand}">candidate warm s</th>'
            f'<th title="{ref}">reference cold s</th><th title="{ref}">reference warm s</th>'
            "<th>notes</th></tr>")
    body_rows = []
    for key, (r, k) in zip(keys, entries):
        m = k.metrics
        link = f'<a href="{escape(r.page)}">{escape(r.scene)}</a>'
        t_c = r.times.get(Role.CANDIDATE, {})
        t_r = r.times.get(Role.REFERENCE, {})
        note = "16 samples against the reference's distribution" if r.jittered else ""
        body_rows.append(
            f'<tr class="{escape(k.verdict)}"{data(key)}><td>{link}</td>'
            f'<td>{escape(r.feature)}</td>'
            f'<td>{escape(k.kind)}</td>'
            f'<td class="{escape(k.verdict)}">{escape(k.verdict)}</td>'
            + num_cell(_metric(m, "ssim")) + num_cell(_metric(m, "psnr"), "{:.1f}")
            + num_cell(None if m is None or m.beyond_tolerance is None
                       else 1 - m.beyond_tolerance, "{:.2%}")
            + num_cell(_metric(m, "max_levels"), "{:d}")
            + num_cell(_metric(m, "mean_abs"), "{:.2e}")
            + num_cell(_metric(m, "brightness_change_pct"), "{:+.3f}")
            + num_cell(_metric(m, "flip"), "{:.4f}")
            + num_cell(t_c.get("cold_s"), "{:.3f}") + num_cell(t_c.get("warm_s"), "{:.3f}")
            + num_cell(t_r.get("cold_s"), "{:.3f}") + num_cell(t_r.get("warm_s"), "{:.3f}")
            + f"<td>{escape('; '.join(k.failures) or note)}</td></tr>")
    for key, s in zip(keys[len(entries):], skips):
        body_rows.append(f'<tr class="skip"{data(key)}><td>{escape(s.scene)}</td>'
                         f'<td>{escape(s.feature)}</td><td>{escape(s.kind)}</td>'
                         f'<td>skip</td>' + '<td></td>' * 11
                         + f'<td>{escape(s.reason)}</td></tr>')
    counts: dict[str, int] = {}
    for _, k in entries:
        counts[k.verdict] = counts.get(k.verdict, 0) + 1
    summary = (f"<p id=\"summary\">{summary_line(len(entries), counts, len(skips))}. "
               f"{intro}</p>")
    body = (f"<h1>{escape(title)}</h1>{opening}{summary}{matrix}<h2>Every comparison</h2>"
            f"<div class=\"filters\">{filters}"
            f"<input id=\"text\" placeholder=\"search\"> <span id=\"count\"></span></div>"
            f"<div class=\"scroll\"><table id=\"cases\"><thead>{head}</thead>"
            f"<tbody>{''.join(body_rows)}</tbody></table></div>"
            + extra + provenance_block(prov))
    return page(title, body, INDEX_JS)


def _panel(title: str, src: str, extra: str = "", cls: str = "") -> str:
    return (f'<div class="panel"><b>{escape(title)}</b><div class="view">'
            f'<img src="{escape(src)}" alt="{escape(title)}"{cls}></div>{extra}</div>')


def _colorbar(lo: str, hi: str) -> str:
    return (f'<div class="bar" style="background:{colormap_css()}"></div>'
            f'<div class="scale"><span>{escape(lo)}</span><span>{escape(hi)}</span></div>')


def _jitter_table(j: JitterRecord) -> str:
    """The statistical test's statistics of a jittered image, each with its acceptance band."""
    def num(v: float | None) -> str:
        return "n/a" if v is None else f"{v:.4g}"

    rows = "".join(f"<tr><td>{escape(s.name)}</td><td class=num>{num(s.value)}</td>"
                   f"<td class=num>{num(s.low)} .. {num(s.high)}</td>"
                   f"<td>{'pass' if s.passed else 'fail'}</td></tr>" for s in j.statistics)
    return (f"<p>Against the reference's distribution of {j.realisations} realisations: "
            f"{j.failing_pixels} of {j.tested_pixels} pixels beyond |z| "
            f"{j.pixel_threshold:.3g}, {j.noisy_pixels} noisy pixels in the global "
            "statistics.</p><table><thead><tr><th>statistic</th><th>value</th>"
            f"<th>accepted</th><th></th></tr></thead><tbody>{rows}</tbody></table>")


def findings_list(kind: KindRecord, explained: bool) -> str:
    """What else is known about a failing kind (judge.findings), most specific first: without
    the cause's findings where the explanation block above says them (explained)."""
    shown = [x for x in kind.findings
             if not (explained and x.code.startswith("cause:"))]
    if kind.verdict != Verdict.FAIL or not shown:
        return ""
    items = "".join(f'<li><b>{escape(x.code)}</b>: {escape(x.message)}</li>' for x in shown)
    return f'<div class="findings"><b>Findings</b><ul>{items}</ul></div>'


# what the reference is, said to a student
REFERENCE_NAMES = {"tracer": "course program", "mitsuba": "Mitsuba 3"}


def case_verdict(record: CaseRecord) -> str:
    """The case's verdict as its overview cell says it: pass (quirk) where only a quirk of the
    course program differs."""
    top = record.top_finding()
    quirk = record.verdict == Verdict.PASS and top is not None and top.code.startswith("quirk:")
    return "pass (quirk)" if quirk else str(record.verdict)


def explanation_block(record: CaseRecord) -> str:
    """What the case page opens with: the cause once, its mistakes numbered, and the command
    that renders the reference with them; else each failing kind's top finding, said once."""
    cause = record.cause
    if cause is not None:
        n = len(cause.mistakes)
        lead = ("one mistake" if n == 1 else f"{n} mistakes together") + ": " + cause.how
        items = "".join(f"<li>{escape(m)}</li>" for m in cause.mistakes)
        return (f'<section class="explanation"><h2>Why: {escape(lead)}</h2><ol>{items}</ol>'
                f"<p>Render the reference with {'it' if n == 1 else 'them'}: "
                f"<code>{escape(cause.command)}</code></p></section>")
    said: dict[tuple[str, str], list[str]] = {}
    for k in record.kinds:
        if k.verdict != Verdict.PASS and k.findings:
            f = k.findings[0]
            said.setdefault((f.code, f.message), []).append(k.kind)
        elif k.findings and k.findings[0].code.startswith("quirk:"):
            said.setdefault((k.findings[0].code, k.findings[0].message), []).append(k.kind)
    if not said:
        return ""
    items = "".join(f"<li>{escape(', '.join(kinds))}: <b>{escape(code)}</b>: "
                    f"{escape(message)}</li>" for (code, message), kinds in said.items())
    return (f'<section class="explanation"><h2>What is known</h2><ul>{items}</ul>'
            "</section>")


def case_page(record: CaseRecord, command: list[str], prov: dict[str, str],
              index_href: str | None = None) -> str:
    title = f"{record.scene} · {record.feature}: {case_verdict(record)}"
    labels = record.labels
    cand, ref = labels[Role.CANDIDATE], labels[Role.REFERENCE]
    # a student's program is theirs; the report's candidates are raycheck's own renderers
    yours = cand if cand in REFERENCE_NAMES else f"your program ({cand})"
    reference = f"the reference ({REFERENCE_NAMES.get(ref, ref)})"
    jittered = record.jittered
    samples = " (16 samples)" if jittered else ""
    sections = []
    if record.error:
        e = record.error
        sections.append(f'<p class="error">{escape(cand)} failed ({escape(e.code)}): '
                        f'{escape(e.message)}</p>')
    for k in record.kinds:
        f = record.files.get(k.kind, {})
        status = k.verdict
        failures = "".join(f"<li>{escape(x)}</li>" for x in k.failures)
        head = (f'<section class="kind"><h2>{escape(k.kind)}: '
                f'<span class="{status}">{status}</span></h2>')
        if "candidate" not in f:
            sections.append(f"{head}<ul>{failures}</ul></section>")
            continue
        against = f"the mean of the reference's {k.jitter.realisations} renders" \
            if jittered and k.jitter is not None else "the reference"
        row = [_panel(yours + samples, f[Role.CANDIDATE]),
               _panel(reference + samples, f[Role.REFERENCE])]
        if "evidence" in f:
            code = k.findings[0].code
            row.append(_panel("the reference with your mistakes" if code.startswith("cause:")
                              else f"evidence: {code}", f["evidence"]))
        row.append(_panel(f"where they differ: |yours - {against}|, max over channels",
                          f["diff"], _colorbar("0", f"{f['diff_scale']} (shown value)")))
        flip = (f'<img class="flip" src="{escape(f[Role.CANDIDATE])}" '
                f'data-candidate="{escape(f[Role.CANDIDATE])}" '
                f'data-reference="{escape(f[Role.REFERENCE])}" '
                f'data-candidate-label="{escape(yours)}" '
                f'data-reference-label="{escape(reference)}" '
                f'data-showing="candidate" alt="flip view">')
        more = [f'<div class="panel"><b>flip: <span class="flipname">{escape(yours)}</span> '
                f'<button class="flipbtn">flip (f)</button></b><div class="view">{flip}</div>'
                "</div>",
                _panel(f"SSIM map, yours against {against}", f["ssim"], _colorbar("0", "1"))]
        if jittered:
            more.append(_panel(against, f[Role.MEAN]))
        jitter = _jitter_table(k.jitter) if k.jitter is not None else ""
        sections.append(
            f'{head}<div class="panels row">{"".join(row)}</div>'
            f"{findings_list(k, record.cause is not None)}"
            f'<div class="panels more">{"".join(more)}</div>'
            f"{numbers_table(k)}{jitter}<ul>{failures}</ul></section>")
    cmd = " ".join([cand, *command])
    w, h = record.size
    fit = max(1, min(16, 256 // max(w, h)))  # start with the image filling its view
    # JSON inside <script>: no raw <, > or & so that no tag can open or close in it
    data = (json.dumps(to_json(record)).replace("<", "\\u003c").replace(">", "\\u003e")
            .replace("&", "\\u0026"))
    back = f'<p><a href="{escape(index_href)}">index</a></p>' if index_href else ""
    output = (f"<details id=\"output\"><summary>Last output lines of {escape(cand)}</summary>"
              f"<pre>{escape(record.log)}</pre></details>" if record.log else "")
    body = (f'{back}<h1>{escape(title)}</h1>'
            f"<p>{escape(record.description)}</p>"
            + explanation_block(record)
            + f"<p>The course command line (in the scene's folder): <code>{escape(cmd)}</code>. "
              f"Depth range {record.depth_range[0]:g} to {record.depth_range[1]:g}, from "
              f"{escape(record.depth_origin)}.</p>"
            f'<p>zoom <input id="zoom" type="range" min="1" max="16" value="{fit}"> '
            f"(nearest neighbour; the views scroll together; key <b>f</b> or a click flips)</p>"
            + "".join(sections) + output + provenance_block(prov)
            + f"<script type=\"application/json\" id=\"data\">"
              f"{data}</script>")
    return page(title, body, CASE_JS)


def numbers_table(k: KindRecord) -> str:
    """The kind's comparison numbers as a table."""
    if k.metrics is None:
        return ""
    cells = "".join(f"<tr><td>{escape(name)}</td><td class=num>{value:.4g}</td></tr>"
                    for name, value in k.metrics.items())
    return (f'<table class="numbers"><thead><tr><th>number</th><th>value</th></tr></thead>'
            f"<tbody>{cells}</tbody></table>")
