"""Benchmarks that print tables (never pass/fail): render times of the bundled course scenes.

Cold = the first render in a fresh process with an empty Dr.Jit kernel cache (scene loading,
tracing, LLVM compilation and the run); warm = the median of the following renders of the same
scene in that process, each ended by dr.eval + dr.sync_thread.

Versus (versus_table): the tracer's command line and any course program, each a whole process
end to end as a user runs it (start-up, scene, render, PNGs written), the tracer's kernel cache
warm; paired runs alternating which goes first, medians.

run_bench makes all of them in one run, with the machine they ran on (machine_info), which is
what the generated performance tables (docs/performance.md) are regenerated from
(pages.benchpage.rewrite_readme).
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from ..catalog import bundled
from .records import BenchRun, LoadAverage, Machine, Timing, Versus, format_table, format_versus

# on this shared VM a median of three moved by more than some of the changes it was to show;
# seven cost about 2 s more at 800x800 for the whole table
WARM_RUNS = 7
VERSUS_SIZES = (800, 200)
VERSUS_FLAGS = ("-bounces", "4", "-shadows")
VERSUS_RUNS = 5
VERSUS_TIMEOUT_S = 600.0  # per run: the unoptimised course program takes ~30 s at 800x800
VERSUS_DEPTH = (0.0, 20.0)  # for scenes whose `# flags:` line gives no -depth range
LOAD_SAMPLE_S = 5.0


def _time_in_this_process(renderer: str, scene_path: str, size: int, flags: list[str]) -> dict:
    from raycheck.tracer.kernel.backend import import_drjit
    from raycheck.tracer.scene.flags import request_from_argv

    from ..renderers import renderer_from_spec

    dr = import_drjit()
    request = request_from_argv(["-size", str(size), str(size), *flags])
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
    return {"cold_s": cold, "warm_s": statistics.median(warm), "warm_runs": len(warm)}


def time_scene(renderer: str, scene_path: Path, size: int, flags: list[str]) -> Timing:
    """Times one scene in a fresh process whose Dr.Jit kernel cache starts empty."""
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, HOME=home)
        code = ("import json, sys; "
                "from raycheck.harness.bench.timing import _time_in_this_process as t; "
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


def versus_table(command: str, sizes: tuple[int, ...] = VERSUS_SIZES, runs: int = VERSUS_RUNS,
                 flags: tuple[str, ...] = VERSUS_FLAGS, scenes: list | None = None,
                 log=print) -> list[Versus]:
    """Each course scene (or each of `scenes`, catalog.BundledScene) at each size with color,
    normals and depth: `python -m raycheck.tracer` and `command` run as course programs are
    (renderers.command: a staged comment-free copy, the scene's folder as working directory),
    timed from start to exit."""
    from raycheck.tracer.scene.flags import request_from_argv

    from ..renderers import CommandRenderer, Limits

    tracer = CommandRenderer([sys.executable, "-m", "raycheck.tracer"], name="tracer")
    other = CommandRenderer.from_string(command, Limits(timeout_s=VERSUS_TIMEOUT_S))
    rows = []
    for scene in bundled("course") if scenes is None else scenes:
        lo, hi = scene.depth_range or VERSUS_DEPTH
        for size in sizes:
            request = request_from_argv(
                ["-size", str(size), str(size), *flags, "-output", "out.png",
                 "-normals", "normals.png", "-depth", f"{lo:g}", f"{hi:g}", "depth.png"])
            # untimed: fills the tracer's kernel cache (a course program has none, and one run
            # of it at 800x800 can take half a minute)
            tracer.open(scene.path, request).render()
            times: dict[str, list[float]] = {"tracer": [], "other": []}
            for i in range(runs):
                pair = [("tracer", tracer), ("other", other)]
                for key, r in (pair if i % 2 == 0 else pair[::-1]):  # neither always first
                    times[key].append(r.open(scene.path, request).render().seconds)
            row = Versus(scene.path.stem, size, " ".join(flags), tuple(times["tracer"]),
                         tuple(times["other"]))
            log(f"  {row.scene} {size}x{size}: tracer {row.tracer_median_s:.3f} s, "
                f"{other.name} {row.other_median_s:.3f} s")
            rows.append(row)
    return rows


class LoadSampler:
    """The 1-minute load average, sampled every LOAD_SAMPLE_S seconds while in the `with`
    block (and at its start and end): how busy the machine was while it was timed."""

    def __init__(self) -> None:
        self.samples: list[float] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while True:
            self.samples.append(round(os.getloadavg()[0], 2))
            if self._stop.wait(LOAD_SAMPLE_S):
                return

    def __enter__(self) -> LoadSampler:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        self.samples.append(round(os.getloadavg()[0], 2))


def machine_info(cpu: str, load_samples: list[float]) -> Machine:
    """The machine a run timed: CPU model (the provenance's), cores, load average during the
    run, date (UTC) and GPU (none unless Dr.Jit's CUDA backend is available)."""
    from raycheck.tracer.kernel.backend import import_drjit

    dr = import_drjit()
    return Machine(cpu, os.cpu_count() or 1,
                   LoadAverage(min(load_samples), max(load_samples), LOAD_SAMPLE_S,
                               tuple(load_samples)),
                   time.strftime("%Y-%m-%d", time.gmtime()),
                   "CUDA" if dr.has_backend(dr.JitBackend.CUDA) else "none")


def run_bench(renderers: list[str], size: int = 800, throughput: bool = False,
              versus: str | None = None, runs: int = VERSUS_RUNS, log=print) -> BenchRun:
    """The course-scene table, with throughput the BVH measurements, and with versus (a course
    program's command line) the whole-process table against it, each printed as it comes;
    returns every number with the machine and the provenance."""
    from ..provenance import provenance

    measured, pairs, program = None, None, None
    with LoadSampler() as load:
        rows = course_table(renderers, size)
        log(format_table(rows))
        if throughput:
            from ..pages.throughput import format_throughput
            from .throughput import run_throughput

            measured = tuple(run_throughput(fresh_cache=True))
            log("")
            log(format_throughput(list(measured)))
        if versus is not None:
            from ..renderers import CommandRenderer

            other = CommandRenderer.from_string(versus)
            pairs = tuple(versus_table(versus, runs=runs, log=log))
            log("")
            log(format_versus(list(pairs), other.name))
            program = other.identity() | {"name": other.name}
    versions = provenance()
    return BenchRun(tuple(rows), measured, pairs, program, versions,
                    machine_info(versions["cpu"], load.samples))
