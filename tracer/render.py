"""Rendering a parsed scene into float images (spec §4, §8, §9).

One kernel traces every (sub)pixel of a launch, with -jitter its samples (a loop inside the
kernel, adding them in sample order); images of more than TILE_RAYS sub-pixels, or renders of
more than LAUNCH_WORK ray casts, take several launches of the same cached kernel. The kernel
scatters its values straight into top-down row-major buffers: returned arrays are (rows,
columns[, 3]) with row 0 at the TOP, as written to files.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from .accel.flat_scene import flatten
from .accel.intersect import Intersector
from .accel.screen_tiles import TILE, device_lists, screen_tiles
from .arithmetic import arithmetic
from .arithmetic.mistaken import switches_of
from .kernel.backend import import_drjit, recording_kernel
from .kernel.frozen import call_frozen, jit_state, plain_state
from .kernel.uniforms import uniform
from .kernel.vecmath import Types, make_types
from .mistakes import Code, hooks
from .operators import APPLY, ENTRIES, K, Operator, Site, op_code, site_codes
from .options import RenderOptions
from .pixel_index import OUTPUT_FORMS, TAP_FORMS, filter_taps, read_output
from .render_limits import check_render_limits
from .scene.model import Scene
from .shade import auxiliary

# the generated mistakes' sites (operators.py) Renderer::Render computes: the camera rays' ndc,
# the normal and depth images' mappings in the kernel; the samples' loop and the filter on the
# host
NDC = {"x": (Site.NDC_X_SCALE, Site.NDC_X_DENOMINATOR, Site.NDC_X_SHIFT),
       "y": (Site.NDC_Y_SCALE, Site.NDC_Y_DENOMINATOR, Site.NDC_Y_SHIFT)}
NDC_OPERATED = {"x": (Site.NDC_X_PRODUCT, Site.NDC_X_QUOTIENT),
                "y": (Site.NDC_Y_PRODUCT, Site.NDC_Y_QUOTIENT)}
NORMALS_OFFSET = (Site.NORMALS_OFFSET_X, Site.NORMALS_OFFSET_Y, Site.NORMALS_OFFSET_Z)
# (site, axis, from the end of the array) of the lines a loop skips: array row 0 is the top
PIXEL_LINES = ((Site.COLUMNS_START, 1, False), (Site.COLUMNS_END, 1, True),
               (Site.ROWS_START, 0, True), (Site.ROWS_END, 0, False))
OUTPUT_LINES = ((Site.OUTPUT_COLUMNS_START, 1, False), (Site.OUTPUT_COLUMNS_END, 1, True),
                (Site.OUTPUT_ROWS_START, 0, True), (Site.OUTPUT_ROWS_END, 0, False))
# the sites of the per-pixel sums' start values and of their += per image kind
STARTS = {"color": (Site.COLOR_START_R, Site.COLOR_START_G, Site.COLOR_START_B),
          "normals": (Site.NORMALS_START_X, Site.NORMALS_START_Y, Site.NORMALS_START_Z),
          "depth": (Site.DEPTH_START,)}
SUMS = {"color": Site.COLOR_SUM, "normals": Site.NORMALS_SUM, "depth": Site.DEPTH_SUM}
ADDS = {"color": Site.COLOR_ADD, "normals": Site.NORMALS_ADD, "depth": Site.DEPTH_ADD}
MEANS = {"color": Site.COLOR_MEAN, "normals": Site.NORMALS_MEAN, "depth": Site.DEPTH_MEAN}
FILTER_WEIGHTS = ((Site.FILTER_WEIGHT_00, Site.FILTER_WEIGHT_01, Site.FILTER_WEIGHT_02),
                  (Site.FILTER_WEIGHT_10, Site.FILTER_WEIGHT_11, Site.FILTER_WEIGHT_12),
                  (Site.FILTER_WEIGHT_20, Site.FILTER_WEIGHT_21, Site.FILTER_WEIGHT_22))
# the mistakes of the camera rays and the -jitter samples, computed in the kernel below, and
# those at the sites above
HOOKS = hooks(
    __name__,
    Code.JITTER_AUX_ONE_SAMPLE,
    Code.JITTER_CENTRED,
    Code.JITTER_FIXED,
    Code.NDC_HALF_SHIFT,
    Code.NDC_PIXEL_CENTRE,
    *site_codes(*NDC["x"], *NDC["y"], *NDC_OPERATED["x"], *NDC_OPERATED["y"],
                *NORMALS_OFFSET, Site.NORMALS_DIVISOR,
                Site.DEPTH_OFFSET, Site.DEPTH_RANGE, Site.SAMPLE_LOOP, Site.SAMPLE_LOOP_START,
                Site.SAMPLE_LOOP_BOUND, Site.JITTER_WIDTH, *SUMS.values(), *ADDS.values(),
                *MEANS.values(),
                *(s for row in FILTER_WEIGHTS for s in row),
                Site.FILTER_DIVISOR, Site.FILTER_TAP_INDEX, Site.OUTPUT_INDEX,
                *(s for s, _, _ in PIXEL_LINES + OUTPUT_LINES),
                *(s for sites in STARTS.values() for s in sites)),
)
FILTER_KERNEL = np.array(K)
TILE_RAYS = 1 << 21
# Ray casts one launch may do at most (~0.5-2 s on a CPU): a longer render takes several
# launches, jittered samples too (each launch goes on from the sums and random streams of the
# last, in sample order), so that Ctrl-C stops it between launches within about a second.
LAUNCH_WORK = 1 << 24


@dataclass
class RenderResult:
    color: np.ndarray | None  # (h, w, 3) unclamped floats
    normals: np.ndarray | None  # (h, w, 3) values (n+1)/2
    depth: np.ndarray | None  # (h, w) values (t-min)/(max-min)
    seconds: float
    launches: int  # kernel launches (image tiles); jitter samples loop inside the kernel
    aux: dict[str, np.ndarray] = field(default_factory=dict)  # name -> image (auxiliary.py)


ProgressFn = Callable[[float], None]


class Renderer:
    """A scene prepared for rendering with fixed options; render() may be called repeatedly
    (warm runs reuse the compiled kernel)."""

    def __init__(self, scene: Scene, opts: RenderOptions,
                 intersector: Intersector | None = None) -> None:
        """intersector: that of an earlier Renderer of the same scene, backend, precision,
        accel and mode, to reuse (its BVHs and octrees) for other sizes and flags."""
        check_render_limits(opts)
        auxiliary.check_aux_request(opts)
        self.arith = arithmetic(opts)
        self.switches = switches_of(opts)
        scene = self.arith.prepare(scene)
        self.scene = scene
        self.opts = opts
        self.T: Types = make_types(opts.backend, opts.precision)
        self.dr = import_drjit()
        frame = self.arith.camera_frame(scene.camera)
        # the camera as run-time values (uniforms.py); the origin as an array to copy per lane
        self.center = self.T.Float(frame.center.tolist())
        self.forward, self.right, self.up = (uniform(self.T, v.tolist())
                                             for v in (frame.forward, frame.right, frame.up))
        if intersector is None:
            exact = self.arith.course_tests and opts.precision == "single"
            intersector = self.arith.intersector(flatten(scene, course=exact), self.T,
                                                 opts.accel)
        elif intersector.T != self.T or type(intersector) is not self.arith.intersector:
            raise ValueError("the intersector was made for another backend, precision or mode")
        self.isect = intersector
        self.background = self.arith.background(scene.background, self.T)
        self.shader = self.arith.shader(scene, self.isect, self.background, self.T,
                                        opts.shadows, opts.bounces)
        self.sub_w = opts.width * (3 if opts.filter else 1)
        self.sub_h = opts.height * (3 if opts.filter else 1)
        self.blocked = self.sub_w % 4 == 0 and self.sub_h % 4 == 0
        self.tiles, self.tile_columns = self._screen_tiles(frame)
        self.aux_buffers = auxiliary.aux_buffers(opts.aux, len(scene.lights)) \
            if opts.aux else []
        # Renders after the first replay its recorded launches (dr.freeze: no tracing, 10-17
        # ms of a warm 800x800 course render); the arrays and the plain attributes the
        # kernels are made from are its inputs, so that a change of either traces again,
        # except the seed: a run-time argument, so that a reseeded render replays too.
        self._frozen = self.dr.freeze(self._trace, state_fn=self._frozen_state,
                                      backend=self.dr.backend_v(self.T.Float))

    def _screen_tiles(self, frame) -> tuple[tuple | None, int]:
        """The camera rays' triangle lists (accel/screen_tiles.py) as device arrays (starts,
        triangles) and the tiles a row, or (None, 0) where the BVH answers them: only in
        the course's tests (robust mode's rays start elsewhere and test triangles another
        way), with the BVH built."""
        isect = self.isect
        if not self.arith.course_tests or self.opts.precision != "single" \
                or isect.triangles.bvh is None:
            return None, 0
        tiles = screen_tiles(frame, isect.flat.triangles, isect.flat.instances,
                             isect.triangles.device_index(), self.sub_w, self.sub_h)
        if tiles is None:
            return None, 0
        return device_lists(self.T, tiles.starts, tiles.triangles), tiles.columns

    # --- the kernel -----------------------------------------------------------------------
    def _sample(self, px, py, tile=None) -> dict:
        """Image values of one sample at sub-pixel coordinates (px, py), y up; tile: the
        lanes' screen tiles (accel/screen_tiles.py), where the renderer has them."""
        T, dr, opts = self.T, self.dr, self.opts
        # (w-1.0f) must stay a runtime value: Dr.Jit turns division by a literal into a
        # multiplication by its reciprocal, which is not the course's float division.
        ndcx = self._ndc(px, self.sub_w, "x")
        ndcy = self._ndc(py, self.sub_h, "y")
        d = self.arith.unit((self.forward + ndcx * self.right) + ndcy * self.up)
        # copied to every lane (adding zeros would turn a -0 coordinate into +0)
        o = dr.gather(T.Array3f, self.center, dr.zeros(T.UInt32, dr.width(px)))
        candidates = None
        if tile is not None:
            assert self.tiles is not None  # _trace passes a tile only where there are tiles
            candidates = (*self.tiles, tile)
        hit = self.isect.closest(o, d, need_normal=opts.wants("normals") or opts.wants("color")
                                 or bool(opts.aux),
                                 candidates=candidates)
        out = {}
        record: dict | None = {} if opts.aux else None
        if opts.wants("color") or record is not None:
            color = self.shader.radiance(o, d, hit, record)
            if opts.wants("color"):
                out["color"] = color
        if record is not None:
            record.update(object=hit.order, material=hit.material)
            out.update(auxiliary.kernel_outputs(record, self.aux_buffers, T))
        on = self.switches  # the image mappings' generated mistakes (operators.py)
        if opts.wants("normals"):
            offset = 1.0
            codes = [op_code(s, Operator.CONSTANT) for s in NORMALS_OFFSET]
            if any(code in on for code in codes):
                offset = T.Array3f(*(on.constant(code, T, 1.0) for code in codes))
            half = on.constant(op_code(Site.NORMALS_DIVISOR, Operator.CONSTANT), T, 2.0)
            out["normals"] = (hit.normal + offset) / half  # halving is exact
        if opts.wants("depth"):
            npf = np.float32 if opts.precision == "single" else np.float64
            lo, hi = npf(opts.depth_min), npf(opts.depth_max)
            near = self._opaque(T.Float, float(lo))
            t = self._operated(Site.DEPTH_OFFSET, hit.t - near, hit.t, near)
            span = self._opaque(T.Float, float(hi - lo))
            with np.errstate(divide="ignore"):  # depth_max / 0 is C++'s inf
                for op in ENTRIES[Site.DEPTH_RANGE].operators:
                    span = self.switches.pick(op_code(Site.DEPTH_RANGE, op), T, lambda op=op:
                                              self._opaque(T.Float, float(APPLY[op](hi, lo))),
                                              span)
            out["depth"] = t / span
        return out

    def _ndc(self, p, n: int, axis: str):
        """2*(p/(n-1.0f)) - 1. Robust mode fixes the 0/0 = NaN of a single column or row
        (1xN, Nx1, 1x1 images): there ndc is 0, the image's center line."""
        T, dr = self.T, self.dr
        if self.arith.centred_single_lines and n == 1:
            return dr.zeros(T.Float, dr.width(p))
        on = self.switches  # the camera's mistakes (mistakes.py, operators.py)
        scale, one, shift = (op_code(s, Operator.CONSTANT) for s in NDC[axis])
        below = (self._opaque(T.Float, n - 1.0) if one not in on
                 else self._opaque(T.Float, float(n)) - on.constant(one, T, 1.0))
        two, quotient = on.constant(scale, T, 2.0), p / below
        quotient = self._operated(NDC_OPERATED[axis][1], quotient, p, below)
        ndc = self._operated(NDC_OPERATED[axis][0], two * quotient, two, quotient) \
            - on.constant(shift, T, 1.0)
        ndc = on.pick(Code.NDC_HALF_SHIFT, T,
                      lambda: 2.0 * ((p + 0.5) / self._opaque(T.Float, n - 1.0)) - 1.0, ndc)
        return on.pick(Code.NDC_PIXEL_CENTRE, T,
                       lambda: 2.0 * ((p + 0.5) / self._opaque(T.Float, float(n))) - 1.0, ndc)

    def _operated(self, site: Site, course, a, b):
        """`a op b` where an arithmetic mistake of `site` is on (operators.Operator), else the
        course's value."""
        on = self.switches
        for op in ENTRIES[site].operators:
            course = on.pick(op_code(site, op), self.T, lambda op=op: APPLY[op](a, b), course)
        return course

    def _lanes(self, first: int, count: int):
        """Sub-pixel coordinates (x, y up) and top-down row-major positions of lanes
        first..first+count-1. Where the sub-image's sides are multiples of 4, each 16
        consecutive lanes cover a 4x4 block of sub-pixels (bands of 4 rows, top down): packets
        of nearby rays take similar paths through the BVH and the mirror loop."""
        T, dr = self.T, self.dr
        k = dr.arange(T.UInt32, count) + self._opaque(T.UInt32, first)
        sub_w = self._opaque(T.UInt32, self.sub_w)
        if self.blocked:
            band = k // self._opaque(T.UInt32, 4 * self.sub_w)
            r = k - band * self._opaque(T.UInt32, 4 * self.sub_w)
            x = (r >> 4) * 4 + (r & 3)
            y_top = band * 4 + ((r >> 2) & 3)
        else:
            y_top = k // sub_w
            x = k - y_top * sub_w
        y = self._opaque(T.UInt32, self.sub_h - 1) - y_top
        return x, y, y_top * sub_w + x

    def _opaque(self, tp, value):
        """An opaque (run-time) scalar: a literal would be folded into the kernel (see _ndc).
        Made anew in each trace, inside the frozen launch (a replay makes none), so that the
        launch's inputs are the same from the first render on."""
        return self.dr.opaque(tp, value)

    def _frozen_state(self, *args) -> tuple:
        """What a frozen launch is made from besides its arguments (frozen.py), the seed
        left out."""
        return (jit_state(self), plain_state(self, skip=("opts",)),
                repr(replace(self.opts, seed=0)))  # a string: see plain_state

    def _trace(self, first: int, count: int, out: dict, samples: tuple[int, int],
               seed=None) -> None:
        """Traces lanes first..first+count-1 and scatters their values, or with -jitter the sums
        of their jittered samples s0..s1-1 (samples = (s0, s1)) added in sample order to the
        sums of samples 0..s0-1 already in the top-down row-major buffers `out`; `seed`: the
        run-time UInt64 stream seed (-jitter)."""
        T, dr, opts = self.T, self.dr, self.opts
        x, y, pos = self._lanes(first, count)
        px, py = T.Float(x), T.Float(y)
        tile = None
        if self.tiles is not None:
            row = (self._opaque(T.UInt32, self.sub_h - 1) - y) // TILE
            tile = row * self._opaque(T.UInt32, self.tile_columns) + x // TILE
        if not opts.jitter:
            values = self._sample(px, py, tile)
        else:
            s0, s1 = samples
            # Each sub-pixel draws its samples from its own PCG32 stream, numbered by its
            # row-major index from the bottom row. seed() rather than the constructor's
            # arguments: the constructor adds the lane number, which depends on the launch
            # split and the lane blocks.
            pix = T.ns.UInt64(y * self._opaque(T.UInt32, self.sub_w) + x)
            rng = T.PCG32(count)
            rng.seed(initstate=seed + pix, initseq=pix)
            shapes = {"color": T.Array3f, "normals": T.Array3f, "depth": T.Float}
            if s0:  # go on where the last launch stopped: two draws per sample
                rng += self._opaque(T.ns.Int64, 2 * s0)  # PCG32 jumps ahead
                acc = {k: dr.gather(shapes[k], buf, pos) for k, buf in out.items()}
            else:
                acc = {k: dr.zeros(shapes[k], count) for k in out}

            def cond(k, _rng, _acc):
                return k < self._opaque(T.UInt32, s1)

            on = self.switches  # the -jitter mistakes (mistakes.py)
            n = self._opaque(T.Float, float(opts.samples)) \
                if Code.JITTER_AUX_ONE_SAMPLE in on else None

            width = op_code(Site.JITTER_WIDTH, Operator.CONSTANT)

            def offset(u):
                u = on.pick(width, T, lambda: u * on.value(width, T), u)
                u = on.pick(Code.JITTER_CENTRED, T,
                            lambda: (u - 0.5) * on.value(Code.JITTER_CENTRED, T), u)
                return on.pick(Code.JITTER_FIXED, T,
                               lambda: on.value(Code.JITTER_FIXED, T) + 0.0 * u, u)

            def add(name, total, value):
                added = on.pick(op_code(SUMS[name], Operator.ASSIGNED), T, lambda: value,
                                total + value)
                if name == "color":
                    return added
                # one sample's value n times: the host's division by n gives it back
                return on.pick(Code.JITTER_AUX_ONE_SAMPLE, T, lambda: value * n, added)

            def body(k, rng, acc):
                sx = px + offset(T.Float(rng.next_float32()))
                sy = py + offset(T.Float(rng.next_float32()))
                values = self._sample(sx, sy, tile)
                return k + 1, rng, {name: add(name, acc[name], values[name]) for name in acc}

            start = self._opaque(T.UInt32, s0)
            _, _, values = dr.while_loop((start + dr.zeros(T.UInt32, count), rng, acc), cond,
                                         body)
        for name, buf in out.items():
            # one scatter per buffer (an Array3f lands at 3·pos..3·pos+2): a second scatter
            # into the same buffer would make Dr.Jit evaluate the first in a kernel of its own
            dr.scatter(buf, values[name], pos)
        dr.eval(out)

    def launches(self) -> list[tuple[int, int, tuple[int, int]]]:
        """(first lane, lane count, (first sample, end sample)) of each launch: bands of 4 rows
        (or rows) of at most TILE_RAYS lanes, and at most LAUNCH_WORK ray casts each (a ray
        per sample, mirror level and, with -shadows, light)."""
        opts = self.opts
        n_sub = self.sub_w * self.sub_h
        # none traced is a black image (host_sites): one is, to fill the buffers
        samples = max(1, traced_samples(opts)) if opts.jitter else 1
        per_sample = (1 + opts.bounces) * (1 + (len(self.scene.lights) if opts.shadows else 0))
        step = self.sub_w * (4 if self.blocked else 1)
        lanes = max(1, TILE_RAYS // step) * step
        if lanes * samples * per_sample > LAUNCH_WORK:
            # fewer lanes (whole 16-lane packets), and if even those are too many for all the
            # samples, the samples in chunks
            lanes = min(lanes, max(16, LAUNCH_WORK // (per_sample * samples) // 16 * 16))
        chunk = max(1, min(samples, LAUNCH_WORK // (per_sample * lanes)))
        return [(first, min(lanes, n_sub - first), (s0, min(s0 + chunk, samples)))
                for first in range(0, n_sub, lanes) for s0 in range(0, samples, chunk)]

    def _stream_seed(self) -> int:
        # splitmix64 of the seed; each sub-pixel draws its samples from its own PCG32 stream
        z = (self.opts.seed * 0x9E3779B97F4A7C15 + 1) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        return z ^ (z >> 31)

    # --- host side --------------------------------------------------------------------------
    def render(self, progress: ProgressFn | None = None) -> RenderResult:
        T, dr, opts = self.T, self.dr, self.opts
        n_sub = self.sub_w * self.sub_h
        start = time.perf_counter()
        launches = self.launches()
        out = {k: dr.empty(T.Float, n_sub * (1 if k == "depth" else 3)) for k in opts.kinds}
        out.update({b.key: dr.empty(T.UInt32 if b.integer else T.Float, n_sub * b.channels)
                    for b in self.aux_buffers})
        seed = self._opaque(T.ns.UInt64, self._stream_seed()) if opts.jitter else None
        with recording_kernel():
            for k, (first, count, samples) in enumerate(launches):
                call_frozen(self._frozen, first, count, out, samples, seed)
                dr.sync_thread()  # the launch is done before the next: Ctrl-C is seen in between
                if progress:
                    progress((k + 1) / len(launches))
        images = {}
        aux = {b.key: out.pop(b.key).numpy() for b in self.aux_buffers}
        with np.errstate(all="ignore"):
            for name, buf in out.items():
                v = buf.numpy().reshape((self.sub_h, self.sub_w) + (() if name == "depth"
                                                                    else (3,)))
                if opts.jitter:
                    v = v / v.dtype.type(opts.samples)  # the plain mean of the samples (spec §9)
                if opts.mistakes:
                    v = host_sites(v, name, opts, PIXEL_LINES)
                v = output_image(v, opts)
                if opts.mistakes:
                    v = skipped_lines(v, opts, OUTPUT_LINES)
                images[name] = v
        if aux:
            aux = auxiliary.assemble(aux, self.aux_buffers, (self.sub_h, self.sub_w),
                                     auxiliary.scene_objects(self.scene), opts.aux)
        return RenderResult(images.get("color"), images.get("normals"), images.get("depth"),
                            time.perf_counter() - start, len(launches), aux)


def lane_positions(sub_w: int, sub_h: int) -> np.ndarray:
    """Top-down row-major positions of lanes 0..sub_w·sub_h-1, as Renderer._lanes orders them
    (4x4 blocks of sub-pixels per 16 lanes where both sides are multiples of 4): for casting
    rays elsewhere (the throughput bench) in the order a render casts them."""
    k = np.arange(sub_w * sub_h, dtype=np.int64)
    if sub_w % 4 or sub_h % 4:
        return k
    band, r = k // (4 * sub_w), k % (4 * sub_w)
    return (band * 4 + ((r >> 2) & 3)) * sub_w + (r >> 4) * 4 + (r & 3)


def _host_value(opts: RenderOptions, site: Site, op: Operator = Operator.CONSTANT):
    """The value of the generated mistake at a site the host computes, where it is on (a
    mistake without a parameter: 0.0), else None."""
    code = op_code(site, op)
    return next((s.value or 0.0 for s in opts.mistakes if s.code == code), None)


def traced_samples(opts: RenderOptions) -> int:
    """How many samples Renderer::Render's loop adds up a (sub-)pixel: the course's (with
    -jitter opts.samples, else 1), or fewer where a generated mistake ends the loop early, less
    the generated mistake's start of the loop (none below zero); the sums are divided by the
    course's count all the same."""
    samples = opts.samples if opts.jitter else 1
    bound = _host_value(opts, Site.SAMPLE_LOOP_BOUND)
    if bound is not None:
        samples = min(samples, int(bound))
    return max(0, samples - int(_host_value(opts, Site.SAMPLE_LOOP_START) or 0))


def host_sites(v: np.ndarray, kind: str, opts: RenderOptions, lines) -> np.ndarray:
    """An image of the sub-pixels as Renderer::Render's sums give it, with the generated
    mistakes at its host sites: the one ray of a pixel without -jitter added up as often as
    the samples' loop runs (the kernel traces a jittered pixel's samples), each sum's start
    value (divided by the samples like the sums) after the samples' loop or the line that adds
    to this kind's sum left out, the sum not divided by the samples or multiplied by them,
    lines the loop over the sub-pixels skips."""
    samples = opts.samples if opts.jitter else 1
    traced = traced_samples(opts)
    if not opts.jitter and traced > 1:
        # the same ray's value n times: as the loop's sum for n = 2 and 3 (a start of -1, -2)
        v = v * v.dtype.type(traced)
    if traced == 0 or _host_value(opts, Site.SAMPLE_LOOP, Operator.DELETED) is not None \
            or _host_value(opts, ADDS[kind], Operator.DELETED) is not None:
        v = np.zeros_like(v)
    start = [_host_value(opts, s) or 0.0 for s in STARTS[kind]]
    if any(start):
        v = v + (np.array(start, v.dtype) if v.ndim == 3 else v.dtype.type(start[0])) \
            / v.dtype.type(samples)
    # v is the mean already: exactly the sum again where the samples are a power of two
    if _host_value(opts, MEANS[kind], Operator.DELETED) is not None:
        v = v * v.dtype.type(samples)
    elif _host_value(opts, MEANS[kind], Operator.TIMES) is not None:
        v = v * v.dtype.type(samples * samples)
    return skipped_lines(v, opts, lines)


def skipped_lines(v: np.ndarray, opts: RenderOptions, lines) -> np.ndarray:
    """v with the lines the generated loop-bound mistakes skip black: (site, axis, from the
    end) each."""
    for site, axis, from_end in lines:
        n = int(_host_value(opts, site) or 0)
        if n:
            v = v.copy()
            index = [slice(None)] * v.ndim
            index[axis] = slice(v.shape[axis] - n, None) if from_end else slice(0, n)
            v[tuple(index)] = 0
    return v


def output_image(v: np.ndarray, opts: RenderOptions) -> np.ndarray:
    """The image Renderer::Render writes from its buffer of (sub-)pixel values: with -filter
    each pixel its 3x3 taps' weighted sum, else the pixel's own value, each read at the index
    a generated mistake gives it where one is on. Where the C program could not read an index
    (out of the buffer, a division by zero) its image is not defined: black here."""
    if opts.filter:
        kernel, divisor = filter_weights(opts)
        form = _host_value(opts, Site.FILTER_TAP_INDEX, Operator.INDEX)
        if form is None:
            return box_filter_3x3(v, kernel, divisor)
        out = filter_taps(v, TAP_FORMS[int(form)], kernel, divisor)
        return out if out is not None else np.zeros_like(v[::3, ::3])
    form = _host_value(opts, Site.OUTPUT_INDEX, Operator.INDEX)
    if form is None:
        return v
    out = read_output(v, OUTPUT_FORMS[int(form)])
    return out if out is not None else np.zeros_like(v)


def filter_weights(opts: RenderOptions) -> tuple[np.ndarray, float]:
    """The -filter kernel and divisor of a render: the course's (spec §9), or the values of
    the generated mistakes at their sites that are on."""
    on = {s.code: s.value for s in opts.mistakes}
    kernel = np.array([[on.get(op_code(site, Operator.CONSTANT), K[j][i])
                        for i, site in enumerate(row)] for j, row in enumerate(FILTER_WEIGHTS)])
    divisor = on.get(op_code(Site.FILTER_DIVISOR, Operator.CONSTANT))
    return kernel, 16.0 if divisor is None else divisor


def box_filter_3x3(big: np.ndarray, kernel: np.ndarray = FILTER_KERNEL,
                   divisor: float = 16.0) -> np.ndarray:
    """Output (x, y) = Σ_j Σ_i K[j][i]·big(3x+i, 3y+j) / 16 with y counted from the bottom,
    summed j-major as the course does. `big` and the result are arrays with row 0 at the top:
    sub-row j of an output row is row 2 - j of its block."""
    h, w = big.shape[0] // 3, big.shape[1] // 3
    out = None
    for j in range(3):
        for i in range(3):
            term = big[2 - j::3, i::3][:h, :w] * big.dtype.type(kernel[j][i])
            out = term if out is None else out + term
    return out / big.dtype.type(divisor)


def render(scene: Scene, opts: RenderOptions, progress: ProgressFn | None = None) -> RenderResult:
    return Renderer(scene, opts).render(progress)
