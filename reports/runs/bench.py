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

from ..catalog import bundled

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
    from raycheck.tracer.backend import import_drjit
    from raycheck.tracer.scene.request import RenderRequest

    from ..renderers import renderer_from_spec

    dr = import_drjit()
    request = RenderRequest.from_argv(["-size", str(size), str(size), *flags])
    start = time.perf_counter()
    session = renderer_from_spec(renderer).open(Path(scene_path), request)
    session.render()
    dr.sync_thread()
    cold = time.perf_counter() - start
    warm = []
    for _ in range(WARM_RUNS):
        t = time.perf_counter()
        session.render()
        dr.sync_thread()
        warm.append(time.perf_counter() - t)
    session.close()
    return {"cold_s": cold, "warm_s": statistics.median(warm)}


def time_scene(renderer: str, scene_path: Path, size: int, flags: list[str]) -> Timing:
    """Times one scene in a fresh process whose Dr.Jit kernel cache starts empty."""
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, HOME=home)
        code = ("import json, sys; from raycheck.harness.runs.bench import _time_in_this_process as t; "
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
    """One line per scene: each renderer's cold and warm times and the warm ratio of the first
    renderer to the second."""
    names = list(dict.fromkeys(r.renderer for r in rows))
    by_scene: dict[str, dict[str, Timing]] = {}
    for r in rows:
        by_scene.setdefault(r.scene, {})[r.renderer] = r
    pair = names[:2] if len(names) >= 2 else None
    head = f"{'scene':<18}" + "".join(f" {n + ' cold':>14} {'warm':>7}" for n in names)
    lines = [head + (f" {'warm ratio':>10}" if pair else "")]
    for scene, t in by_scene.items():
        cells = [f"{scene:<18}"]
        for n in names:
            cells.append(f"{t[n].cold_s:14.3f} {t[n].warm_s:7.3f}" if n in t
                         else f"{'-':>14} {'-':>7}")
        if pair:
            a, b = (t.get(n) for n in pair)
            cells.append(f"{a.warm_s / b.warm_s:10.2f}" if a and b else f"{'-':>10}")
        lines.append(" ".join(cells))
    if rows:
        ratio = f"; ratio = {pair[0]}/{pair[1]}" if pair else ""
        lines.append(f"({rows[0].size}x{rows[0].size}, {rows[0].flags}; seconds{ratio})")
    return "\n".join(lines)


def run_bench(renderers: list[str], size: int = 800, throughput: bool = False,
              log=print) -> dict:
    """The course-scene table (and with throughput the BVH measurements), printed as they
    come; returns every number with the provenance."""
    from ..provenance import provenance

    rows = course_table(renderers, size)
    log(format_table(rows))
    data: dict = {"provenance": provenance(), "course": [asdict(r) for r in rows]}
    if throughput:
        from ..renderers.throughput import format_throughput, run_throughput

        data["throughput"] = run_throughput(fresh_cache=True)
        log("")
        log(format_throughput(data["throughput"]))
    return data
