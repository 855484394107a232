"""Rendering a course scene with Mitsuba into float images (spec §8, §9), with timings.

    r = ReferenceRenderer(scene, ReferenceOptions(width=48, height=48, kinds=("color", "normals")))
    result = r.render()        # first call: traces and compiles (cold); later calls: warm

Images come back like the tracer's: (rows, columns[, 3]) float32 with row 0 at the TOP; color
unclamped, normals (n+1)/2, depth (t - min)/(max - min).

Anti-aliasing is done here, independently of the tracer: -jitter renders `samples` (16) jittered
samples per (sub)pixel and takes their plain mean (Mitsuba's film with a box filter divides the
sum by the sample count); -filter renders the 3w x 3h sub-pixel grid and applies the 1-2-1
kernel of spec §9 on the host. Large jittered renders are split into passes of at most
MAX_PASS_LANES rays (the mean of equal-sized pass means is the overall mean).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from raycheck.tracer.scene.model import Scene

from . import translate, variant

MAX_PASS_LANES = 1 << 24  # rays per mi.render call: bounds the memory of one wavefront
# Film pixels per band: a larger film (4096x4096 and up) is rendered in bands of rows, each
# with its own cropped film, so Mitsuba's film and image block stay bounded in memory.
MAX_FILM_PIXELS = 1 << 22
KERNEL = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]], dtype=np.float32)


class OptionError(ValueError):
    """Render options out of range (one-line message)."""


@dataclass(frozen=True)
class ReferenceOptions(translate.Settings):
    """A render request with Mitsuba's own settings."""

    variant: str = variant.DEFAULT_VARIANT

    def check(self) -> None:
        # the limits checked before any work starts, the same as the tracer's
        problem = self.limit_problem()
        if problem:
            raise OptionError(problem)
        if self.offsets not in ("course", "mitsuba"):
            raise OptionError(f"offsets must be course or mitsuba, found {self.offsets!r}")
        if self.variant not in variant.VARIANTS:
            raise OptionError(f"unknown variant {self.variant!r} "
                              "(expected llvm_ad_rgb or cuda_ad_rgb)")


@dataclass
class ReferenceResult:
    color: np.ndarray | None    # (h, w, 3) unclamped floats
    normals: np.ndarray | None  # (h, w, 3) values (n+1)/2
    depth: np.ndarray | None    # (h, w) values (t-min)/(max-min)
    seconds: float              # this render() call
    load_seconds: float         # building the Mitsuba scene (once per renderer)
    passes: int


