"""Error against run time: jittered renders at growing sample counts and resolutions, for both
renderers, measured against one converged reference per resolution.

The reference is Mitsuba's render with REFERENCE_SAMPLES jittered samples per pixel (the
independent engine is the reference of this project): Mitsuba's curve falls with its own noise,
the tracer's falls the same way until it meets the floor of its systematic difference from
Mitsuba, which is where more samples stop helping.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

from tracer.scene import load_scene

from . import metrics
from .cases import Case
from .catalog import BundledScene
from .runners import render_case

SAMPLE_COUNTS = (1, 4, 16, 64, 256)
SIZES = (64, 128, 256)
SWEEP_SIZE = 128  # resolution of the sample-count sweep
SIZE_SWEEP_SAMPLES = 16  # samples per pixel of the resolution sweep
REFERENCE_SAMPLES = 1024


@dataclass(frozen=True)
class Point:
    scene: str
    renderer: str
    size: int
    samples: int
    cold_s: float
    warm_s: float
    rmse: float
    one_minus_ssim: float


def _jitter_case(scene: BundledScene) -> Case:
    return Case(scene, "jitter", ("-jitter",) + tuple(scene.flags), ("color",))


def sweep(scene: BundledScene, sample_counts=SAMPLE_COUNTS, sizes=SIZES,
          reference_samples: int = REFERENCE_SAMPLES, sweep_size: int = SWEEP_SIZE,
          size_sweep_samples: int = SIZE_SWEEP_SAMPLES) -> list[Point]:
    model = load_scene(scene.path)
    case = _jitter_case(scene)
    points: list[Point] = []
    runs = [(sweep_size, n) for n in sample_counts] + \
           [(s, size_sweep_samples) for s in sizes if s != sweep_size]
    references = {}
    for size, samples in runs:
        if size not in references:
            ref = render_case("mitsuba", model, case, (size, size), samples=reference_samples,
                              seed=10_000, warm=False)
            references[size] = ref.images["color"]
        for renderer in ("tracer", "mitsuba"):
            run = render_case(renderer, model, case, (size, size), samples=samples)
            img = run.images["color"]
            points.append(Point(scene.name, renderer, size, samples, run.cold_s, run.warm_s or 0,
                                metrics.rmse(references[size], img),
                                1.0 - metrics.ssim(references[size], img)))
    return points


def as_rows(points: list[Point]) -> list[dict]:
    return [asdict(p) for p in points]
