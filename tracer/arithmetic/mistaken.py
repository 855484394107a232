"""Course arithmetic with mistakes (tracer/mistakes.py): subclasses of the course's parts that
replace one hook per mistake and otherwise compute as the course does, so that an image
rendered with a mistake differs from the course's only by what that mistake changes.

Mistakes are kernel inputs, not kernels. A render compiles in a set of mistakes (its options'
`mistake_kernel`: by default the ones it switches on); each compiled-in mistake is computed
beside the course's value and chosen by an opaque on/off switch, with its parameter an opaque
value too. So every render with the same compiled-in set, whichever of them are on and with
whatever parameters, runs the same kernel code, which Dr.Jit compiles once: a cause search
compiles the whole catalogue in and tries every mistake, parameter and pair with one kernel
per scene and request. Where a switch is off, the select gives the course's value exactly.
"""
from __future__ import annotations

import functools
import operator
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..accel.flat_scene import NO_INSTANCE, ObjectTransform
from ..accel.intersect import FLT_MAX, Intersector
from ..accel.memo import kept
from ..accel.transform_sites import OBJECT_RAY
from ..accel.triangles import RESHAPING, TriangleSet
from ..kernel.backend import import_drjit
from ..kernel.vecmath import div3, dot, gather_packet, normalize
from ..mistakes import Code, Switch, hooks
from ..operators import (
    COMPARE,
    COMPARISONS,
    GENERATED_CODES,
    CourseSites,
    Operator,
    Site,
    op_code,
    site_codes,
)
from ..scene.model import REFLECTIVE_KS
from ..shade.shading import Shader

# the mistakes whose hooks are the course parts' subclasses below
HOOKS = hooks(
    __name__,
    Code.AMBIENT_PER_LIGHT,
    Code.AMBIENT_PER_LIT_LIGHT,
    Code.DIFFUSE_UNCLAMPED,
    Code.FALLOFF_IGNORED,
    Code.FALLOFF_POWER,
    Code.LIGHT_REVERSED,
    Code.LIGHT_UNNORMALISED,
    Code.PLANE_NORMALISED,
    Code.PLANE_OFFSET_NEGATED,
    Code.PLANE_SHADING_NORMAL_NORMALISED,
    Code.REFLECTION_DEPTH,
    Code.REFLECTION_GATE,
    Code.REFLECTION_OFFSET,
    Code.REFLECTION_OFFSET_NORMAL,
    Code.REFLECTION_PER_LIGHT,
    Code.REFLECTION_PER_LIT_LIGHT,
    Code.REFLECTION_UNWEIGHTED,
    Code.REFLECTION_WEIGHT_SQUARED,
    Code.LIGHTS_SKIPPED,
    Code.SHADOW_ALWAYS,
    Code.SHADOW_BEYOND_LIGHT,
    Code.SHADOW_DISTANCE_SQUARED,
    Code.SHADOW_INVERTED,
    Code.SHADOW_MISSING,
    Code.SHADOW_OFFSET,
    Code.SHADOW_OFFSET_NORMAL,
    Code.SHININESS_SCALE,
    Code.SPECULAR_GATED,
    Code.SPECULAR_HALF_VECTOR,
    Code.SPECULAR_REVERSED,
    Code.SPHERE_FAR_ROOT,
    Code.SPHERE_INSIDE_MISSED,
    Code.TRANSFORM_DIRECTION_NORMALISED,
    Code.TRANSFORM_NORMAL_OBJECT,
    Code.TRANSFORM_NORMAL_UNNORMALISED,
    Code.TRIANGLE_FLAT_NORMALS,
    Code.TRIANGLE_NORMAL_ONE_VERTEX,
    Code.TRIANGLE_NORMAL_UNNORMALISED,
    Code.TRIANGLE_NORMAL_WEIGHTS,
)

