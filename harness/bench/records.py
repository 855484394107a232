"""The benchmarks' results as typed records (records.py's to_json / from_json), and their text
tables: a `raycheck bench` run, what `--json` writes and docs/bench.json holds, and what the
benchmark page, the generated performance tables and `raycheck report --bench FILE` read back
(a saved run may hold only some of the tables, the course scenes' always); a point of the
report's error-against-time sweeps. The pages read these and nothing else of bench/."""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Any

from ..records import from_json, optional, to_json

# the targets of issue 17: whole processes at 800x800 at least 5x faster than the course
# program, and at 200x200 no slower where the course program takes more than 0.3 s
VERSUS_GOALS = {800: (5.0, 0.0), 200: (1.0, 0.3)}  # size -> (speed-up, only above these a2 s)


@dataclass(frozen=True)
class Timing:
    """One course scene in one renderer: a fresh process with an empty kernel cache."""

    scene: str
    renderer: str
    size: int
    flags: str
    cold_s: float
    warm_s: float
    warm_runs: int | None = optional("the warm renders' count (runs saved before: none)")


def _derived() -> Any:
    """A field computed from the others (__post_init__): written to JSON, never read."""
    return field(init=False, metadata={"doc": "derived from the other fields", "json": None})


@dataclass(frozen=True)
class Versus:
    """The tracer's command line and another course program, whole processes in pairs."""

    scene: str
    size: int
    flags: str
    tracer_s: tuple[float, ...]  # every paired run, in order
    other_s: tuple[float, ...]
    tracer_median_s: float = _derived()
    other_median_s: float = _derived()
    goal: str = _derived()  # met, missed, or - where VERSUS_GOALS has none for the size

    def __post_init__(self) -> None:
        tracer, other = statistics.median(self.tracer_s), statistics.median(self.other_s)
        object.__setattr__(self, "tracer_median_s", tracer)
        object.__setattr__(self, "other_median_s", other)
        speedup, above_s = VERSUS_GOALS.get(self.size, (0.0, float("inf")))
        object.__setattr__(self, "goal", "-" if other <= above_s else
                           "met" if other / tracer >= speedup else "missed")


@dataclass(frozen=True)
class LoadAverage:
    min: float
    max: float
    every_s: float
    samples: tuple[float, ...]


@dataclass(frozen=True)
class Machine:
    """The machine a run timed, as the performance tables name it."""

    cpu: str
    cores: int
    load_average: LoadAverage  # the 1-minute load average, sampled during the run
    date: str  # UTC, YYYY-MM-DD
    gpu: str  # CUDA, or none


@dataclass(frozen=True)
class BenchRun:
    course: tuple[Timing, ...]
    throughput: tuple[ThroughputRow, ...] | None = optional("primary-ray throughput")
    versus: tuple[Versus, ...] | None = optional("against another course program")
    versus_program: dict[str, Any] | None = optional("that program's identity and name")
    provenance: dict[str, Any] | None = optional("the run's versions and machine")
    machine: Machine | None = optional("where it ran")

    def to_json(self) -> dict:
        return to_json(self)

    @classmethod
    def from_json(cls, data: Any) -> BenchRun:
        """ValueError naming the key where data is not a bench run."""
        return from_json(cls, data)


@dataclass(frozen=True)
class JitCounts:
    """Kernels launched between two points of a measurement, from Dr.Jit's kernel history."""

    kernels: int
    cache_hits: int
    compile_ms: float = 0.0  # codegen and LLVM time of the kernels not found in a cache
    disk_hits: int = 0  # of cache_hits, those loaded from the on-disk cache
    # Dr.Jit 1.5 turns a gather of 4 or 8 consecutive values into a packet load only from
    # 64-byte aligned memory; otherwise scalar gathers (and another kernel)
    packet_gathers: bool = False


