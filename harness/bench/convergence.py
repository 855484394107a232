"""Error against run time: jittered renders at growing sample counts and resolutions, for both
renderers, measured against one converged reference per resolution.

The reference is one renderer's render with REFERENCE_SAMPLES jittered samples per pixel (in
the report: the independent engine): its own curve falls with its own noise, another
renderer's falls the same way until it meets the floor of its systematic difference from the
reference, which is where more samples stop helping.
"""
from __future__ import annotations

from dataclasses import replace

from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.limits import Budget, scene_request_problem

from ..cases import Case
from ..catalog import BundledScene
from ..judge import metrics
from ..pipeline.case import cached_role, render_role
from ..renderers import Renderer
from .records import SIZE_SWEEP_SAMPLES, SWEEP_SIZE, Point

SAMPLE_COUNTS = (1, 4, 16, 64, 256)
SIZES = (64, 128, 256)
REFERENCE_SAMPLES = 1024


def _jitter_case(scene: BundledScene, size: int) -> Case:
    request = scene.typical_request((size, size))
    return Case(scene, "jitter", replace(request, jitter=True))


def sweep_problem(scene: BundledScene, budget: Budget, sizes=SIZES,
                  reference_samples: int = REFERENCE_SAMPLES) -> str | None:
    """What puts scene's sweep over a limit, or None: its largest renders, the reference's at
    each size, are checked as a case is (before a report starts, not when the sweep comes)."""
    model = load_scene(scene.path, budget)
    for size in sorted(set(sizes) | {SWEEP_SIZE}):
        request = replace(_jitter_case(scene, size).request, samples=reference_samples)
        problem = request.limit_problem() or scene_request_problem(model, request, budget)
        if problem:
            return f"{size}x{size} at {reference_samples} samples: {problem}"
    return None


def sweep(scene: BundledScene, renderers: list[Renderer], reference: Renderer,
          sample_counts=SAMPLE_COUNTS, sizes=SIZES,
          reference_samples: int = REFERENCE_SAMPLES, sweep_size: int = SWEEP_SIZE,
          size_sweep_samples: int = SIZE_SWEEP_SAMPLES) -> list[Point]:
    """Each renderer's jittered renders at the sample counts (at sweep_size) and sizes (at
    size_sweep_samples), against `reference`'s render of reference_samples per pixel."""
    points: list[Point] = []
    runs = [(sweep_size, n) for n in sample_counts] + \
           [(s, size_sweep_samples) for s in sizes if s != sweep_size]
    references = {}
    for size, samples in runs:
        case = _jitter_case(scene, size)
        if size not in references:
            # converged, so the same on every run: cached on disk like the cases' references
            ref = cached_role(reference, case, False, samples=reference_samples, seed=10_000)
            references[size] = ref.images["color"]
        for renderer in renderers:
            run = render_role(renderer, case, True, samples=samples)
            img = run.images["color"]
            points.append(Point(scene.name, renderer.name, size, samples, run.cold_s,
                                run.warm_s or 0, metrics.rmse(references[size], img),
                                1.0 - metrics.ssim(references[size], img)))
    return points