# the most mirror levels reflection_depth may add to -bounces (its parameter's range)
MAX_EXTRA_LEVELS = 4
KEPT_BVHS = 4  # a process's BVHs kept for renders with mistakes (MistakenTriangles._upload)
# the triangle sites that reshape a triangle, and the Transform sites that hand its test another
# ray (a BVH of more than one instance bounds world-space triangles)
RESHAPING_CODES = frozenset(site_codes(*RESHAPING, *OBJECT_RAY))
TRIANGLE_RESHAPING_CODES = frozenset(site_codes(*RESHAPING))


@dataclass(frozen=True)
class Switches:
    """The mistakes of a render as its parts read them: which are compiled in, and per
    compiled-in mistake whether it is on and its parameter, as opaque kernel values."""

    compiled: frozenset[str]
    on: tuple[Switch, ...]

    def __contains__(self, code: str) -> bool:
        """Whether the mistake is compiled in (its hook computes it)."""
        return _checked(code) in self.compiled

    def enabled(self, code: str, types):
        value = any(s.code == _checked(code) for s in self.on)
        return import_drjit().opaque(types.Bool, value)

    def value(self, code: str, types):
        found = next((s.value for s in self.on if s.code == _checked(code)), None)
        return import_drjit().opaque(types.Float, float(found or 0.0))

    def pick(self, code: str, types, mistaken, course):
        """The mistaken value where the mistake is on, else the course's."""
        if _checked(code) not in self.compiled:
            return course
        return import_drjit().select(self.enabled(code, types), mistaken(), course)

    def constant(self, code: str, types, course: float):
        """A constant of the course's formula: the mistake's parameter where it is on, else
        the course's value (a literal where the mistake is not compiled in)."""
        return self.pick(code, types, lambda: self.value(code, types), course)


def _checked(code: str) -> str:
    """A hook's code, which must be a Code member or a generated mistake's (operators.op_code):
    a string would be compared as text and a misspelt one would silently give the course's
    value."""
    if not isinstance(code, Code) and code not in GENERATED_CODES:
        raise TypeError(f"a mistake's hook names {code!r}, not a Code member")
    return code


@functools.lru_cache(maxsize=None)
def _remembered(build):
    """`build` (a BVH builder), its results for the last few point sets it was given kept."""
    return kept(KEPT_BVHS)(build)


def _identity(v):
    return v


class MistakenSites(CourseSites):
    """The generated mistakes (operators.py) at the sites the course's parts compute through
    CourseSites: each site's value picked by its operators' switches."""

    SWITCHES: Switches
    T: Any

    def site_constant(self, site: Site, course: float):
        return self.SWITCHES.constant(op_code(site, Operator.CONSTANT), self.T, course)

    def site_sign(self, site: Site, value):
        return self.SWITCHES.pick(op_code(site, Operator.SIGN), self.T, lambda: -value, value)

    def site_unsquared(self, site: Site, squared, plain):
        return self.SWITCHES.pick(op_code(site, Operator.UNSQUARED), self.T, plain, squared)

    def site_arithmetic(self, site: Site, course, forms):
        for op, form in forms.items():
            course = self.SWITCHES.pick(op_code(site, op), self.T, form, course)
        return course

    def site_weight(self, site: Site, terms):
        return self._chosen(op_code(site, Operator.WEIGHT), super().site_weight(site, terms),
                            lambda: [self.T.Float(t) if isinstance(t, float) else t
                                     for t in terms])

    def site_index(self, site: Site, terms):
        return self._chosen(op_code(site, Operator.INDEX), super().site_index(site, terms),
                            lambda: list(terms))

    def site_deleted(self, site: Site, course, without):
        return self.SWITCHES.pick(op_code(site, Operator.DELETED), self.T, without, course)

    def site_compiled(self, site: Site) -> bool:
        return any(code in self.SWITCHES for code in site_codes(site))

    def site_on(self, site: Site):
        on = [self.SWITCHES.enabled(code, self.T) for code in site_codes(site)
              if code in self.SWITCHES]
        return functools.reduce(operator.or_, on) if on else None

    def site_added(self, site: Site, course, term):
        code = op_code(site, Operator.CONSTANT)
        return self.SWITCHES.pick(code, self.T,
                                  lambda: course + self.SWITCHES.value(code, self.T) * term, course)

    def site_swapped(self, site: Site, a, b):
        code = op_code(site, Operator.SWAPPED)
        return (self.SWITCHES.pick(code, self.T, lambda: b, a),
                self.SWITCHES.pick(code, self.T, lambda: a, b))

    def site_compare(self, site: Site, a, b):
        return self._chosen(op_code(site, Operator.COMPARISON),
                            super().site_compare(site, a, b),
                            lambda: [COMPARE[c](a, b) for c in COMPARISONS])

    def _chosen(self, code: str, course, options):
        """The option the mistake's parameter numbers where it is on, else the course's."""
        on, T = self.SWITCHES, self.T
        if code not in on:
            return course
        dr, k, values = import_drjit(), on.value(code, T), options()
        chosen = values[-1]
        for i in reversed(range(len(values) - 1)):
            chosen = dr.select(k == float(i), values[i], chosen)
        return on.pick(code, T, lambda: chosen, course)


