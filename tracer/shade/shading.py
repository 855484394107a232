"""The course's Whitted recursion (spec §6) as one Dr.Jit kernel.

The recursion color = (direct + ks ⊙ trace(reflected)) + ambient ⊙ kd is evaluated in the
course's exact order: a forward loop follows the mirror chain and stores each level's direct
sum, ks and ambient term in per-lane local memory; a backward loop then folds them from the
deepest level up, so every float addition happens in the same order as the recursive original.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..accel.intersect import FLT_MAX, Hit, Intersector
from ..kernel.backend import from_numpy, import_drjit
from ..kernel.uniforms import uniform
from ..kernel.vecmath import (
    FLT_MIN_NORMAL,
    Types,
    div3,
    dot,
    round_f32_subnormal,
)
from ..mistakes import hooks
from ..operators import ENTRIES, CourseSites, Operator, Site, site_codes
from ..scene.model import DirectionalLight, Material, PointLight, Scene, reflective_mask
from .background import Background

# the generated mistakes (operators.py) at the sites the shading below computes
HOOKS = hooks(__name__, *site_codes(
    Site.FALLOFF_DIVISION, Site.SHADE_MIRROR_FACTOR, Site.SHADE_DIFFUSE_CLAMP,
    Site.SHADE_SPECULAR_CLAMP, Site.TRACE_MIRROR_FACTOR, Site.TRACE_LIGHT_SUM,
    Site.TRACE_LIGHT_LOOP, Site.TRACE_LIGHT_START, Site.TRACE_BLOCKED_LIGHT,
    Site.TRACE_AMBIENT, Site.LIGHT_VECTOR, Site.LIGHT_DIRECTION_SET,
    Site.LIGHT_INTENSITY_SET,
    Site.DIRECTIONAL_DIRECTION, Site.DIRECTIONAL_DIRECTION_SET, Site.DIRECTIONAL_INTENSITY_SET,
    Site.LIGHT_NORMALISE, Site.FALLOFF_PRODUCT, Site.FALLOFF_OUTER,
    Site.SHADE_DIFFUSE_THRESHOLD, Site.SHADE_SPECULAR_THRESHOLD, Site.SHADE_MIRROR_PRODUCT,
    Site.SHADE_MIRROR_NORMAL, Site.SHADE_MIRROR_DIFFERENCE, Site.SHADE_POWER,
    Site.SHADE_DIFFUSE_LIGHT, Site.SHADE_DIFFUSE_PRODUCT, Site.SHADE_SPECULAR_LIGHT,
    Site.SHADE_SPECULAR_PRODUCT, Site.SHADE_SUM, Site.TRACE_MIRROR_PRODUCT,
    Site.TRACE_MIRROR_NORMAL, Site.TRACE_MIRROR_DIFFERENCE, Site.TRACE_MIRROR_ORIGIN,
    Site.TRACE_MIRROR_WEIGHT, Site.TRACE_AMBIENT_PRODUCT, Site.TRACE_START_R, Site.TRACE_START_G,
    Site.TRACE_START_B, Site.TRACE_SHADOW_TEST, Site.TRACE_MIRROR_OFFSET,
    Site.TRACE_SHADOW_ORIGIN, Site.TRACE_MIRROR_SUM, Site.TRACE_MIRROR_STEP,
    Site.TRACE_MIRROR_RAY, Site.TRACE_SHADOW_RAY))
# the sites of the two mirrored rays, d - (2 * N·d) * N: the highlight's and the reflection's
# (its 2, the 2's product with N·d, that product's with N, the difference)
SHADE_MIRROR = (Site.SHADE_MIRROR_FACTOR, Site.SHADE_MIRROR_PRODUCT, Site.SHADE_MIRROR_NORMAL,
                Site.SHADE_MIRROR_DIFFERENCE)
TRACE_MIRROR = (Site.TRACE_MIRROR_FACTOR, Site.TRACE_MIRROR_PRODUCT, Site.TRACE_MIRROR_NORMAL,
                Site.TRACE_MIRROR_DIFFERENCE)
SHADOW_OFFSET = 0.01  # the course offsets shadow and reflection rays by 0.01 along the ray


def reflect(d, n):
    return d - (2.0 * dot(n, d)) * n


@dataclass(frozen=True)
class LightValues:
    """A light's values as the kernel reads them (uniforms.py): its color, and to_light (the
    negated direction, a literal) or position and falloff. `spec` is the parsed light, for
    the code paths its values choose."""

    spec: DirectionalLight | PointLight
    color: Any
    to_light: Any = None
    position: Any = None
    falloff: Any = None

    @property
    def directional(self) -> bool:
        return isinstance(self.spec, DirectionalLight)


def _light_values(light: DirectionalLight | PointLight, types: Types) -> LightValues:
    if isinstance(light, DirectionalLight):
        return LightValues(light, uniform(types, light.color),
                           to_light=types.Array3f(*(-c for c in light.direction)))
    return LightValues(light, uniform(types, light.color),
                       position=uniform(types, light.position),
                       falloff=uniform(types, light.falloff))


# the light loop of Renderer::traceRay where a generated mistake is at its bounds: the course
# runs it over every light, skipping a blocked one with `continue`; a program may start it late
# (`for (int i = 1; ...)`), end it once some lights have added their terms (a `break` after the
# sum), or end it at a blocked light (a `break` for the `continue`)
BOUNDS = (Site.TRACE_LIGHT_START, Site.TRACE_LIGHT_LOOP, Site.TRACE_BLOCKED_LIGHT)


class LightLoop:
    """Which lanes run the light loop's body at each light: the lanes' counts of the lights
    that have added their terms and of those blocked, and the bounds the mistakes at the
    loop's sites set (the course's where a switch is off)."""

    def __init__(self, sites: CourseSites, T: Any, dr: Any, width: int, lights: int) -> None:
        self.dr = dr
        self.first = sites.site_constant(Site.TRACE_LIGHT_START, 0.0)
        # the course's bounds for the ends: counts the loop never reaches
        self.most = sites.site_constant(Site.TRACE_LIGHT_LOOP, float(lights))
        self.blocks = sites.site_constant(Site.TRACE_BLOCKED_LIGHT, float(lights + 1))
        self.added = dr.zeros(T.Float, width)
        self.blocked = dr.zeros(T.Float, width)

    @staticmethod
    def needed(sites: CourseSites) -> bool:
        """Whether a mistake at one of the loop's bounds may be on (else the course's loop)."""
        return any(sites.site_compiled(s) for s in BOUNDS)

    def step(self, i: int, blocked: Any) -> Any:
        """Whether each lane runs the loop's body for light `i` (whose term then adds where
        the light is not blocked), counting it; `blocked`: None without -shadows."""
        dr = self.dr
        runs = (self.first <= i) & (self.added < self.most) & (self.blocked < self.blocks)
        adds = runs if blocked is None else runs & ~blocked
        self.added = dr.select(adds, self.added + 1.0, self.added)
        if blocked is not None:
            self.blocked = dr.select(runs & blocked, self.blocked + 1.0, self.blocked)
        return runs


class Shader(CourseSites):
    """The course's shading and recursion (robust.py's subclass: robust mode's)."""

    def __init__(self, scene: Scene, intersector: Intersector, background: Background,
                 types: Types, shadows: bool, bounces: int) -> None:
        self.scene = scene
        self.isect = intersector
        self.bg = background
        self.T = types
        self.dr = import_drjit()
        self.shadows = shadows and bool(scene.lights)
        # A scene without materials has no objects either; one default keeps the arrays
        # non-empty for the (never executed) gathers.
        mats = scene.materials or (Material(),)
        npf = types.np_float
        kd = np.array([m.diffuse for m in mats], np.float32).reshape(-1, 3)
        ks = np.array([m.specular for m in mats], np.float32).reshape(-1, 3)
        reflective = self._reflective(mats)
        self.any_reflective = bool(reflective.any())
        self.bounces = bounces if self.any_reflective else 0
        self.kd = types.Float(kd.astype(npf).ravel())
        self.ks = types.Float(ks.astype(npf).ravel())
        self.shininess = from_numpy(types.Float, np.array([m.shininess for m in mats], npf))
        self.reflective = from_numpy(types.UInt32, reflective.astype(np.uint32))
        self.lights = [_light_values(light, types) for light in scene.lights]
        # a directional light's shadow rays share their direction: a grid of the triangles
        # along it answers them (shadow_grid.py) where one can be made (isinstance: what
        # light.directional tests, spelled out so that the type checker knows the direction)
        self.shadow_grids = [intersector.shadow_grid([-c for c in light.spec.direction])
                             if self.shadows and isinstance(light.spec, DirectionalLight)
                             and intersector.triangles.count
                             else None for light in self.lights]
        # a scene without lights has the ambient light forced to 1 (spec §6), nothing to edit:
        # a literal 1, whose product Dr.Jit drops, keeps a subnormal kd as the course's C
        # does, where its worker threads would flush 1 * kd to 0 (uniforms.py)
        ambient = scene.background.ambient
        self.ambient_light = uniform(types, ambient) if scene.lights else types.Array3f(*ambient)

    def _reflective(self, materials) -> np.ndarray:
        """Per material: whether a ray hitting it recurses (spec §6: |ks| > 0.1)."""
        return reflective_mask(materials)

    # --- material and light terms ---------------------------------------------------------
    def _gather3(self, arr, mat):
        return self.dr.gather(self.T.Array3f, arr, mat)

    def powf(self, x, e):
        """powf(x, e) correctly rounded: evaluated in double, as glibc's powf effectively is;
        Dr.Jit's float32 power is off by up to ~100 ulp. powf(x, 0) = 1 for every x.
        The double evaluation is a branch that packets skip when every lane has x = ±0 and
        e > 0 (unlit highlights, R·L clamped to 0): there it gives exactly 0 (log2(±0) = -inf,
        times e > 0 is below -151), which the other branch returns."""
        dr, T = self.dr, self.T

        def in_double(x, e):
            y = dr.log2(T.Float64(dr.abs(x))) * T.Float64(e)
            # Dr.Jit 1.5's exp2 returns -inf for results in double's subnormal range (y in
            # about [-1075, -1022]); anything below 2^-151 rounds to 0 in float32 anyway.
            r = T.Float(dr.select(y < -151.0, 0.0, dr.exp2(y)))
            # a negative base (never the course's: its cosines are clamped; a program's that
            # does not clamp them) as C's powf takes it: an integer exponent gives the power's
            # sign, any other NaN
            whole = dr.floor(e) == e
            odd = whole & (dr.floor(e * 0.5) * 2.0 != e)
            return dr.select(x < 0.0, dr.select(whole, dr.select(odd, -r, r), dr.nan), r)

        def zero(x, e):
            return dr.zeros(T.Float, dr.width(x))

        r = dr.if_stmt((x, e), (x != 0.0) | ~(e > 0.0), in_double, zero)
        return dr.select((e == 0.0) | (x == 1.0), 1.0, r)

    def _point_intensity(self, light, dist):
        """color / ((dist·falloff)·dist) in float32. A subnormal falloff would read as 0 in
        Dr.Jit's kernels (worker threads flush subnormals) and make the light infinitely
        bright; then the two products and the division are evaluated in double, each rounded
        to float32 as the course's C arithmetic rounds it, subnormals kept (spec §6)."""
        T, spec = self.T, light.spec
        if T.precision != "single" or not 0.0 < abs(spec.falloff) < FLT_MIN_NORMAL:
            return div3(light.color, (dist * light.falloff) * dist)
        d64 = T.Float64(dist)  # a code path of its own, chosen by the value: literals here
        den = round_f32_subnormal(round_f32_subnormal(d64 * spec.falloff) * d64)
        return T.Array3f(*(T.Float(round_f32_subnormal(c / den)) for c in spec.color))

    def _material(self, mat):
        """kd, ks and shininess of the hit materials."""
        return (self._gather3(self.kd, mat), self._gather3(self.ks, mat),
                self.dr.gather(self.T.Float, self.shininess, mat))

    def _phong(self, n, to_light, rl, intensity, material, record=None, light=0):
        """shade() of spec §6: max(N·L, 0)·I ⊙ kd + rl^shininess·I ⊙ ks, with rl = the
        clamped R·L (each mode clamps it its own way). `record`: a dict that receives the
        light's parts (auxiliary.py)."""
        kd, ks, shin = material
        nl = dot(n, to_light)
        ks, shin = self.specular_material(ks, shin, nl)
        cosine = self.diffuse_cosine(nl)
        lit = self.site_arithmetic(Site.SHADE_DIFFUSE_LIGHT, cosine * intensity, {
            Operator.PLUS: lambda: cosine + intensity, Operator.MINUS: lambda: cosine - intensity})
        diffuse = self.site_arithmetic(Site.SHADE_DIFFUSE_PRODUCT, lit * kd, {
            Operator.PLUS: lambda: lit + kd, Operator.MINUS: lambda: lit - kd})
        power = self.powf(*self.site_swapped(Site.SHADE_POWER, rl, shin))
        shine = self.site_arithmetic(Site.SHADE_SPECULAR_LIGHT, power * intensity, {
            Operator.PLUS: lambda: power + intensity, Operator.MINUS: lambda: power - intensity})
        specular = self.site_arithmetic(Site.SHADE_SPECULAR_PRODUCT, shine * ks, {
            Operator.PLUS: lambda: shine + ks, Operator.MINUS: lambda: shine - ks})
        if record is not None:
            record.update({f"diffuse:{light}": diffuse, f"specular:{light}": specular,
                           f"cos_nl:{light}": nl, f"cos_rl:{light}": rl,
                           f"intensity:{light}": intensity})
        return self.site_arithmetic(Site.SHADE_SUM, diffuse + specular, {
            Operator.MINUS: lambda: diffuse - specular,
            Operator.TIMES: lambda: diffuse * specular})

    def mirrored(self, d, n, sites: tuple[Site, Site, Site, Site]):
        """d mirrored about n, d - (2 * N·d) * N, as shade() and traceRay() compute it, through
        their sites (SHADE_MIRROR, TRACE_MIRROR). A float in a vector's place is the vector of
        three of it, as vecmath's implicit constructor reads it."""
        two, product, normal, difference = sites
        factor, nd = self.site_constant(two, 2.0), dot(n, d)
        scale = self.site_arithmetic(product, factor * nd, {
            Operator.PLUS: lambda: factor + nd, Operator.MINUS: lambda: factor - nd,
            Operator.DIVIDED: lambda: factor / nd})
        along = self.site_arithmetic(normal, scale * n, {
            # d - s + N and d - s - N as d minus (s - N) and (s + N)
            Operator.PLUS: lambda: scale - n, Operator.MINUS: lambda: scale + n})
        return self.site_arithmetic(difference, d - along, {Operator.TIMES: lambda: d * along})

    def diffuse_cosine(self, nl):
        """N·L as the diffuse term takes it: clamped at 0 (spec §6)."""
        below = self.site_compare(Site.SHADE_DIFFUSE_CLAMP, nl,
                                  self.site_constant(Site.SHADE_DIFFUSE_THRESHOLD, 0.0))
        return self.dr.select(below, self.site_constant(Site.SHADE_DIFFUSE_CLAMP, 0.0), nl)

    def specular_material(self, ks, shininess, nl):
        """(ks, shininess) as the specular term takes them: the material's (spec §6)."""
        return ks, shininess

    def highlight_cosine(self, d, n, r, to_light):
        """The cosine the specular term raises to the shininess, before clamping: R·L with R
        the mirrored view ray (spec §6)."""
        return dot(r, to_light)

    def toward(self, light: LightValues, p):
        """(to_light, intensity, distance) of a light at the points p, as the course's
        getIllumination gives them (spec §6); a directional light's distance is FLT_MAX."""
        def unset():  # traceRay's Vector3f before getIllumination sets it
            return self.dr.zeros(self.T.Array3f, self.dr.width(p))

        if light.directional:
            to_light = self.site_deleted(Site.DIRECTIONAL_DIRECTION_SET, self.site_sign(
                Site.DIRECTIONAL_DIRECTION, light.to_light), unset)
            return to_light, self.site_deleted(Site.DIRECTIONAL_INTENSITY_SET, light.color,
                                               unset), FLT_MAX
        at, color, falloff = light.position, light.color, light.falloff
        v = self.site_arithmetic(Site.LIGHT_VECTOR, at - p, {
            Operator.PLUS: lambda: at + p, Operator.TIMES: lambda: at * p})
        dist = self.dr.sqrt(dot(v, v))
        near = dist * falloff
        intensity = self.site_arithmetic(Site.FALLOFF_PRODUCT, self._point_intensity(light, dist), {
            Operator.PLUS: lambda: div3(color, (dist + falloff) * dist),
            Operator.MINUS: lambda: div3(color, (dist - falloff) * dist),
            Operator.DIVIDED: lambda: div3(color, (dist / falloff) * dist)})
        intensity = self.site_arithmetic(Site.FALLOFF_OUTER, intensity, {
            Operator.PLUS: lambda: div3(color, near + dist),
            Operator.MINUS: lambda: div3(color, near - dist)})
        intensity = self.site_arithmetic(Site.FALLOFF_DIVISION, intensity, {
            Operator.PLUS: lambda: color + near * dist,
            Operator.MINUS: lambda: color - near * dist,
            Operator.TIMES: lambda: color * (near * dist)})
        to_light = self.site_arithmetic(Site.LIGHT_NORMALISE, div3(v, dist), {
            Operator.PLUS: lambda: v + dist, Operator.MINUS: lambda: v - dist,
            Operator.TIMES: lambda: v * dist})
        return (self.site_deleted(Site.LIGHT_DIRECTION_SET, to_light, unset),
                self.site_deleted(Site.LIGHT_INTENSITY_SET, intensity, unset), dist)

    def shadow_ray(self, p, n, to_light, dist):
        """(origin, distance blockers count up to) of the shadow ray from p toward a light:
        p + 0.01·L, up to the light's distance (spec §6)."""
        return self._offset(p, to_light, SHADOW_OFFSET, Site.TRACE_SHADOW_ORIGIN), dist

    def _offset(self, p, r, step, origin_site: Site, offset_site: Site | None = None):
        """p + step * r (step: 0.01), and the forms its sites' operators give, as C evaluates
        them: p - 0.01 * r; p * 0.01 * r and p / 0.01 * r, (p * 0.01) * r and (p / 0.01) * r by
        C's precedence (vecmath multiplies two vectors per component); p + 0.01 + r and
        p + 0.01 - r, (p + 0.01) ± r, a float beside a vector the vector of three of it
        (vecmath's implicit constructor)."""
        forms = {Operator.MINUS: lambda: p - step * r,
                 Operator.TIMES: lambda: (p * step) * r,
                 # an opaque divisor: Dr.Jit turns a division by a literal into a product
                 Operator.DIVIDED: lambda: div3(p, self.dr.opaque(self.T.Float, step)
                                                if isinstance(step, float) else step) * r}
        origin = self.site_arithmetic(origin_site, p + step * r,
                                      {op: forms[op] for op in ENTRIES[origin_site].operators})
        if offset_site is None:
            return origin
        return self.site_arithmetic(offset_site, origin, {
            Operator.PLUS: lambda: (p + step) + r, Operator.MINUS: lambda: (p + step) - r})

    def add_light(self, color, term, blocked, mat):
        """The sum of the lights so far plus a light's term, unless the light is blocked
        (blocked: None without a shadow test)."""
        lit = self.site_arithmetic(Site.TRACE_LIGHT_SUM, color + term,
                                   {Operator.MINUS: lambda: color - term})
        return lit if blocked is None else self.dr.select(blocked, color, lit)

    @staticmethod
    def _term_matters(term, active):
        """Lanes whose shadow test can change the color: where a light's term is exactly zero
        (±0 in every channel), color + term equals color whatever the test says, so those
        lanes, and lanes outside `active`, skip the triangle traversal (an exact saving)."""
        matters = (term.x != 0.0) | (term.y != 0.0) | (term.z != 0.0)
        return matters if active is None else matters & active

    def direct(self, p, n, d, mat, geom=None, scale=None, active=None, record=None):
        """Σ over lights in file order of the Phong terms of the lights that are not blocked
        (spec §6). `record` (course mode): a dict that receives each light's parts."""
        T, dr = self.T, self.dr
        material = self._material(mat)
        r = self.mirrored(d, n, SHADE_MIRROR)
        color = dr.zeros(T.Array3f, dr.width(p))
        start = (Site.TRACE_START_R, Site.TRACE_START_G, Site.TRACE_START_B)
        if any(self.site_compiled(s) for s in start):  # else the course's exact zeros
            color = color + T.Array3f(*(self.site_constant(s, 0.0) for s in start))
        loop = (LightLoop(self, T, dr, dr.width(p), len(self.lights))
                if LightLoop.needed(self) else None)
        for i, light in enumerate(self.lights):
            to_light, intensity, dist = self.toward(light, p)
            rl = self.highlight_cosine(d, n, r, to_light)
            below = self.site_compare(Site.SHADE_SPECULAR_CLAMP, rl, self.site_constant(
                Site.SHADE_SPECULAR_THRESHOLD, 0.0))
            rl = dr.select(below, self.site_constant(Site.SHADE_SPECULAR_CLAMP, 0.0), rl)
            term = self._phong(n, to_light, rl, intensity, material, record, i)
            blocked = None
            if self.shadows:
                origin, limit = self.shadow_ray(p, n, to_light, dist)
                origin, toward = self.site_swapped(Site.TRACE_SHADOW_RAY, origin, to_light)
                # recorded shadows are traced in full, zero terms too (the mask is the test's),
                # and so are they where the light loop counts blocked lights (a zero term that
                # is blocked is skipped, not added)
                blocked = self.shadow_test(origin, toward, limit,
                                           self._term_matters(term, active)
                                           if record is None and loop is None else active, i)
            lit = self.add_light(color, term, blocked, mat)
            color = lit if loop is None else dr.select(loop.step(i, blocked), lit, color)
            if record is not None:
                record[f"shadow:{i}"] = (dr.zeros(T.Bool, dr.width(p)) if blocked is None
                                         else blocked)
        return color

    def shadow_test(self, origin, to_light, limit, active, light: int):
        """Whether light `light` is blocked: the course's "intersect && !(t > dist)", any hit
        within the distance (Intersector.occluded). Its comparison is a site: where a mistake
        there is on, the closest hit is compared (traced in those lanes alone: the triangles
        are skipped where it is off)."""
        blocked = self.isect.occluded(origin, to_light, limit, active, self.shadow_grids[light])
        on = self.site_on(Site.TRACE_SHADOW_TEST)
        if on is None:
            return blocked
        lanes = self.dr.full(self.T.Bool, True, self.dr.width(origin)) & on
        hit = self.isect.closest(origin, to_light, need_normal=False,
                                 active=lanes if active is None else lanes & active)
        return self.dr.select(on, hit.found() & ~self.site_compare(Site.TRACE_SHADOW_TEST,
                                                                   hit.t, limit), blocked)

    def error_scale(self, o, t):
        """What the rounding error of p = o + t*d is proportional to, where new rays' offsets
        depend on it (robust mode); None in course mode, whose offsets are fixed."""
        return None

    def leaving(self, p, geom, r, scale):
        """Where a reflected ray along r leaves p: 0.01 along r, as the course offsets it."""
        return self._offset(p, r, self.site_constant(Site.TRACE_MIRROR_STEP, SHADOW_OFFSET),
                            Site.TRACE_MIRROR_ORIGIN, Site.TRACE_MIRROR_OFFSET)

    def finished(self, color):
        """The color a primary ray returns; the course's is as computed."""
        return color

    def ambient(self, mat):
        light, kd = self.ambient_light, self._gather3(self.kd, mat)
        return self.site_sign(Site.TRACE_AMBIENT, self.site_arithmetic(
            Site.TRACE_AMBIENT_PRODUCT, light * kd, {Operator.PLUS: lambda: light + kd,
                                                    Operator.MINUS: lambda: light - kd}))

    def levels_stored(self) -> int:
        """Mirror levels the chain keeps per lane: -bounces'."""
        return self.bounces

    def level_limit(self):
        """The mirror levels a ray follows at most: -bounces (spec §6)."""
        return self.bounces

    def chained(self) -> bool:
        """Whether a ray's color is folded over a chain of mirror levels (_mirror_chain), not
        taken from its one hit (which gives the same color where no level is followed)."""
        return self.bounces > 0

    def mirrors(self, mat):
        """Whether a hit on material mat recurses: |ks| > 0.1 (spec §6)."""
        return self.dr.gather(self.T.UInt32, self.reflective, mat) != 0

    def reflection_weight(self, mat):
        """What the reflected color is multiplied by: ks (spec §6)."""
        return self._gather3(self.ks, mat)

    # --- the recursion --------------------------------------------------------------------
    def radiance(self, o, d, hit: Hit, record: dict | None = None):
        """The color of the primary rays o + t·d with their hits. `record` (course mode): a
        dict that receives the primary hit's parts (auxiliary.py) under their names, per
        light as name:index."""
        if not self.chained():
            p = o + hit.t * d
            amb = self.ambient(hit.material)
            local = self.direct(p, hit.normal, d, hit.material, hit.geom,
                                self.error_scale(o, hit.t), hit.found(), record) + amb
            if record is not None:
                zero = self.dr.zeros(self.T.Array3f, self.dr.width(o))
                record.update(ambient=amb, reflection=zero,
                              mirror_depth=self.dr.zeros(self.T.UInt32, self.dr.width(o)))
            return self.finished(self.dr.select(hit.found(), local, self.bg.lookup(d)))
        return self.finished(self._mirror_chain(o, d, hit, record))

    def _mirror_chain(self, o, d, hit: Hit, record: dict | None = None):
        dr, T = self.dr, self.T
        A3 = T.Array3f
        n_levels = self.level_limit()
        direct_buf = dr.alloc_local(A3, self.levels_stored())
        ks_buf = dr.alloc_local(A3, self.levels_stored())
        amb_buf = dr.alloc_local(A3, self.levels_stored())
        width = dr.width(o)
        depth = dr.zeros(T.UInt32, width)
        end = dr.zeros(A3, width)
        active = dr.full(T.Bool, True, width)
        t, normal, mat = hit.t, hit.normal, hit.material
        geom = hit.geom if hit.geom is not None else normal

        def cond(active, *_):
            return active

        def body(active, depth, end, o, d, t, normal, mat, geom, record=None):
            found = t < FLT_MAX
            p = o + t * d
            scale = self.error_scale(o, t)
            local_direct = self.direct(p, normal, d, mat, geom, scale, found, record)
            amb = self.ambient(mat)
            if record is not None:
                record["ambient"] = amb
            mirror = found & self.mirrors(mat) & (depth < n_levels)
            end = local_direct + amb  # where the chain ends on a miss: background, below
            direct_buf.write(local_direct, depth, mirror)
            ks_buf.write(self.reflection_weight(mat), depth, mirror)
            amb_buf.write(amb, depth, mirror)
            r = self.mirrored(d, normal, TRACE_MIRROR)
            o_next, d_next = self.site_swapped(Site.TRACE_MIRROR_RAY,
                                               self.leaving(p, geom, r, scale), r)
            o = dr.select(mirror, o_next, o)
            d = dr.select(mirror, d_next, d)
            nxt = self.isect.closest(o, d, active=mirror)  # ending lanes trace nothing more
            t = dr.select(mirror, nxt.t, t)
            normal = dr.select(mirror, nxt.normal, normal)
            mat = dr.select(mirror, nxt.material, mat)
            if nxt.geom is not None:
                geom = dr.select(mirror, nxt.geom, geom)
            depth = dr.select(mirror, depth + 1, depth)
            return mirror, depth, end, o, d, t, normal, mat, geom

        state = (active, depth, end, o, d, t, normal, mat, geom)
        if record is not None:  # the primary level unrolled, so that its parts are recorded
            state = body(*state, record=record)
        state = dr.while_loop(state, cond, body)
        depth, end, d, t = state[1], state[2], state[4], state[5]
        # each lane's last ray: its background is looked up once, not on every level
        color = dr.select(t < FLT_MAX, end, self.bg.lookup(d))

        def cond_up(level, *_):
            return level > 0

        def fold(level, color):
            level = level - 1
            ks = ks_buf.read(level)
            reflected = self.site_arithmetic(Site.TRACE_MIRROR_WEIGHT, ks * color, {
                Operator.PLUS: lambda: ks + color, Operator.MINUS: lambda: ks - color})
            direct = direct_buf.read(level)
            total = self.site_arithmetic(Site.TRACE_MIRROR_SUM, direct + reflected, {
                Operator.MINUS: lambda: direct - reflected})
            return level, total + amb_buf.read(level), reflected

        def body_up(level, color):
            return fold(level, color)[:2]

        def body_recorded(level, color, reflection):  # keeps the primary level's reflection
            level, color, reflected = fold(level, color)
            return level, color, dr.select(level == 0, reflected, reflection)

        if record is None:
            _, color = dr.while_loop((depth, color), cond_up, body_up)
        else:
            _, color, reflection = dr.while_loop((depth, color, dr.zeros(A3, width)), cond_up,
                                                 body_recorded)
            record.update(reflection=reflection, mirror_depth=depth)
        return color
