"""Benchmarks that print tables (never pass/fail): render times of the bundled course scenes.

Cold = the first render in a fresh process with an empty Dr.Jit kernel cache (scene loading,
tracing, LLVM compilation and the run); warm = the median of the following renders of the same
scene in that process, each ended by dr.eval + dr.sync_thread.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from .catalog import bundled

WARM_RUNS = 3


@dataclass(frozen=True)
class Timing:
    scene: str
    renderer: str
    size: int
    flags: str
    cold_s: float
    warm_s: float


def _time_in_this_process(renderer: str, scene_path: str, size: int, flags: list[str]) -> dict:
    from tracer.backend import import_drjit
    from tracer.scene import load_scene
    from tracer.scene.flags import parse_course_flags

    dr = import_drjit()
    args = parse_course_flags(["-input", scene_path, "-size", str(size), str(size), *flags])
    start = time.perf_counter()
    scene = load_scene(scene_path)
    args.output = Path("unused.png")
    if renderer == "tracer":
        from tracer.cli import options_from_args
        from tracer.render import Renderer

        render = Renderer(scene, options_from_args(args)).render
    elif renderer == "mitsuba":
        from mitsuba_ref.cli import options_from_args as reference_options
        from mitsuba_ref.render import ReferenceRenderer

        render = ReferenceRenderer(scene, reference_options(args)).render
    else:
        raise ValueError(f"unknown renderer {renderer}")
    render()
    dr.sync_thread()
    cold = time.perf_counter() - start
    warm = []
    for _ in range(WARM_RUNS):
        t = time.perf_counter()
        render()
        dr.sync_thread()
        warm.append(time.perf_counter() - t)
    return {"cold_s": cold, "warm_s": statistics.median(warm)}


def time_scene(renderer: str, scene_path: Path, size: int, flags: list[str]) -> Timing:
    """Times one scene in a fresh process whose Dr.Jit kernel cache starts empty."""
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, HOME=home)
        code = ("import json, sys; from reports.bench import _time_in_this_process as t; "
                "print(json.dumps(t(*json.loads(sys.argv[1]))))")
        proc = subprocess.run(
            [sys.executable, "-c", code, json.dumps([renderer, str(scene_path), size, flags])],
            capture_output=True, text=True, env=env, check=True,
            cwd=Path(__file__).resolve().parent.parent)
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    return Timing(scene_path.stem, renderer, size, " ".join(flags), **result)


def course_table(renderers: list[str], size: int = 800,
                 flags: tuple[str, ...] = ("-bounces", "4", "-shadows")) -> list[Timing]:
    rows = []
    for scene in bundled("course"):
        for renderer in renderers:
            rows.append(time_scene(renderer, scene.path, size, list(flags)))
    return rows


def format_table(rows: list[Timing]) -> str:
    """One line per scene: both renderers' cold and warm times and the warm ratio."""
    by_scene: dict[str, dict[str, Timing]] = {}
    for r in rows:
        by_scene.setdefault(r.scene, {})[r.renderer] = r
    lines = [f"{'scene':<18} {'tracer cold':>11} {'warm':>7} {'Mitsuba cold':>12} {'warm':>7} "
             f"{'warm ratio':>10}"]
    for scene, t in by_scene.items():
        tr, mi = t.get("tracer"), t.get("mitsuba")
        cells = [f"{scene:<18}"]
        cells.append(f"{tr.cold_s:11.3f} {tr.warm_s:7.3f}" if tr else f"{'-':>11} {'-':>7}")
        cells.append(f"{mi.cold_s:12.3f} {mi.warm_s:7.3f}" if mi else f"{'-':>12} {'-':>7}")
        cells.append(f"{tr.warm_s / mi.warm_s:10.2f}" if tr and mi else f"{'-':>10}")
        lines.append(" ".join(cells))
    first = rows[0] if rows else None
    if first:
        lines.append(f"({first.size}x{first.size}, {first.flags}; seconds; ratio = tracer/Mitsuba)")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="raycheck bench")
    ap.add_argument("--size", type=int, default=800)
    ap.add_argument("--renderer", action="append", choices=["tracer", "mitsuba"], default=None)
    ap.add_argument("--json", type=Path, help="also write every number as JSON")
    ap.add_argument("--html", type=Path, metavar="DIR",
                    help="also write the tables and plots as DIR/bench.html (and bench.json)")
    ap.add_argument("--throughput", action="store_true",
                    help="also measure BVH and Mitsuba/Embree primary-ray throughput on meshes "
                         "of 1k-1M triangles, build time, memory, scaling and JIT (minutes)")
    args = ap.parse_args(argv)
    data = run_bench(args.renderer or ["tracer", "mitsuba"], args.size, args.throughput)
    if args.json:
        args.json.write_text(json.dumps(data, indent=2))
    if args.html:
        from .benchpage import write_bench_page

        print(f"page: {write_bench_page(data, args.html).resolve()}")
    return 0


def run_bench(renderers: list[str], size: int = 800, throughput: bool = False,
              log=print) -> dict:
    """The course-scene table (and with throughput the BVH measurements), printed as they
    come; returns every number with the provenance."""
    from .provenance import provenance

    rows = course_table(renderers, size)
    log(format_table(rows))
    data: dict = {"provenance": provenance(), "course": [asdict(r) for r in rows]}
    if throughput:
        from .throughput import format_throughput, run_throughput

        data["throughput"] = run_throughput(fresh_cache=True)
        log("")
        log(format_throughput(data["throughput"]))
    return data