class MistakenTriangles(MistakenSites, TriangleSet):
    SWITCHES: Switches
    all_octree = False

    def _upload(self, tris, accel: str, build) -> None:
        # a cause search renders one scene a few hundred times, each render with a renderer
        # (and these classes) of its own: the same triangles get the same BVH
        if any(s.code in RESHAPING_CODES for s in self.SWITCHES.on):
            accel = "brute"
        super()._upload(tris, accel, _remembered(build))

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        on, T = self.SWITCHES, self.T
        # a test that accepts a hit outside its triangle (or behind the ray) finds it only in
        # the octree leaves the ray visits that hold the triangle, as the course's traversal
        # visits them (not in every triangle, as the brute-force search would): each mesh ray
        # goes through its octree
        self.all_octree = self.octrees and any(s.code in TRIANGLE_RESHAPING_CODES
                                               for s in on.on)
        if Code.TRANSFORM_NORMAL_UNNORMALISED in on:
            self.world_unit = lambda v: on.pick(Code.TRANSFORM_NORMAL_UNNORMALISED, T,
                                                lambda: v, normalize(v))
        if Code.TRIANGLE_NORMAL_UNNORMALISED in on:
            self.unit = lambda v: on.pick(Code.TRIANGLE_NORMAL_UNNORMALISED, T, lambda: v,
                                          normalize(v))

    def _is_degenerate(self, d):
        if self.all_octree:
            return self.dr.full(self.T.Bool, True, self.dr.width(d))
        return TriangleSet._is_degenerate(d)

    def _skip_mesh(self, deg, bits):
        if self.all_octree and deg is not None:
            return True  # the brute-force search leaves every mesh triangle to the octree
        return super()._skip_mesh(deg, bits)

    def shading_normal(self, idx, found, bu, bv, normals):
        on, T, (n0, n1, n2) = self.SWITCHES, self.T, normals
        n = super().shading_normal(idx, found, bu, bv, normals)
        n = on.pick(Code.TRIANGLE_NORMAL_ONE_VERTEX, T, lambda: self.unit(n0), n)
        n = on.pick(Code.TRIANGLE_NORMAL_WEIGHTS, T,
                    lambda: self.unit((bu * n0 + bv * n1) + (1.0 - bu - bv) * n2), n)

        def face():
            record = gather_packet(T, self.trecord, 8, idx * 2)
            return T.Array3f(record[4], record[5], record[6])  # the unit face normal

        return on.pick(Code.TRIANGLE_FLAT_NORMALS, T, face, n)

    def into_instance(self, inst, o, d):
        o, d = super().into_instance(inst, o, d)
        return o, self.SWITCHES.pick(Code.TRANSFORM_DIRECTION_NORMALISED, self.T,
                                     lambda: self.dr.select(inst != NO_INSTANCE, normalize(d),
                                                            d), d)

    def _in_one_instance(self, o, d):
        o, d = super()._in_one_instance(o, d)
        if not self.one_inverses:
            return o, d
        return o, self.SWITCHES.pick(Code.TRANSFORM_DIRECTION_NORMALISED, self.T,
                                     lambda: normalize(d), d)

    def _to_world_normal(self, inst, n):
        return self.SWITCHES.pick(Code.TRANSFORM_NORMAL_OBJECT, self.T, lambda: n,
                                  super()._to_world_normal(inst, n))


