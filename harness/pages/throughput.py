"""The primary-ray throughput benchmark's rows (bench/throughput.py) for people to read: plain-text
tables for the terminal, and the bench page's section with its table and log-log plots."""
from __future__ import annotations

from ..bench.records import ThroughputRow
from .html import num_cell
from .svgplot import loglog


def _f(v, fmt: str) -> str:
    width = int("".join(ch for ch in fmt.split(".")[0] if ch.isdigit()) or 0)
    return "-".rjust(width) if v is None else format(v, fmt)


def format_throughput(rows: list[ThroughputRow]) -> str:
    """Plain-text tables: throughput, build and memory, render scaling, JIT."""
    if not rows:
        return "(no rows)"
    out = [f"Primary rays, closest hit ({rows[0].rays} rays, {rows[0].threads} threads), "
           "M rays/s (warm; best of the warm runs)",
           f"{'triangles':>10} {'hit%':>5} {'ours':>7} {'+normal':>7} {'cold s':>7} {'brute':>7} "
           f"{'(rays)':>7} {'Gtest/s':>7} {'=bvh':>4} {'mi pre':>7} {'mi full':>7} "
           f"{'ours/pre':>8} {'ours/full':>9} {'agree%':>6} {'pkt':>3}"]
    for r in rows:
        out.append(
            f"{r.triangles:>10} {100 * r.hit_fraction:5.1f} {r.ours_mrays:7.2f} "
            f"{_f(r.ours_full_mrays, '7.2f')} "
            f"{r.ours_cold_s:7.3f} {_f(r.brute_mrays, '7.3f')} "
            f"{_f(r.brute_rays, '7d')} "
            f"{_f(None if r.brute_mtests is None else r.brute_mtests / 1e3, '7.3f')} "
            f"{'-' if r.brute_agrees is None else ('yes' if r.brute_agrees else 'NO'):>4} "
            f"{_f(r.mi_prelim_mrays, '7.2f')} {_f(r.mi_full_mrays, '7.2f')} "
            f"{_f(r.vs_mitsuba_prelim, '8.2f')} {_f(r.vs_mitsuba_full, '9.2f')} "
            f"{_f(None if r.mi_agree is None else 100 * r.mi_agree, '6.2f')} "
            f"{'yes' if r.jit_cold.packet_gathers else 'no':>3}")
    out += ["", "BVH build and memory",
            f"{'triangles':>10} {'build s':>8} {'(cpu s)':>8} {'upload s':>8} {'mi build s':>10} "
            f"{'nodes':>9} "
            f"{'leaves':>8} {'depth':>5} {'nodes MB':>8} {'tris MB':>8} {'order MB':>8} "
            f"{'B/tri':>6} {'peak RSS MB':>11}"]
    for r in rows:
        out.append(
            f"{r.triangles:>10} {r.build_s:8.3f} {r.build_cpu_s:8.3f} "
            f"{r.upload_s:8.3f} "
            f"{_f(r.mi_build_s, '10.3f')} {r.nodes:>9} {r.leaves:>8} "
            f"{r.depth:>5} {r.node_bytes / 2**20:8.2f} {r.triangle_bytes / 2**20:8.2f} "
            f"{r.order_bytes / 2**20:8.2f} {r.bytes_per_triangle:6.1f} "
            f"{r.peak_rss_mb:11.0f}")
    rendered = [r for r in rows if r.render_warm_s is not None]
    if rendered:
        base = rendered[0].render_warm_s
        out += ["", "Render (primary + shading + shadow rays, one image of rays.sqrt()^2 "
                "pixels): time against triangle count",
                f"{'triangles':>10} {'setup s':>8} {'cold s':>8} {'warm s':>8} "
                f"{'x first':>8} {'compile ms':>10} {'kernels':>7} {'cache hits':>10}"]
        for r in rendered:
            j, setup, cold, warm = (r.render_jit_cold, r.render_setup_s, r.render_cold_s,
                                    r.render_warm_s)
            # a render's numbers are measured together: a row with one has them all
            assert j is not None and setup is not None and cold is not None \
                and warm is not None and base is not None
            out.append(f"{r.triangles:>10} {setup:8.3f} {cold:8.3f} {warm:8.3f} "
                       f"{warm / base:8.2f} {j.compile_ms:10.1f} {j.kernels:>7} "
                       f"{j.cache_hits:>10}")
    out += ["", "JIT, closest-hit launch: cold (first launch at this size) and warm",
            f"{'triangles':>10} {'kernels':>7} {'compile ms':>10} {'mem hits':>8} "
            f"{'disk hits':>9} {'warm kernels':>12} {'warm hits':>9}"]
    for r in rows:
        c, w = r.jit_cold, r.jit_warm
        out.append(f"{r.triangles:>10} {c.kernels:>7} {c.compile_ms:10.1f} "
                   f"{c.cache_hits - c.disk_hits:>8} {c.disk_hits:>9} "
                   f"{w.kernels:>12} {w.cache_hits:>9}")
    return "\n".join(out)


def _series(rows: list[ThroughputRow], key: str, name: str) -> dict[str, list]:
    pts = [(r.triangles, getattr(r, key), f"{r.triangles} triangles") for r in rows
           if getattr(r, key) is not None]
    return {name: pts} if pts else {}


def throughput_section(rows: list[ThroughputRow]) -> str:
    """The bench page's section of these measurements: a table and log-log plots."""
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
        f"<tr><td class=num>{r.triangles}</td>" + num_cell(r.ours_mrays, "{:.2f}")
        + num_cell(r.brute_mrays, "{:.3f}") + num_cell(r.mi_prelim_mrays, "{:.2f}")
        + num_cell(r.mi_full_mrays, "{:.2f}") + num_cell(r.vs_mitsuba_prelim, "{:.2f}")
        + num_cell(r.build_s, "{:.3f}")
        + num_cell(r.bytes_per_triangle, "{:.0f}")
        + num_cell(r.render_warm_s, "{:.3f}") + "</tr>" for r in rows)
    first = rows[0]
    return (f"<h2>BVH against Mitsuba/Embree</h2><p>{first.rays} primary rays, "
            f"{first.threads} threads, best of the warm runs; memory is the tracer's device "
            "arrays (nodes, triangle records, normals, materials) per triangle.</p>"
            "<table><thead><tr><th>triangles</th><th>tracer M rays/s</th>"
            "<th>brute force M rays/s</th><th>Mitsuba prelim M rays/s</th>"
            "<th>Mitsuba full M rays/s</th><th>tracer/Mitsuba prelim</th><th>build s</th>"
            "<th>bytes/triangle</th><th>render warm s</th></tr></thead><tbody>" + trs
            + "</tbody></table>" + "".join(plots))
