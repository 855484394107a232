"""The benchmark page of the report (bench.html): `raycheck bench` numbers as tables and plots.

Always the course scenes (both renderers' cold and warm times and their ratio); with
`raycheck bench --throughput` data also primary-ray throughput against triangle count, BVH
build time and memory, and render time against triangle count.
"""
from __future__ import annotations

import json
from html import escape
from pathlib import Path

from .html import _num, page, provenance_block
from .svgplot import bars


def _course(rows: list[dict]) -> str:
    """Per scene each renderer's cold and warm times, and the warm ratio of the first renderer
    to the second (green rows: the first is at least as fast)."""
    names = list(dict.fromkeys(r["renderer"] for r in rows))
    by_scene: dict[str, dict[str, dict]] = {}
    for r in rows:
        by_scene.setdefault(r["scene"], {})[r["renderer"]] = r
    pair = names[:2] if len(names) >= 2 else None
    trs = []
    for scene, t in by_scene.items():
        cells = "".join(_num(t.get(n) and t[n]["cold_s"], "{:.3f}")
                        + _num(t.get(n) and t[n]["warm_s"], "{:.3f}") for n in names)
        ratio = None
        if pair and all(t.get(n) for n in pair) and t[pair[1]]["warm_s"] > 0:
            ratio = t[pair[0]]["warm_s"] / t[pair[1]]["warm_s"]
        status = "" if ratio is None else ("pass" if ratio <= 1.0 else "fail")
        trs.append(f'<tr class="{status}"><td>{escape(scene)}</td>{cells}'
                   + (_num(ratio, "{:.2f}") if pair else "") + "</tr>")
    first = rows[0]
    setting = f"{first['size']}x{first['size']}, {first['flags']}"
    plot = bars(f"Warm render time (s), {setting}", "seconds (lower is faster)",
                {s: {r: v["warm_s"] for r, v in t.items()} for s, t in by_scene.items()})
    heads = "".join(f"<th>{escape(n)} cold s</th><th>{escape(n)} warm s</th>" for n in names)
    ratio_head = f"<th>warm ratio {escape(pair[0])}/{escape(pair[1])}</th>" if pair else ""
    green = (f" Green rows: {escape(pair[0])} is at least as fast as {escape(pair[1])} warm."
             if pair else "")
    return (f"<h2>Course scenes</h2><p>{escape(setting)}. Each renderer in a fresh process "
            "with an empty Dr.Jit kernel cache: cold = load, trace, compile and the first "
            f"render; warm = the median of the next three renders.{green}</p><table><thead>"
            f"<tr><th>scene</th>{heads}{ratio_head}</tr></thead><tbody>"
            + "".join(trs) + "</tbody></table>" + plot)


def bench_page(data: dict) -> str:
    """data: what `raycheck bench --json` writes (course rows, optional throughput rows,
    provenance)."""
    body = ["<h1>raycheck bench</h1><p><a href=\"bench.json\">All numbers as JSON</a>. "
            "<a href=\"index.html\">Comparison report</a>.</p>"]
    if data.get("course"):
        body.append(_course(data["course"]))
    if data.get("throughput"):
        from ..renderers.throughput import throughput_section

        body.append(throughput_section(data["throughput"]))
    else:
        body.append("<p>Throughput, build, memory and scaling: run <code>raycheck bench "
                    "--throughput --json FILE</code> and <code>raycheck report --bench "
                    "FILE</code>.</p>")
    if data.get("provenance"):
        body.append(provenance_block(data["provenance"]))
    return page("raycheck bench", "".join(body))


def write_bench_page(data: dict, folder: Path) -> Path:
    """Writes folder/bench.html and folder/bench.json; returns the page's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "bench.json").write_text(json.dumps(data, indent=2), encoding="utf-8")
    path = folder / "bench.html"
    path.write_text(bench_page(data), encoding="utf-8")
    return path