class ReferenceRenderer:
    """A scene loaded into Mitsuba with fixed options; render() may be called repeatedly."""

    def __init__(self, scene: Scene, opts: ReferenceOptions) -> None:
        opts.check()
        self.opts = opts
        self.mi = variant.use(opts.variant)
        start = time.perf_counter()
        self.plan = translate.plan(scene, opts)
        self.bands = self._bands()
        # one band: the scene stays loaded for warm re-runs; bands each load their own
        self.scene = (self.mi.load_dict(translate.load_dict_form(self.plan))
                      if len(self.bands) == 1 else None)
        self.load_seconds = time.perf_counter() - start
        self.renders = 0

    def close(self) -> None:
        """Free the Mitsuba scene now: its plugins would otherwise stay in every later symbolic
        call's set of instances (Dr.Jit traces all live instances of a class). No reference
        cycle holds any of it (translate._converted), so dropping the reference frees it; a
        full garbage collection here took 0.1 s a call in a large process."""
        self.scene = None

    def _bands(self) -> list[tuple[int, int]]:
        """Film rows (first, end) of each band: the whole film if it is small enough."""
        w, h = self.plan["camera"]["film"]["width"], self.plan["camera"]["film"]["height"]
        rows = max(1, MAX_FILM_PIXELS // w)
        return [(y, min(y + rows, h)) for y in range(0, h, rows)]

    def _band_scene(self, first: int, end: int):
        """The scene with its film cropped to rows first..end-1."""
        film = self.plan["camera"]["film"]
        cropped = {**film, "crop_offset_x": 0, "crop_offset_y": first,
                   "crop_width": film["width"], "crop_height": end - first}
        plan = {**self.plan, "camera": {**self.plan["camera"], "film": cropped}}
        return self.mi.load_dict(translate.load_dict_form(plan))

    def _passes(self) -> list[int]:
        """Samples per pass: all at once if the wavefront is small enough."""
        first, end = self.bands[0]
        w, h = self.plan["camera"]["film"]["width"], end - first
        total = self.opts.samples if self.opts.jitter else 1
        per_pass = max(1, min(total, MAX_PASS_LANES // max(1, w * h)))
        passes = [per_pass] * (total // per_pass)
        if total % per_pass:
            passes.append(total % per_pass)
        return passes

    def _render_band(self, scene, passes: list[int]) -> np.ndarray:
        """(rows, W, 3 + AOVs) of one film (band): the passes' mean, row 0 at the top."""
        import drjit as dr  # here, not at the top: variant.use() pins libLLVM before drjit loads

        mi, opts = self.mi, self.opts
        acc = None
        for k, spp in enumerate(passes):
            seed = translate.sampler_seed(opts.seed, k)
            # The film adds samples with scatter-adds. Dr.Jit's local pre-reduction of those
            # (JitFlag.ScatterReduceLocal, on by default) turned NaN samples into 0 on larger
            # films (falloff 0 with -filter at 128 px and AOVs: 100,992 NaN sub-pixels came out
            # 0), while the course's arithmetic keeps them NaN, so black.
            with dr.scoped_set_flag(dr.JitFlag.ScatterReduceLocal, False):
                image = mi.render(scene, spp=spp, seed=seed)
            data = np.array(image, dtype=np.float32)  # (H, W, 3 + AOVs), row 0 = top
            with np.errstate(all="ignore"):
                # pass means weighted by their sample counts (equal passes: plain mean)
                part = data * np.float32(spp) if len(passes) > 1 else data
                acc = part if acc is None else acc + part
        with np.errstate(all="ignore"):
            return acc / np.float32(sum(passes)) if len(passes) > 1 else acc

    def render(self) -> ReferenceResult:
        import drjit as dr  # here, not at the top: variant.use() pins libLLVM before drjit loads

        opts = self.opts
        start = time.perf_counter()
        passes = self._passes()
        if self.scene is not None:
            acc = self._render_band(self.scene, passes)
        else:
            acc = None
            for first, end in self.bands:
                band = self._render_band(self._band_scene(first, end), passes)
                if acc is None:
                    acc = np.empty((self.bands[-1][1],) + band.shape[1:], np.float32)
                acc[first:end] = band
        with np.errstate(all="ignore"):
            if opts.filter:
                acc = filter_121(acc)
        dr.sync_thread()
        seconds = time.perf_counter() - start
        self.renders += 1
        channels = 3
        normals = depth = None
        if opts.wants("normals"):
            normals = np.ascontiguousarray(acc[..., channels:channels + 3])
            channels += 3
        if opts.wants("depth"):
            depth = np.ascontiguousarray(acc[..., channels])
        color = np.ascontiguousarray(acc[..., :3]) if opts.wants("color") else None
        return ReferenceResult(color, normals, depth, seconds, self.load_seconds, len(passes))


def filter_121(big: np.ndarray) -> np.ndarray:
    """Spec §9 -filter: output pixel = Σ K[j][i] * big(3x+i, 3y+j) / 16 over its 3x3 block of
    sub-pixels. The kernel is symmetric, so flipping rows (film row 0 = top) changes nothing."""
    h, w = big.shape[0] // 3, big.shape[1] // 3
    blocks = big.reshape((h, 3, w, 3) + big.shape[2:])
    out = np.zeros((h, w) + big.shape[2:], dtype=np.float32)
    for j in range(3):
        for i in range(3):
            out = out + blocks[:, j, :, i] * KERNEL[j, i]
    return out / np.float32(16.0)


def render(scene: Scene, opts: ReferenceOptions) -> ReferenceResult:
    renderer = ReferenceRenderer(scene, opts)
    try:
        return renderer.render()
    finally:
        renderer.close()