class MistakenIntersector(MistakenSites, Intersector):
    SWITCHES: Switches

    def _object_ray(self, xf: ObjectTransform, o, d):
        o, d = super()._object_ray(xf, o, d)
        return o, self.SWITCHES.pick(Code.TRANSFORM_DIRECTION_NORMALISED, self.T,
                                     lambda: normalize(d), d)

    def _world_normal(self, xf: ObjectTransform, n, unit=normalize):
        on, T = self.SWITCHES, self.T
        world = super()._world_normal(xf, n, unit)
        world = on.pick(Code.TRANSFORM_NORMAL_UNNORMALISED, T,
                        lambda: Intersector._world_normal(self, xf, n, _identity), world)
        return on.pick(Code.TRANSFORM_NORMAL_OBJECT, T, lambda: n, world)

    def _sphere_root(self, t_minus, t_plus):
        dr, on, T = self.dr, self.SWITCHES, self.T
        t_minus = on.pick(Code.SPHERE_FAR_ROOT, T,
                          lambda: dr.select((t_minus > 0.0) & (t_plus > 0.0), t_plus, t_minus),
                          t_minus)
        t = super()._sphere_root(t_minus, t_plus)
        # the nearer root only: from inside the sphere (behind the ray) a miss
        return on.pick(Code.SPHERE_INSIDE_MISSED, T, lambda: dr.select(t_minus > 0.0, t_minus,
                                                                    -1.0), t)

    def _plane_equation(self, plane):
        on, T, dr = self.SWITCHES, self.T, self.dr
        n, offset = super()._plane_equation(plane)
        offset = on.pick(Code.PLANE_OFFSET_NEGATED, T, lambda: dr.opaque(T.Float, -offset),
                         offset)
        unit = tuple(float(c) for c in _unit32(n))
        n = tuple(on.pick(Code.PLANE_NORMALISED, T, lambda c=c: dr.opaque(T.Float, c),
                          raw) for c, raw in zip(unit, n))
        return n, offset

    def _plane_normals(self, pp, n):
        normal, geom = super()._plane_normals(pp, n)
        return self.SWITCHES.pick(Code.PLANE_SHADING_NORMAL_NORMALISED, self.T,
                                  lambda: normalize(normal), normal), geom


def _unit32(v) -> np.ndarray:
    """v normalised in float32, as a C++ constructor normalising a Vector3f would."""
    a = np.asarray(v, np.float32)
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / np.sqrt(np.float32((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2]))


# mistakes that need to know, per lane, how many lights were not blocked
COUNTS_LIT = (Code.AMBIENT_PER_LIT_LIGHT, Code.REFLECTION_PER_LIT_LIGHT)
AMBIENT_IN_LOOP = (Code.AMBIENT_PER_LIGHT, Code.AMBIENT_PER_LIT_LIGHT)


