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
from .rebase import camera_relative
from .intersect import Intersector
from .limits import check_render_limits
from .scene.model import Scene
from .shading import Shader
from .vecmath import Types, make_types, normalize, normalize_safe

JITTER_SAMPLES = 16
FILTER_KERNEL = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]])
TILE_RAYS = 1 << 21
DEFAULT_SEED = 0
MODES = ("course", "robust")


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
    # "course": the course's arithmetic bit for bit; "robust": scale-aware ray offsets, stable
    # sphere roots, watertight triangles and NaN-safe shading (docs in intersect.py, shading.py,
    # vecmath.py, camera.py, background.py and _ndc below)
    mode: str = "course"


@dataclass
class RenderResult:
    color: np.ndarray | None  # (h, w, 3) unclamped floats
    normals: np.ndarray | None  # (h, w, 3) values (n+1)/2
    depth: np.ndarray | None  # (h, w) values (t-min)/(max-min)
    seconds: float
    launches: int  # kernel launches (image tiles); jitter samples loop inside the kernel


ProgressFn = Callable[[float], None]


class Renderer:
    """A scene prepared for rendering with fixed options; render() may be called repeatedly
    (warm runs reuse the compiled kernel)."""

    def __init__(self, scene: Scene, opts: RenderOptions) -> None:
        check_render_limits(opts)
        if opts.mode not in MODES:
            raise ValueError(f"unknown mode {opts.mode!r} (expected course or robust)")
        self.robust = opts.mode == "robust"
        if self.robust:
            scene = camera_relative(scene)
        self.scene = scene
        self.opts = opts
        self.T: Types = make_types(opts.backend, opts.precision)
        self.dr = import_drjit()
        self.frame = camera_frame(scene.camera, self.robust)
        self.isect = Intersector(flatten(scene), self.T, opts.accel, self.robust)
        self.background = Background(scene.background, self.T, self.robust)
        self.shader = Shader(scene, self.isect, self.background, self.T, opts.shadows,
                             opts.bounces, self.robust)
        self.sub_w = opts.width * (3 if opts.filter else 1)
        self.sub_h = opts.height * (3 if opts.filter else 1)

    # --- the kernel -----------------------------------------------------------------------
    def _sample(self, px, py) -> dict:
        """Image values of one sample at sub-pixel coordinates (px, py), y up."""
        T, dr, opts = self.T, self.dr, self.opts
        # (w-1.0f) must stay a runtime value: Dr.Jit turns division by a literal into a
        # multiplication by its reciprocal, which is not the course's float division.
        ndcx = self._ndc(px, self.sub_w)
        ndcy = self._ndc(py, self.sub_h)
        f = self.frame
        norm = normalize_safe if self.robust else normalize
        d = norm((T.Array3f(*f.forward.tolist()) + ndcx * T.Array3f(*f.right.tolist()))
                      + ndcy * T.Array3f(*f.up.tolist()))
        o = dr.full(T.Array3f, f.center.tolist(), dr.width(px))
        hit = self.isect.closest(o, d, need_normal=opts.want_normals or opts.want_color)
        out = {}
        if opts.want_color:
            out["color"] = self.shader.radiance(o, d, hit)
        if opts.want_normals:
            out["normals"] = (hit.normal + 1.0) / 2.0  # halving is exact
        if opts.want_depth:
            npf = np.float32 if opts.precision == "single" else np.float64
            lo, hi = npf(opts.depth_min), npf(opts.depth_max)
            out["depth"] = (hit.t - float(lo)) / dr.opaque(T.Float, float(hi - lo))
        return out

    def _ndc(self, p, n: int):
        """2*(p/(n-1.0f)) - 1. Robust mode fixes the 0/0 = NaN of a single column or row
        (1xN, Nx1, 1x1 images): there ndc is 0, the image's center line."""
        T, dr = self.T, self.dr
        if self.robust and n == 1:
            return dr.zeros(T.Float, dr.width(p))
        return 2.0 * (p / dr.opaque(T.Float, n - 1.0)) - 1.0

    def _trace(self, first: int, count: int) -> dict[str, np.ndarray]:
        """Sub-pixels first..first+count-1 (row-major, row 0 = bottom): their values, or with
        -jitter the sums of their jittered samples' values, added in sample order."""
        T, dr, opts = self.T, self.dr, self.opts
        idx = dr.arange(T.UInt32, count) + dr.opaque(T.UInt32, first)
        sub_w = dr.opaque(T.UInt32, self.sub_w)
        px = T.Float(idx % sub_w)
        py = T.Float(idx // sub_w)
        if not opts.jitter:
            out = self._sample(px, py)
        else:
            rng = T.PCG32(count, initstate=dr.opaque(T.ns.UInt64, self._stream_seed()),
                          initseq=T.ns.UInt64(idx))
            shapes = {"color": T.Array3f, "normals": T.Array3f, "depth": T.Float}
            wanted = [k for k, on in (("color", opts.want_color), ("normals", opts.want_normals),
                                      ("depth", opts.want_depth)) if on]
            acc = {k: dr.zeros(shapes[k], count) for k in wanted}

            def cond(k, _rng, _acc):
                return k < dr.opaque(T.UInt32, opts.samples)

            def body(k, rng, acc):
                x = px + T.Float(rng.next_float32())
                y = py + T.Float(rng.next_float32())
                values = self._sample(x, y)
                return k + 1, rng, {name: acc[name] + values[name] for name in acc}

            _, _, out = dr.while_loop((dr.zeros(T.UInt32, count), rng, acc), cond, body)
        dr.eval(out)
        # Array3f.numpy() is (3, n): transpose to one row per sub-pixel.
        return {k: np.asarray(v.numpy()).T if k != "depth" else np.asarray(v.numpy())
                for k, v in out.items()}

    def _stream_seed(self) -> int:
        # splitmix64 of the seed; each sub-pixel draws its samples from its own PCG32 stream
        z = (self.opts.seed * 0x9E3779B97F4A7C15 + 1) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        return z ^ (z >> 31)

    # --- host side --------------------------------------------------------------------------
    def render(self, progress: ProgressFn | None = None) -> RenderResult:
        opts = self.opts
        npf = np.float32 if opts.precision == "single" else np.float64
        n_sub = self.sub_w * self.sub_h
        start = time.perf_counter()
        tiles = [(s, min(TILE_RAYS, n_sub - s)) for s in range(0, n_sub, TILE_RAYS)]
        parts: dict[str, list[np.ndarray]] = {}
        for k, (first, count) in enumerate(tiles):
            for name, v in self._trace(first, count).items():
                parts.setdefault(name, []).append(v.astype(npf, copy=False))
            if progress:
                progress((k + 1) / len(tiles))
        images = {}
        with np.errstate(all="ignore"):
            for name, chunks in parts.items():
                v = np.concatenate(chunks)
                if opts.jitter:
                    v = v / npf(opts.samples)  # the plain mean of the samples (spec §9)
                v = v.reshape((self.sub_h, self.sub_w) + v.shape[1:])
                if opts.filter:
                    v = box_filter_3x3(v)
                images[name] = np.ascontiguousarray(v[::-1])  # row 0 = bottom -> file order
        return RenderResult(images.get("color"), images.get("normals"), images.get("depth"),
                            time.perf_counter() - start, len(tiles))


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
