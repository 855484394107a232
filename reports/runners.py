"""Both renderers behind one call: render a case, time it cold and warm, return float images.

Cold is the first render of the case in this process (tracing and compiling its kernels, or
finding them in Dr.Jit's on-disk cache); warm is a second render of the same case.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from tracer.scene.model import Scene

from .cases import Case

RENDERERS = ("tracer", "mitsuba")


@dataclass
class Rendered:
    images: dict[str, np.ndarray]  # kind -> float image, row 0 = top
    cold_s: float
    warm_s: float | None


def _options(case: Case, size: tuple[int, int], samples: int, seed: int) -> dict:
    lo, hi = case.scene.depth_range
    return dict(width=size[0], height=size[1], bounces=case.bounces,
                shadows="-shadows" in case.flags, jitter=case.jittered,
                filter="-filter" in case.flags, want_color="color" in case.kinds,
                want_normals="normals" in case.kinds, want_depth="depth" in case.kinds,
                depth_min=lo, depth_max=hi, seed=seed, samples=samples)


def _images(result, kinds) -> dict[str, np.ndarray]:
    return {k: getattr(result, k) for k in kinds}


def render_case(renderer: str, scene: Scene, case: Case, size: tuple[int, int],
                samples: int = 16, seed: int = 0, warm: bool = True,
                tracer_options: dict | None = None) -> Rendered:
    """Render a case with one renderer; with warm=True a second, timed render follows.
    tracer_options (e.g. mode, precision) go to the tracer's RenderOptions only."""
    opts = _options(case, size, samples, seed)
    start = time.perf_counter()
    if renderer == "tracer":
        from tracer.render import RenderOptions, Renderer

        r = Renderer(scene, RenderOptions(**opts, **(tracer_options or {})))
        close = None
    elif renderer == "mitsuba":
        from mitsuba_ref.render import ReferenceOptions, ReferenceRenderer

        r = ReferenceRenderer(scene, ReferenceOptions(**opts))
        close = r.close
    else:
        raise ValueError(f"unknown renderer '{renderer}' (expected one of {RENDERERS})")
    try:
        result = r.render()
        cold = time.perf_counter() - start
        warm_s = None
        if warm:
            start = time.perf_counter()
            result = r.render()
            warm_s = time.perf_counter() - start
        return Rendered(_images(result, case.kinds), cold, warm_s)
    finally:
        if close:
            close()