class MistakenShader(MistakenSites, Shader):
    SWITCHES: Switches

    def __init__(self, scene, intersector, background, types, shadows, bounces) -> None:
        self._requested = bounces
        super().__init__(scene, intersector, background, types, shadows, bounces)
        self._lit = None  # lights not blocked, per lane, in the direct() being traced

    def _reflective(self, materials) -> np.ndarray:
        if Code.REFLECTION_GATE in self.SWITCHES:  # decided in the kernel: any ks may recurse
            ks = np.array([m.specular for m in materials], np.float32).reshape(-1, 3)
            return (ks != 0).any(axis=1)
        return super()._reflective(materials)

    def _on(self, code: Code):
        return self.SWITCHES.enabled(code, self.T)

    # --- lights
    def toward(self, light, p):
        on, T = self.SWITCHES, self.T
        to_light, intensity, dist = super().toward(light, p)
        if not light.directional:
            intensity = on.pick(Code.FALLOFF_POWER, T, lambda: div3(
                light.color, light.falloff * self.powf(dist, on.value(Code.FALLOFF_POWER, T))),
                intensity)
            intensity = on.pick(Code.FALLOFF_IGNORED, T, lambda: light.color, intensity)
            to_light = on.pick(Code.LIGHT_UNNORMALISED, T, lambda: light.position - p, to_light)
        return on.pick(Code.LIGHT_REVERSED, T, lambda: -to_light, to_light), intensity, dist

    # --- shading
    def highlight_cosine(self, d, n, r, to_light):
        on, T = self.SWITCHES, self.T
        rl = super().highlight_cosine(d, n, r, to_light)
        rl = on.pick(Code.SPECULAR_HALF_VECTOR, T, lambda: dot(n, normalize(to_light - d)), rl)
        return on.pick(Code.SPECULAR_REVERSED, T, lambda: -dot(r, to_light), rl)

    def diffuse_cosine(self, nl):
        return self.SWITCHES.pick(Code.DIFFUSE_UNCLAMPED, self.T, lambda: nl,
                                  super().diffuse_cosine(nl))

    def specular_material(self, ks, shininess, nl):
        on, T = self.SWITCHES, self.T
        ks = on.pick(Code.SPECULAR_GATED, T, lambda: self.dr.select(nl > 0.0, ks, 0.0), ks)
        shininess = on.pick(Code.SHININESS_SCALE, T,
                            lambda: shininess * on.value(Code.SHININESS_SCALE, T), shininess)
        return ks, shininess

    def ambient(self, mat):
        course = super().ambient(mat)
        for code in AMBIENT_IN_LOOP:  # added per light instead (add_light)
            course = self.SWITCHES.pick(code, self.T,
                                        lambda: self.dr.zeros(self.T.Array3f,
                                                              self.dr.width(mat)), course)
        return course

    def direct(self, p, n, d, mat, geom=None, scale=None, active=None, record=None):
        self._lit = self.dr.zeros(self.T.Float, self.dr.width(p))
        return super().direct(p, n, d, mat, geom, scale, active, record)

    def add_light(self, color, term, blocked, mat):
        on, dr, T = self.SWITCHES, self.dr, self.T
        term = on.pick(Code.LIGHTS_SKIPPED, T,
                       lambda: dr.zeros(T.Array3f, dr.width(term)), term)
        if blocked is not None:
            blocked = on.pick(Code.SHADOW_MISSING, T, lambda: dr.zeros(T.Bool, dr.width(term)),
                              blocked)
            blocked = on.pick(Code.SHADOW_INVERTED, T, lambda: ~blocked, blocked)
            blocked = on.pick(Code.SHADOW_ALWAYS, T, lambda: dr.full(T.Bool, True,
                                                                   dr.width(term)), blocked)
        unblocked = 1.0 if blocked is None else dr.select(blocked, 0.0, 1.0)
        self._lit = self._lit + unblocked
        ambient = super().ambient(mat)
        term = on.pick(Code.AMBIENT_PER_LIT_LIGHT, T, lambda: term + ambient, term)
        color = super().add_light(color, term, blocked, mat)
        return on.pick(Code.AMBIENT_PER_LIGHT, T, lambda: color + ambient, color)

    def _term_matters(self, term, active):
        if any(code in self.SWITCHES for code in COUNTS_LIT):
            return active  # a zero term's shadow test matters: it decides the count
        return super()._term_matters(term, active)

    # --- shadows
    def shadow_ray(self, p, n, to_light, dist):
        on, T = self.SWITCHES, self.T
        origin, limit = super().shadow_ray(p, n, to_light, dist)
        origin = on.pick(Code.SHADOW_OFFSET, T,
                         lambda: p + on.value(Code.SHADOW_OFFSET, T) * to_light, origin)
        origin = on.pick(Code.SHADOW_OFFSET_NORMAL, T,
                         lambda: p + on.value(Code.SHADOW_OFFSET_NORMAL, T) * n, origin)
        limit = on.pick(Code.SHADOW_BEYOND_LIGHT, T,
                        lambda: self.dr.full(T.Float, FLT_MAX, self.dr.width(p)), limit)
        return origin, on.pick(Code.SHADOW_DISTANCE_SQUARED, T, lambda: limit * limit, limit)

    # --- reflection
    def leaving(self, p, geom, r, scale):
        on, T = self.SWITCHES, self.T
        origin = super().leaving(p, geom, r, scale)
        origin = on.pick(Code.REFLECTION_OFFSET, T,
                         lambda: p + on.value(Code.REFLECTION_OFFSET, T) * r, origin)
        return on.pick(Code.REFLECTION_OFFSET_NORMAL, T,  # geom: the hit normal
                       lambda: p + on.value(Code.REFLECTION_OFFSET_NORMAL, T) * geom, origin)

    def levels_stored(self) -> int:
        if Code.REFLECTION_DEPTH in self.SWITCHES:
            return self._requested + MAX_EXTRA_LEVELS
        return super().levels_stored()

    def chained(self) -> bool:
        # an extra bounce reflects without -bounces too
        return super().chained() or (Code.REFLECTION_DEPTH in self.SWITCHES
                                     and self.any_reflective)

    def level_limit(self):
        on, T, dr = self.SWITCHES, self.T, self.dr
        if Code.REFLECTION_DEPTH not in on:
            return super().level_limit()
        extra = dr.select(self._on(Code.REFLECTION_DEPTH), T.Int32(on.value(Code.REFLECTION_DEPTH,
                                                                        T)), 0)
        return T.UInt32(dr.maximum(T.Int32(self.bounces) + extra, 0))

    def mirrors(self, mat):
        on, dr, T = self.SWITCHES, self.dr, self.T
        if Code.REFLECTION_GATE not in on:
            return super().mirrors(mat)
        # any ks may recurse (_reflective): the gate is decided here, the course's too
        ks = self._gather3(self.ks, mat)
        length = dr.sqrt((ks.x * ks.x + ks.y * ks.y) + ks.z * ks.z)
        return on.pick(Code.REFLECTION_GATE, T, lambda: length > on.value(Code.REFLECTION_GATE, T),
                       length > float(np.float32(REFLECTIVE_KS)))

    def reflection_weight(self, mat):
        on, T = self.SWITCHES, self.T
        ks = super().reflection_weight(mat)
        ks = on.pick(Code.REFLECTION_UNWEIGHTED, T,
                     lambda: self.dr.full(T.Array3f, 1.0, self.dr.width(mat)), ks)
        ks = on.pick(Code.REFLECTION_WEIGHT_SQUARED, T, lambda: ks * ks, ks)
        ks = on.pick(Code.REFLECTION_PER_LIGHT, T, lambda: ks * float(len(self.lights)), ks)
        return on.pick(Code.REFLECTION_PER_LIT_LIGHT, T, lambda: ks * self._lit, ks)


def switches_of(opts) -> Switches:
    """The Switches of a render's options (RenderOptions: mistakes on, mistake_kernel)."""
    return Switches(frozenset(opts.mistake_kernel) | {s.code for s in opts.mistakes},
                    opts.mistakes)


@dataclass(frozen=True)
class MistakenParts:
    intersector: type[Intersector]
    shader: type[Shader]


@functools.cache
def mistaken_parts(switches: Switches) -> MistakenParts:
    """The course's intersector and shader with these mistakes (one pair of classes per
    Switches, so that a renderer's intersector is reused only by renders with the same)."""
    name = "+".join(sorted(switches.compiled))
    triangles = type(f"Triangles[{name}]", (MistakenTriangles,), {"SWITCHES": switches})
    intersector = type(f"Intersector[{name}]", (MistakenIntersector,),
                       {"SWITCHES": switches, "TRIANGLES": triangles})
    shader = type(f"Shader[{name}]", (MistakenShader,), {"SWITCHES": switches})
    return MistakenParts(intersector, shader)
