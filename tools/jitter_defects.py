"""Jittered renders with one known defect, for the jitter test's benchmark
(tools/bench_jitter.py) and its wrapper candidate (tests/wrappers/corrupt.py); never part of the
tracer's own path. Each function returns the float images (kind -> array) that the tracer
renders for a -jitter request, wrong in one way:

    brightness   every color value times a factor
    samples      the mean of N samples instead of 16 (the tracer's --samples)
    no_jitter    -jitter ignored: one sample per (sub)pixel at its corner, as without -jitter
    shared       one jitter pattern for all pixels: the same 16 offsets everywhere
    half         offsets drawn in [0, 0.5)^2 instead of [0, 1)^2
    filter_twice the 1-2-1 filter applied once more to the filtered jittered image
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import FILTER_KERNEL, Renderer
from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.request import RenderRequest, request_fields

DEFECTS = ("brightness", "samples", "no_jitter", "shared", "half", "filter_twice")


def _images(renderer: Renderer) -> dict[str, np.ndarray]:
    result = renderer.render()
    return {k: getattr(result, k) for k in renderer.opts.kinds}


def _options(request: RenderRequest, **changes) -> RenderOptions:
    return RenderOptions(**{**request_fields(request), **changes})


def tracer(scene: Path, request: RenderRequest) -> dict[str, np.ndarray]:
    return _images(Renderer(load_scene(scene), _options(request)))


def brightness(scene: Path, request: RenderRequest, factor: float) -> dict[str, np.ndarray]:
    images = tracer(scene, request)
    images["color"] = images["color"] * np.float32(factor)
    return images


def samples(scene: Path, request: RenderRequest, n: int) -> dict[str, np.ndarray]:
    return tracer(scene, replace(request, samples=n))


def no_jitter(scene: Path, request: RenderRequest) -> dict[str, np.ndarray]:
    return tracer(scene, replace(request, jitter=False))


class _Shifted(Renderer):
    """Unjittered samples at (sub)pixel + (dx, dy), the offsets runtime values (one kernel)."""

    offset = (0.0, 0.0)

    def _sample(self, px, py, tile=None) -> dict:
        T = self.T
        dx, dy = (self._opaque(T.Float, float(v)) for v in self.offset)
        return super()._sample(px + dx, py + dy, tile)


def shared(scene: Path, request: RenderRequest) -> dict[str, np.ndarray]:
    """The mean of request.samples unjittered renders, each shifted by one offset drawn from
    the request's seed: every pixel sees the same pattern (filtering is linear, so filtering
    each render equals filtering their mean)."""
    r = _Shifted(load_scene(scene), _options(request, jitter=False))
    offsets = np.random.default_rng(request.seed).random((request.samples, 2), np.float32)
    total: dict[str, np.ndarray] = {}
    with np.errstate(all="ignore"):  # missed depth samples are FLT_MAX-sized: sums overflow
        for dx, dy in offsets:
            r.offset = (dx, dy)
            for k, v in _images(r).items():
                total[k] = v if k not in total else total[k] + v  # in sample order
        return {k: v / np.float32(request.samples) for k, v in total.items()}


class _Half(Renderer):
    """Jittered samples whose offsets are halved: floor(s) + (s - floor(s)) / 2."""

    def _sample(self, px, py, tile=None) -> dict:
        dr = self.dr
        fx, fy = dr.floor(px), dr.floor(py)
        return super()._sample(fx + (px - fx) * 0.5, fy + (py - fy) * 0.5, tile)


def half(scene: Path, request: RenderRequest) -> dict[str, np.ndarray]:
    return _images(_Half(load_scene(scene), _options(request)))


def filter_twice(scene: Path, request: RenderRequest) -> dict[str, np.ndarray]:
    """The -filter render blurred once more by the 1-2-1 kernel at the output resolution
    (edges repeated)."""
    from scipy.ndimage import convolve

    k = FILTER_KERNEL.astype(np.float32) / np.float32(16)
    images = tracer(scene, request)
    out = {}
    for name, v in images.items():
        kernel = k if v.ndim == 2 else k[..., None]
        with np.errstate(all="ignore"):
            out[name] = convolve(v, kernel, mode="nearest")
    return out
