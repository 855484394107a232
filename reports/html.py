"""Static, self-contained HTML pages (no CDN; works from file://): the index and one page per
case. Every piece of scene-derived text goes through html.escape."""
from __future__ import annotations

import json
from html import escape

from .imaging import colormap_css

STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;font-size:13px}th,td{border:1px solid #ccc;padding:3px 6px}
th{background:#f3f3f3;cursor:pointer;position:sticky;top:0}td.num{text-align:right}
tr.fail td{background:#fde8e8}tr.skip td{color:#777}.pass{color:#137333}.fail{color:#b3261e}
.panels{display:flex;gap:10px;flex-wrap:wrap}.panel{display:flex;flex-direction:column}
.view{width:260px;height:260px;overflow:auto;border:1px solid #aaa;background:#777}
.view img{image-rendering:pixelated;display:block}
.bar{height:10px;width:260px}.scale{display:flex;justify-content:space-between;width:260px;font-size:11px}
.filters select,.filters input{margin-right:8px}code{background:#f5f5f5;padding:1px 3px}
dl.prov{display:grid;grid-template-columns:max-content auto;gap:2px 12px;font-size:13px}
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
document.querySelectorAll('.filters select, #text').forEach(e=>e.addEventListener('input',applyFilters));
let sortCol=-1,sortDir=1;
table.tHead.querySelectorAll('th').forEach((th,i)=>th.addEventListener('click',()=>{
  sortDir=(sortCol===i)?-sortDir:1;sortCol=i;
  const key=r=>{const c=r.cells[i];const v=c.dataset.v;return v!==undefined?parseFloat(v):c.textContent;};
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
document.querySelectorAll('.view img').forEach(img=>img.complete?setZoom():img.addEventListener('load',setZoom));
let syncing=false;
document.querySelectorAll('.view').forEach(v=>v.addEventListener('scroll',()=>{
  if(syncing)return;syncing=true;
  document.querySelectorAll('.view').forEach(o=>{if(o!==v){o.scrollLeft=v.scrollLeft;o.scrollTop=v.scrollTop;}});
  syncing=false;}));
function flip(section){const img=section.querySelector('img.flip');
  const next=img.dataset.showing==='tracer'?'mitsuba':'tracer';
  img.src=img.dataset[next];img.dataset.showing=next;
  section.querySelector('.flipname').textContent=next;}
document.querySelectorAll('button.flipbtn').forEach(b=>b.addEventListener('click',()=>flip(b.closest('section'))));
document.querySelectorAll('img.flip').forEach(i=>i.addEventListener('click',()=>flip(i.closest('section'))));
document.addEventListener('keydown',e=>{if(e.key==='f'){document.querySelectorAll('section.kind').forEach(flip);}});
"""


def _num(v, fmt: str = "{:.4f}") -> str:
    if v is None:
        return '<td class="num" data-v="NaN">–</td>'
    return f'<td class="num" data-v="{float(v)!r}">{escape(fmt.format(v))}</td>'


def page(title: str, body: str, script: str = "") -> str:
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{escape(title)}</title><style>{STYLE}</style></head><body>{body}"
            + (f"<script>{script}</script>" if script else "") + "</body></html>\n")


def provenance_block(prov: dict[str, str]) -> str:
    items = "".join(f"<dt>{escape(k)}</dt><dd>{escape(v)}</dd>" for k, v in prov.items())
    return f"<h2>Provenance</h2><dl class=\"prov\">{items}</dl>"


def index_page(rows: list[dict], skips: list[dict], plots: list[str], timing_rows: list[dict],
               prov: dict[str, str], title: str = "raycheck report",
               stress_link: bool = False, bench_link: bool = False) -> str:
    cols = ("scene", "feature", "kind", "status")
    options = {c: sorted({r.get(c, "skip") for r in rows + skips}) for c in cols}
    filters = "".join(
        f'<label>{c} <select data-col="{c}"><option value="">all</option>'
        + "".join(f'<option value="{escape(v)}">{escape(v)}</option>' for v in options[c])
        + "</select></label>" for c in cols)
    head = ("<tr><th>scene</th><th>feature</th><th>kind</th><th>status</th><th>SSIM</th>"
            "<th>PSNR dB</th><th>within 1 level</th><th>max abs</th><th>mean abs</th>"
            "<th>brightness Δ%</th><th>FLIP</th><th>tracer cold s</th><th>tracer warm s</th>"
            "<th>Mitsuba cold s</th><th>Mitsuba warm s</th><th>notes</th></tr>")
    body_rows = []
    for r in rows:
        m = r["metrics"]
        data = "".join(f' data-{c}="{escape(str(r[c]))}"' for c in cols)
        link = f'<a href="{escape(r["page"])}">{escape(r["scene"])}</a>'
        body_rows.append(
            f'<tr class="{escape(r["status"])}"{data}><td>{link}</td><td>{escape(r["feature"])}</td>'
            f'<td>{escape(r["kind"])}</td><td class="{escape(r["status"])}">{escape(r["status"])}</td>'
            + _num(m["ssim"]) + _num(m["psnr"], "{:.1f}") + _num(1 - m["off_by_more_than_one"], "{:.2%}")
            + _num(m["max_abs"]) + _num(m["mean_abs"], "{:.2e}") + _num(m["brightness_change_pct"], "{:+.3f}") + _num(m["flip"], "{:.4f}")
            + _num(r["times"]["tracer"]["cold_s"], "{:.3f}") + _num(r["times"]["tracer"]["warm_s"], "{:.3f}")
            + _num(r["times"]["mitsuba"]["cold_s"], "{:.3f}") + _num(r["times"]["mitsuba"]["warm_s"], "{:.3f}")
            + f"<td>{escape('; '.join(r['failures']) or r.get('note', ''))}</td></tr>")
    for s in skips:
        data = "".join(f' data-{c}="{escape(str(s.get(c, "skip")))}"' for c in cols)
        body_rows.append(f'<tr class="skip"{data}><td>{escape(s["scene"])}</td>'
                         f'<td>{escape(s["feature"])}</td><td>{escape(s["kind"])}</td>'
                         f'<td>skip</td>' + '<td></td>' * 11
                         + f'<td>{escape(s["reason"])}</td></tr>')
    n_fail = sum(r["status"] == "fail" for r in rows)
    summary = (f"<p>{len(rows)} comparisons, <span class=\"fail\">{n_fail} failed</span>, "
               f"{len(skips)} skipped. Metrics compare the tracer with Mitsuba on the values as "
               f"shown (clipped to [0, 1]); jittered rows compare the tracer's 16 samples with a "
               f"converged Mitsuba render. "
               f"<a href=\"report.json\">All numbers as JSON</a>."
               + (" The extreme scenes in course mode, robust mode, float64 and Mitsuba: "
                  "<a href=\"stress.html\">stress tests</a>." if stress_link else "")
               + (" Render times of both renderers and the BVH against Mitsuba/Embree: "
                  "<a href=\"bench.html\">benchmarks</a>." if bench_link else "")
               + "</p>")
    timing = ""
    if timing_rows:
        trs = "".join(
            f"<tr><td>{escape(t['scene'])}</td><td>{escape(t['renderer'])}</td>"
            f"<td class=num>{t['size']}</td><td class=num>{t['samples']}</td>"
            + _num(t["cold_s"], "{:.3f}") + _num(t["warm_s"], "{:.3f}")
            + _num(t["rmse"], "{:.3e}") + _num(t["one_minus_ssim"], "{:.3e}") + "</tr>"
            for t in timing_rows)
        timing = ("<h3>Times and errors of the sweeps</h3><table><thead><tr><th>scene</th>"
                  "<th>renderer</th><th>size</th><th>spp</th><th>cold s</th><th>warm s</th>"
                  "<th>RMSE</th><th>1-SSIM</th></tr></thead><tbody>" + trs + "</tbody></table>")
    body = (f"<h1>{escape(title)}</h1>{summary}<div class=\"filters\">{filters}"
            f"<input id=\"text\" placeholder=\"search\"> <span id=\"count\"></span></div>"
            f"<table id=\"cases\"><thead>{head}</thead><tbody>{''.join(body_rows)}</tbody></table>"
            + ("<h2>Error against run time</h2>" + "".join(plots) + timing if plots else "")
            + provenance_block(prov))
    return page(title, body, INDEX_JS)


def _panel(title: str, src: str, extra: str = "", cls: str = "") -> str:
    return (f'<div class="panel"><b>{escape(title)}</b><div class="view">'
            f'<img src="{escape(src)}" alt="{escape(title)}"{cls}></div>{extra}</div>')


def _colorbar(lo: str, hi: str) -> str:
    return (f'<div class="bar" style="background:{colormap_css()}"></div>'
            f'<div class="scale"><span>{escape(lo)}</span><span>{escape(hi)}</span></div>')


def case_page(result_row: dict, files: dict[str, dict[str, str]], command: list[str],
              prov: dict[str, str], index_href: str | None = None) -> str:
    title = f"{result_row['case']}"
    jittered = result_row["jittered"]
    sections = []
    for k in result_row["kinds"]:
        f = files[k["kind"]]
        flip = (f'<img class="flip" src="{escape(f["tracer"])}" data-tracer="{escape(f["tracer"])}" '
                f'data-mitsuba="{escape(f["mitsuba"])}" data-showing="tracer" alt="flip view">')
        metrics_list = ", ".join(f"{escape(n)} {v:.4g}" for n, v in k["metrics"].items())
        status = "pass" if k["passed"] else "fail"
        against = "Mitsuba converged" if jittered else "Mitsuba"
        samples = " (16 samples)" if jittered else ""
        panels = [
            _panel("tracer" + samples, f["tracer"]),
            _panel("Mitsuba" + samples, f["mitsuba"]),
            f'<div class="panel"><b>flip: <span class="flipname">tracer</span> '
            f'<button class="flipbtn">flip (f)</button></b><div class="view">{flip}</div></div>',
            _panel(f"|tracer - {against}|, max over channels", f["diff"],
                   _colorbar("0", f"{f['diff_scale']} (shown value)")),
            _panel(f"SSIM map, tracer against {against}", f["ssim"], _colorbar("0", "1")),
        ]
        if jittered:
            panels.append(_panel("Mitsuba converged (256 samples)", f["converged"]))
        failures = "".join(f"<li>{escape(x)}</li>" for x in k["failures"])
        jitter = ""
        if k["jitter"]:
            j = k["jitter"]
            jitter = (f"<p>Against the converged render: mean error tracer {j['error_tracer']:.3f}, "
                      f"Mitsuba {j['error_mitsuba']:.3f} levels; pixels decided by an inf/NaN/"
                      f"missed sample: tracer {j['poisoned_tracer']}, Mitsuba "
                      f"{j['poisoned_mitsuba']}</p>")
        sections.append(
            f'<section class="kind"><h2>{escape(k["kind"])}: <span class="{status}">{status}</span></h2>'
            f"<p>{metrics_list}</p>{jitter}<ul>{failures}</ul>"
            f'<div class="panels">{"".join(panels)}</div></section>')
    cmd = " ".join(command)
    w, h = result_row["size"]
    fit = max(1, min(16, 256 // max(w, h)))  # start with the image filling its view
    # JSON inside <script>: no raw <, > or & so that no tag can open or close in it
    data = (json.dumps(result_row).replace("<", "\\u003c").replace(">", "\\u003e")
            .replace("&", "\\u0026"))
    back = f'<p><a href="{escape(index_href)}">index</a></p>' if index_href else ""
    body = (f'{back}<h1>{escape(title)}</h1>'
            f"<p>{escape(result_row['description'])}</p><p>Course command: <code>{escape(cmd)}</code></p>"
            f'<p>zoom <input id="zoom" type="range" min="1" max="16" value="{fit}"> '
            f"(nearest neighbour; the views scroll together; key <b>f</b> or a click flips)</p>"
            + "".join(sections) + provenance_block(prov)
            + f"<script type=\"application/json\" id=\"data\">"
              f"{data}</script>")
    return page(title, body, CASE_JS)
