"""Rendering a course scene with Mitsuba into float images (spec §8, §9), with timings.

    r = ReferenceRenderer(scene, ReferenceOptions(width=48, height=48, kinds=("color", "normals")))
    result = r.render()        # first call: traces and compiles (cold); later calls: warm

Images come back like the tracer's: (rows, columns[, 3]) float32 with row 0 at the TOP; color
unclamped, normals (n+1)/2, depth (t - min)/(max - min).

Anti-aliasing is done here, independently of the tracer: -jitter renders `samples` (16) jittered
samples per (sub)pixel and takes their plain mean; -filter renders the 3w x 3h sub-pixel grid
and applies the 1-2-1 kernel of spec §9 on the host.

The samples are Mitsuba's: its sampler, our sensor and integrator plugins, called as
mi.render's render_sample calls them (same sample positions, same random numbers). Only the
film is ours: each sample's values are kept, and a second kernel adds each pixel's in sample
order, as the course does (a NaN sample keeps its pixel NaN). Mitsuba's film adds them with
atomic scatter-adds, which cost 43% of a 16-sample -filter render on the CPU with the local
pre-reduction that would make them cheap turned off: that pre-reduction turned NaN samples into
0 (falloff 0 with -filter at 128 px and AOVs: 100,992 NaN sub-pixels came out 0). A pairwise sum
(Dr.Jit's block sums) would be cheap too, but its rounding moves truncated bytes (_launch). One
sample per pixel gives mi.render's image bit for bit, 16 the bits of Mitsuba's film.

A render is split into launches of at most MAX_LAUNCH_LANES samples: passes of fewer samples
per pixel (each goes on from the last one's sums) and, for films too large even at one sample,
bands of rows.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from raycheck.tracer.kernel.backend import traced_errors_unwrapped
from raycheck.tracer.process import signals_deferred
from raycheck.tracer.scene.model import Scene

from . import translate, variant

# samples per launch: each keeps its 3-7 channel values in memory (up to 112 MiB here) until
# its pixel's sum is taken
MAX_LAUNCH_LANES = 1 << 22
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
        # Mitsuba calls our plugins' Python constructors from C++, which passes an exception
        # of theirs on as a message: an interrupt there is raised once the scene is loaded
        with signals_deferred():
            self.scene = self.mi.load_dict(translate.load_dict_form(self.plan))
        self.bands, self.passes = launch_plan(*opts.film_size,
                                              opts.samples if opts.jitter else 1)
        self.load_seconds = time.perf_counter() - start
        self.renders = 0

    def close(self) -> None:
        """Free the Mitsuba scene now: its plugins would otherwise stay in every later symbolic
        call's set of instances (Dr.Jit traces all live instances of a class). No reference
        cycle holds any of it (translate._converted), so dropping the reference frees it; a
        full garbage collection here took 0.1 s a call in a large process."""
        self.scene = None

    def _launch(self, first: int, end: int, spp: int, seed: int, sums: list | None) -> list:
        """The values of film rows first..end-1 (row 0 at the top), one Dr.Jit array per channel
        (3 + AOVs) and pixel: without -jitter the one sample's; with it, `sums` (None: 0) plus
        the launch's `spp` samples, added in sample order. Each sample is made as mi.render's
        render_sample makes it."""
        import drjit as dr  # here, not at the top: variant.use() pins libLLVM before drjit loads

        mi = self.mi
        sensor = self.scene.sensors()[0]
        width, height = (int(n) for n in sensor.film().size())
        sampler = sensor.sampler()
        sampler.set_sample_count(spp)
        sampler.set_samples_per_wavefront(spp)
        lanes = (end - first) * width * spp
        sampler.seed(seed, lanes)
        pixel = dr.arange(mi.UInt32, lanes) // dr.opaque(mi.UInt32, spp)
        row = pixel // width
        position = mi.Vector2f(mi.Vector2u(pixel - row * width, row + first))
        # Mitsuba's film position: (pixel + sampler offset) * (1.f / size), in float32
        scale = np.float32(1.0) / np.array([width, height], dtype=np.float32)
        film_position = (position + sampler.next_2d()) * mi.ScalarVector2f(*scale.tolist())
        ray, weight = sensor.sample_ray_differential(sensor.shutter_open(), 0.0, film_position,
                                                     mi.Point2f(0.5))
        spectrum, _, aovs = self.scene.integrator().sample(self.scene, sampler, ray, None,
                                                           mi.Bool(True))
        color = weight * spectrum
        # a channel the integrator leaves constant (no color wanted) is one value for all
        channels = [c if dr.width(c) == lanes else dr.full(mi.Float, c[0], lanes)
                    for c in (color.x, color.y, color.z, *aovs)]
        dr.eval(channels)
        if not self.opts.jitter:
            return channels
        # The course adds a pixel's samples one after another (as Mitsuba's film does, one
        # atomic add per sample in lane order). The order matters: a mean of cube-map texels
        # (k/255) often lands on an 8-bit boundary, where a pairwise sum's rounding moves
        # the truncated byte, one way for many pixels.
        first_sample = dr.arange(mi.UInt32, lanes // spp) * spp

        def add_next(j, acc):
            return j + 1, [a + dr.gather(mi.Float, c, first_sample + j)
                           for a, c in zip(acc, channels)]

        start = sums if sums is not None else [mi.Float(0.0) for _ in channels]
        # a name of its own: assigned to `sums`, mypy would infer the loop state as Optional
        _, new_sums = dr.while_loop((mi.UInt32(0), start), lambda j, acc: j < spp, add_next,
                                    labels=("sample", "sums"), label="sample_order_sums")
        dr.eval(new_sums)
        return new_sums

    def render(self) -> ReferenceResult:
        import drjit as dr  # here, not at the top: variant.use() pins libLLVM before drjit loads

        opts = self.opts
        start = time.perf_counter()
        acc = None
        launch = 0
        for first, end in self.bands:
            values = None
            for spp in self.passes:
                # every launch draws its own samples, and goes on from the last one's sums
                with traced_errors_unwrapped():
                    values = self._launch(first, end, spp,
                                          translate.sampler_seed(opts.seed, launch), values)
                launch += 1
            assert values is not None  # check() makes samples >= 1: at least one pass
            band = np.stack([np.asarray(c, dtype=np.float32) for c in values], axis=-1)
            if opts.jitter:
                with np.errstate(all="ignore"):
                    band = band / np.float32(sum(self.passes))  # the plain mean (spec §9)
            if acc is None:
                width, height = opts.film_size
                acc = np.empty((height, width, band.shape[1]), np.float32)
            acc[first:end] = band.reshape(end - first, -1, band.shape[1])
        assert acc is not None  # check() makes height >= 1: at least one band
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
        return ReferenceResult(color, normals, depth, seconds, self.load_seconds,
                               len(self.passes))


def launch_plan(width: int, height: int, samples: int) -> tuple[list[tuple[int, int]], list[int]]:
    """Bands of film rows (first, end) and samples per pass such that one band at one pass is
    at most MAX_LAUNCH_LANES samples (a band is at least one row of one sample)."""
    per_pass = max(1, min(samples, MAX_LAUNCH_LANES // max(1, width * height)))
    passes = [per_pass] * (samples // per_pass)
    if samples % per_pass:
        passes.append(samples % per_pass)
    rows = max(1, MAX_LAUNCH_LANES // (width * per_pass))
    return [(y, min(y + rows, height)) for y in range(0, height, rows)], passes


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
