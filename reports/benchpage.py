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
from .svgplot import bars, loglog


def _course(rows: list[dict]) -> str:
    by_scene: dict[str, dict[str, dict]] = {}
    for r in rows:
        by_scene.setdefault(r["scene"], {})[r["renderer"]] = r
    trs = []
    for scene, t in by_scene.items():
        tr, mi = t.get("tracer"), t.get("mitsuba")
        ratio = tr["warm_s"] / mi["warm_s"] if tr and mi and mi["warm_s"] > 0 else None
        status = "" if ratio is None else ("pass" if ratio <= 1.0 else "fail")
        trs.append(f'<tr class="{status}"><td>{escape(scene)}</td>'
                   + _num(tr and tr["cold_s"], "{:.3f}") + _num(tr and tr["warm_s"], "{:.3f}")
                   + _num(mi and mi["cold_s"], "{:.3f}") + _num(mi and mi["warm_s"], "{:.3f}")
                   + _num(ratio, "{:.2f}") + "</tr>")
    first = rows[0]
    setting = f"{first['size']}x{first['size']}, {first['flags']}"
    plot = bars(f"Warm render time (s), {setting}", "seconds (lower is faster)",
                {s: {("tracer" if r == "tracer" else "Mitsuba"): v["warm_s"]
                     for r, v in t.items()} for s, t in by_scene.items()})
    return (f"<h2>Course scenes</h2><p>{escape(setting)}. Each renderer in a fresh process "
            "with an empty Dr.Jit kernel cache: cold = load, trace, compile and the first "
            "render; warm = the median of the next three renders. Green rows: the tracer is at "
            "least as fast as Mitsuba warm.</p><table><thead><tr><th>scene</th>"
            "<th>tracer cold s</th><th>tracer warm s</th><th>Mitsuba cold s</th>"
            "<th>Mitsuba warm s</th><th>warm ratio tracer/Mitsuba</th></tr></thead><tbody>"
            + "".join(trs) + "</tbody></table>" + plot)


def _series(rows: list[dict], key: str, name: str) -> dict[str, list]:
    pts = [(r["triangles"], r[key], f"{r['triangles']} triangles") for r in rows
           if r.get(key) is not None]
    return {name: pts} if pts else {}


def _throughput(rows: list[dict]) -> str:
    speed = {**_series(rows, "ours_mrays", "tracer BVH"),
             **_series(rows, "brute_mrays", "tracer brute force"),
             **_series(rows, "mi_prelim_mrays", "Mitsuba/Embree preliminary hit"),
             **_series(rows, "mi_full_mrays", "Mitsuba/Embree full surface data")}
    build = {**_series(rows, "build_s", "tracer BVH build"),
             **_series(rows, "mi_build_s", "Mitsuba scene build")}
    render = _series(rows, "render_warm_s", "tracer render, warm")
    plots = [loglog("Primary-ray throughput against triangle count", "triangles", "M rays/s",
                    speed, dashed=("tracer brute force", "Mitsuba/Embree full surface data")),
             loglog("Build time against triangle count", "triangles", "seconds", build,
                    dashed=("Mitsuba scene build",))]
    if render:
        plots.append(loglog("Render time against triangle count", "triangles", "warm seconds",
                            render))
    trs = "".join(
        f"<tr><td class=num>{r['triangles']}</td>" + _num(r["ours_mrays"], "{:.2f}")
        + _num(r.get("brute_mrays"), "{:.3f}") + _num(r.get("mi_prelim_mrays"), "{:.2f}")
        + _num(r.get("mi_full_mrays"), "{:.2f}") + _num(r.get("vs_mitsuba_prelim"), "{:.2f}")
        + _num(r["build_s"], "{:.3f}")
        + _num((r["node_bytes"] + r["triangle_bytes"] + r["order_bytes"]) / r["triangles"],
               "{:.0f}")
        + _num(r.get("render_warm_s"), "{:.3f}") + "</tr>" for r in rows)
    first = rows[0]
    return (f"<h2>BVH against Mitsuba/Embree</h2><p>{first['rays']} primary rays, "
            f"{first['threads']} threads, best of the warm runs; memory is the tracer's device "
            "arrays (nodes, triangle records, normals, materials) per triangle.</p>"
            "<table><thead><tr><th>triangles</th><th>tracer M rays/s</th>"
            "<th>brute force M rays/s</th><th>Mitsuba prelim M rays/s</th>"
            "<th>Mitsuba full M rays/s</th><th>tracer/Mitsuba prelim</th><th>build s</th>"
            "<th>bytes/triangle</th><th>render warm s</th></tr></thead><tbody>" + trs
            + "</tbody></table>" + "".join(plots))


def bench_page(data: dict) -> str:
    """data: what `raycheck bench --json` writes (course rows, optional throughput rows,
    provenance)."""
    body = ["<h1>raycheck bench</h1><p><a href=\"bench.json\">All numbers as JSON</a>. "
            "<a href=\"index.html\">Comparison report</a>.</p>"]
    if data.get("course"):
        body.append(_course(data["course"]))
    if data.get("throughput"):
        body.append(_throughput(data["throughput"]))
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