@dataclass(frozen=True)
class ThroughputRow:
    """All numbers for one mesh size (measure): times in seconds, throughput in M rays/s,
    memory in bytes; Mitsuba's, brute force's and the render's only where they ran."""

    triangles: int
    vertices: int
    rays: int
    threads: int
    build_s: float
    build_cpu_s: float
    upload_s: float
    nodes: int
    leaves: int
    depth: int
    node_bytes: int
    triangle_bytes: int
    order_bytes: int
    ours_cold_s: float
    jit_cold: JitCounts
    ours_full_cold_s: float
    hit_fraction: float
    jit_warm: JitCounts
    ours_warm_s: float
    ours_mrays: float
    ours_full_warm_s: float
    ours_full_mrays: float
    peak_rss_mb: float
    mi_build_s: float | None = optional("Mitsuba's scene build")
    mi_prelim_cold_s: float | None = optional("ray_intersect_preliminary, first launch")
    mi_full_cold_s: float | None = optional("ray_intersect, first launch")
    mi_prelim_warm_s: float | None = optional("ray_intersect_preliminary, warm")
    mi_prelim_mrays: float | None = optional("ray_intersect_preliminary, warm")
    mi_full_warm_s: float | None = optional("ray_intersect, warm")
    mi_full_mrays: float | None = optional("ray_intersect, warm")
    vs_mitsuba_prelim: float | None = optional("ours_mrays / mi_prelim_mrays")
    vs_mitsuba_full: float | None = optional("ours_full_mrays / mi_full_mrays")
    mi_agree: float | None = optional("share of rays whose hit agrees with Mitsuba's")
    brute_rays: int | None = optional("rays brute force was timed on")
    brute_warm_s: float | None = optional("brute force, warm")
    brute_mrays: float | None = optional("brute force, warm")
    brute_mtests: float | None = optional("brute force's M ray-triangle tests/s")
    brute_agrees: bool | None = optional("brute force gave exactly the BVH's hits")
    render_setup_s: float | None = optional("Renderer construction")
    render_cold_s: float | None = optional("the first render")
    render_jit_cold: JitCounts | None = optional("kernels of the first render")
    render_warm_s: float | None = optional("the best warm render")

    @property
    def bytes_per_triangle(self) -> float:
        return (self.node_bytes + self.triangle_bytes + self.order_bytes) / self.triangles

    def to_json(self) -> dict:
        return to_json(self)

    @classmethod
    def from_json(cls, data: Any) -> ThroughputRow:
        return from_json(cls, data)


# the report's two error-against-time sweeps: sample counts at one resolution, resolutions at
# one sample count (a point at both is on both curves)
SWEEP_SIZE = 128
SIZE_SWEEP_SAMPLES = 16


@dataclass(frozen=True)
class Point:
    """One render of a sweep: its times and its error against the converged reference."""

    scene: str
    renderer: str
    size: int
    samples: int
    cold_s: float
    warm_s: float
    rmse: float
    one_minus_ssim: float


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
        runs = rows[0].warm_runs
        warm = f"; warm: median of {runs} renders" if runs else ""
        ratio = f"; ratio = {pair[0]}/{pair[1]}" if pair else ""
        lines.append(f"({rows[0].size}x{rows[0].size}, {rows[0].flags}; seconds{warm}{ratio})")
    return "\n".join(lines)


def format_versus(rows: list[Versus], name: str) -> str:
    """One line per scene and size: the medians, how many times faster the tracer is, and
    whether that meets the goal for the size (VERSUS_GOALS)."""
    lines = [f"{'scene':<18} {'size':>4} {'tracer s':>9} {name[:14] + ' s':>16} "
             f"{'speed-up':>8} {'goal':>6}"]
    for r in rows:
        lines.append(f"{r.scene:<18} {r.size:>4} {r.tracer_median_s:9.3f} {r.other_median_s:16.3f} "
                     f"{r.other_median_s / r.tracer_median_s:8.2f} {r.goal:>6}")
    if rows:
        goals = "; ".join(f"{size}: {x:g}x" + (f" where {name[:14]} takes over {s:g} s"
                                                 if s else "")
                          for size, (x, s) in VERSUS_GOALS.items())
        lines.append(f"({rows[0].flags}, color+normals+depth; whole processes, the tracer's "
                     f"kernel cache warm; medians of {len(rows[0].tracer_s)} paired runs;")
        lines.append(f" speed-up = {name[:14]} s / tracer s; goal {goals})")
    return "\n".join(lines)

