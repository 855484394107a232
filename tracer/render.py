"""Rendering a parsed scene into float images (spec §4, §8, §9).

The kernel traces one sample per (sub)pixel per launch; jitter samples and image tiles are
further launches of the same cached kernel, accumulated on the host in the course's order.
Returned arrays are (rows, columns[, 3]) with row 0 at the TOP, as written to files.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .backend import import_drjit
from .background import Background
from .camera import camera_frame
from .geometry import flatten
from .intersect import Intersector
from .limits import check_render_limits
from .scene.model import Scene
from .shading import Shader
from .vecmath import Types, make_types, normalize

JITTER_SAMPLES = 16
FILTER_KERNEL = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]])
TILE_RAYS = 1 << 21
DEFAULT_SEED = 0


@dataclass(frozen=True)
class RenderOptions:
    width: int = 100
    height: int = 100
    bounces: int = 0
    shadows: bool = False
    jitter: bool = False
    filter: bool = False
    want_color: bool = True
    want_normals: bool = False
    want_depth: bool = False
    depth_min: float = 0.0
    depth_max: float = 1.0
    seed: int = DEFAULT_SEED
    backend: str = "llvm"
    precision: str = "single"
    accel: str = "bvh"  # or "brute": every ray tests every triangle (for checking the BVH)
    samples: int = JITTER_SAMPLES  # jitter samples per (sub)pixel; the course uses 16


@dataclass
class RenderResult:
    color: np.ndarray | None  # (h, w, 3) unclamped floats
    normals: np.ndarray | None  # (h, w, 3) values (n+1)/2
    depth: np.ndarray | None  # (h, w) values (t-min)/(max-min)
    seconds: float
    launches: int


ProgressFn = Callable[[float], None]


class Renderer:
    """A scene prepared for rendering with fixed options; render() may be called repeatedly
    (warm runs reuse the compiled kernel)."""

    def __init__(self, scene: Scene, opts: RenderOptions) -> None:
        check_render_limits(opts)
        self.scene = scene
        self.opts = opts
        self.T: Types = make_types(opts.backend, opts.precision)
        self.dr = import_drjit()
        self.frame = camera_frame(scene.camera)
        self.isect = Intersector(flatten(scene), self.T, opts.accel)
        self.background = Background(scene.background, self.T)
        self.shader = Shader(scene, self.isect, self.background, self.T, opts.shadows,
                             opts.bounces)
        self.sub_w = opts.width * (3 if opts.filter else 1)
        self.sub_h = opts.height * (3 if opts.filter else 1)

    # --- the kernel -----------------------------------------------------------------------
    def _trace(self, first: int, count: int, sample: int):
        """Trace subpixels first..first+count-1 (row-major, row 0 = bottom) for one sample."""
        T, dr, opts = self.T, self.dr, self.opts
        idx = dr.arange(T.UInt32, count) + dr.opaque(T.UInt32, first)
        sub_w = dr.opaque(T.UInt32, self.sub_w)
        px = T.Float(idx % sub_w)
        py = T.Float(idx // sub_w)
        if opts.jitter:
            rng = T.PCG32(count, initstate=dr.opaque(T.ns.UInt64, self._stream_seed(sample)),
                          initseq=T.ns.UInt64(idx))
            px = px + T.Float(rng.next_float32())
            py = py + T.Float(rng.next_float32())
        # (w-1.0f) must stay a runtime value: Dr.Jit turns division by a literal into a
        # multiplication by its reciprocal, which is not the course's float division.
        ndcx = 2.0 * (px / dr.opaque(T.Float, self.sub_w - 1.0)) - 1.0
        ndcy = 2.0 * (py / dr.opaque(T.Float, self.sub_h - 1.0)) - 1.0
        f = self.frame
        d = normalize((T.Array3f(*f.forward.tolist()) + ndcx * T.Array3f(*f.right.tolist()))
                      + ndcy * T.Array3f(*f.up.tolist()))
        o = dr.full(T.Array3f, f.center.tolist(), count)
        need_normal = opts.want_normals or opts.want_color
        hit = self.isect.closest(o, d, need_normal=need_normal)
        out = {}
        if opts.want_color:
            out["color"] = self.shader.radiance(o, d, hit)
        if opts.want_normals:
            out["normal"] = hit.normal
        if opts.want_depth:
            out["t"] = hit.t
        dr.eval(out)
        # Array3f.numpy() is (3, n): transpose to one row per sample.
        return {k: np.asarray(v.numpy()).T if k != "t" else np.asarray(v.numpy())
                for k, v in out.items()}

    def _stream_seed(self, sample: int) -> int:
        # splitmix64 of (seed, sample): independent streams per jitter sample
        z = (self.opts.seed * 0x9E3779B97F4A7C15 + sample + 1) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        return z ^ (z >> 31)

    # --- host-side accumulation -------------------------------------------------------------
    def render(self, progress: ProgressFn | None = None) -> RenderResult:
        opts = self.opts
        npf = np.float32 if opts.precision == "single" else np.float64
        n_sub = self.sub_w * self.sub_h
        samples = opts.samples if opts.jitter else 1
        acc: dict[str, np.ndarray] = {}
        shapes = {"color": (n_sub, 3), "normals": (n_sub, 3), "depth": (n_sub,)}
        lo, hi = npf(opts.depth_min), npf(opts.depth_max)
        start = time.perf_counter()
        launches = 0
        tiles = [(s, min(TILE_RAYS, n_sub - s)) for s in range(0, n_sub, TILE_RAYS)]
        total = samples * len(tiles)
        with np.errstate(all="ignore"):
            for k in range(samples):
                values: dict[str, np.ndarray] = {}
                for first, count in tiles:
                    raw = self._trace(first, count, k)
                    launches += 1
                    sl = slice(first, first + count)
                    if "color" in raw:
                        values.setdefault("color", np.empty(shapes["color"], npf))[sl] = \
                            raw["color"].reshape(-1, 3)
                    if "normal" in raw:
                        values.setdefault("normals", np.empty(shapes["normals"], npf))[sl] = \
                            (raw["normal"].reshape(-1, 3).astype(npf) + npf(1)) / npf(2)
                    if "t" in raw:
                        values.setdefault("depth", np.empty(shapes["depth"], npf))[sl] = \
                            (raw["t"].astype(npf) - lo) / (hi - lo)
                    if progress:
                        progress(launches / total)
                for name, v in values.items():
                    acc[name] = v if k == 0 else acc[name] + v
            images = {}
            for name, v in acc.items():
                if samples > 1:
                    v = v / npf(samples)
                v = v.reshape((self.sub_h, self.sub_w) + v.shape[1:])
                if opts.filter:
                    v = box_filter_3x3(v)
                images[name] = np.ascontiguousarray(v[::-1])  # row 0 = bottom -> file order
        return RenderResult(images.get("color"), images.get("normals"), images.get("depth"),
                            time.perf_counter() - start, launches)


def box_filter_3x3(big: np.ndarray) -> np.ndarray:
    """Output (x, y) = Σ_j Σ_i K[j][i]·big(3x+i, 3y+j) / 16, summed j-major as the course does."""
    h, w = big.shape[0] // 3, big.shape[1] // 3
    out = None
    for j in range(3):
        for i in range(3):
            term = big[j::3, i::3][:h, :w] * big.dtype.type(FILTER_KERNEL[j][i])
            out = term if out is None else out + term
    return out / big.dtype.type(16)


def render(scene: Scene, opts: RenderOptions, progress: ProgressFn | None = None) -> RenderResult:
    return Renderer(scene, opts).render(progress)
