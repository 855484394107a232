"""Closest-hit queries over the flattened scene, traced into the render kernel (spec §5).

Only the primitive kinds the scene has are traced. Spheres and planes are few and are unrolled
with their parameters as literals; triangles are read from arrays in a symbolic loop.
Every test keeps the spec's comparison semantics, including how NaN falls through them.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..kernel.backend import import_drjit
from ..kernel.vecmath import Types, dot, mat3_mul, normalize
from ..mistakes import hooks
from ..operators import Operator, Site, site_codes
from .bvh import build_bvh
from .flat_scene import FlatScene, ObjectTransform, PlacedPlane, PlacedSphere
from .transform_sites import TransformSites
from .triangle_search import NO_TRIANGLE
from .triangles import FLT_MAX, TriangleSet

# The course's sphere test starts from this t and only rejects a sphere when both roots are below
# tmin: where neither root is strictly on its side of tmin (NaN roots of a NaN ray, a root exactly
# at 0) the sphere is hit at t = 10000 (spec §5).
SPHERE_FALLBACK_T = 10000.0

# the generated mistakes (operators.py) at the sites the tests below compute
HOOKS = hooks(__name__, *site_codes(
    Site.SPHERE_OFFSET, Site.SPHERE_B, Site.SPHERE_B_FACTOR, Site.SPHERE_C_TERM,
    Site.SPHERE_RADIUS,
    Site.SPHERE_RADIUS_PRODUCT, Site.SPHERE_DISC, Site.SPHERE_DISC_PRODUCT,
    Site.SPHERE_DISC_FACTOR, Site.SPHERE_DISC_THRESHOLD, Site.SPHERE_NEAR_ROOT, Site.SPHERE_SQRT,
    Site.SPHERE_NEAR_TERM, Site.SPHERE_FAR_TERM, Site.SPHERE_NEAR_DIVISOR, Site.SPHERE_FAR_DIVISOR,
    Site.SPHERE_BEHIND, Site.SPHERE_NORMAL_CENTER, Site.SPHERE_NORMAL, Site.SPHERE_NORMAL_UNIT,
    Site.SPHERE_CLOSER, Site.PLANE_ORIGIN_TERM, Site.PLANE_NUMERATOR, Site.PLANE_BEHIND,
    Site.PLANE_CLOSER))


@dataclass
class Hit:
    t: Any  # FLT_MAX where nothing was hit
    order: Any  # file-order number of the primitive hit (ties in t go to the earlier one)
    normal: Any  # as the course stores it (raw for untransformed planes); zero on a miss
    material: Any
    # robust mode only (robust.py): the unit geometric normal (the offset direction for new
    # rays), and t in float64 where a sphere set it (two spheres closer than float32's t
    # spacing)
    geom: Any = None
    t64: Any = None

    def found(self):
        return self.t < FLT_MAX


def to_world_normal(xf: ObjectTransform, n, unit=normalize):
    """A child's hit normal in world space: unit(N · n) per level, innermost first."""
    for nm in reversed(xf.normal_matrices):
        n = unit(mat3_mul(nm.tolist(), n))
    return n


class Intersector(TransformSites):
    """Closest hits and shadow tests over the whole scene with the course's tests: spheres and
    planes unrolled, and every triangle in one set (`triangles`, a TriangleSet), transformed
    ones entered through their instances. robust.py's subclass has robust mode's tests."""

    # the course's mesh octrees matter for the course's tests in float32 only (where images
    # are compared byte for byte); float64 keeps the brute-force answer
    OCTREES = True
    TRIANGLES: type[TriangleSet] = TriangleSet  # whose triangle test the set has

    def __init__(self, flat: FlatScene, types: Types, accel: str = "bvh") -> None:
        self.T = types
        self.dr = import_drjit()
        self.flat = flat
        octrees = self.OCTREES and types.precision == "single"
        self.triangles = self.TRIANGLES(flat.triangles, types, accel, octrees, build_bvh,
                                        flat.instances)

    def shadow_grid(self, direction):
        """The triangles' shadow grid along `direction` (TriangleSet.shadow_grid), if any."""
        return self.triangles.shadow_grid(direction)

    # ------------------------------------------------------------------------------------
    def closest(self, o, d, need_normal: bool = True, skip_triangles: bool = False,
                active=None, candidates=None) -> Hit:
        """The closest hit along o + t·d. Lanes outside `active` (if given) skip the BVH
        traversal; their result is unspecified. candidates: camera rays' triangle lists
        (TriangleSet.search)."""
        hit = self._no_hit(self.dr.width(o), need_normal)
        # in file order, as the course's Group tests its children: the closest hit does not
        # depend on it (ties go to the earlier object), a closer test a mistake changes does
        unrolled: list[PlacedSphere | PlacedPlane] = [*self.flat.spheres, *self.flat.planes]
        for p in sorted(unrolled, key=lambda p: p.order):
            if isinstance(p, PlacedSphere):
                self._sphere(p, o, d, hit, need_normal)
            else:
                self._plane(p, o, d, hit, need_normal)
        if self.triangles.count and not skip_triangles:
            self._triangles(o, d, hit, need_normal, active, candidates)
        return hit

    def _no_hit(self, width: int, need_normal: bool) -> Hit:
        T, dr = self.T, self.dr
        return Hit(t=dr.full(T.Float, FLT_MAX, width), order=dr.full(T.UInt32, 0xFFFFFFFF, width),
                   normal=dr.zeros(T.Array3f, width), material=dr.zeros(T.UInt32, width))

    def _triangles(self, o, d, hit: Hit, need_normal: bool, active, candidates=None) -> None:
        T, dr = self.T, self.dr
        state = self.triangles.search(o, d, hit.t, hit.order, active, candidates)
        found = state.tri != NO_TRIANGLE
        if hit.t64 is not None:
            hit.t64 = dr.select(found, T.Float64(state.t), hit.t64)
        hit.t, hit.order = state.t, state.order
        mat, normal, geom = self.triangles.hit_data(state, found, need_normal)
        hit.material = dr.select(found, mat, hit.material)
        if normal is not None:
            hit.normal = dr.select(found, normal, hit.normal)
        if hit.geom is not None and geom is not None:
            hit.geom = dr.select(found, geom, hit.geom)

    def _closer(self, t, order: int, hit: Hit):
        return (t < hit.t) | ((t == hit.t) & (hit.order > order))

    def _replaces(self, site: Site, t, order: int, hit: Hit):
        """Whether a sphere's or plane's hit at t replaces the hit so far: the course's closer
        test, or the site's mistaken one, against the spheres and planes before it in file
        order (the triangles, searched after them, still compare with the hit they leave)."""
        if not self.site_compiled(site):
            return self._closer(t, order, hit)
        # the course's t < h.t: in file order a tie cannot favour the later object
        return self.site_deleted(site, self.site_compare(site, t, hit.t),
                                 lambda: self.T.Bool(True))

    def _take(self, mask, t, order, normal, material, hit: Hit, geom=None, t64=None) -> None:
        dr = self.dr
        if hit.geom is not None and geom is not None:
            hit.geom = dr.select(mask, geom, hit.geom)
        if hit.t64 is not None:
            hit.t64 = dr.select(mask, self.T.Float64(t) if t64 is None else t64, hit.t64)
        hit.t = dr.select(mask, t, hit.t)
        hit.order = dr.select(mask, self.T.UInt32(order), hit.order)
        if normal is not None:
            hit.normal = dr.select(mask, normal, hit.normal)
        hit.material = dr.select(mask, self.T.UInt32(material), hit.material)

    def _sphere(self, ps, o, d, hit: Hit, need_normal: bool) -> None:
        if ps.xform is not None:
            o, d = self._object_ray(ps.xform, o, d)
        self._sphere_test(ps, o, d, hit, need_normal)

    def _object_ray(self, xf: ObjectTransform, o, d):
        """The ray in a transformed sphere's or plane's space: through each level's M^-1,
        outermost first (spec §5)."""
        for inverse in xf.inverses:
            o, d = self.object_ray(inverse.tolist(), o, d)
        return o, d

    def _world_normal(self, xf: ObjectTransform, n, unit=normalize):
        """A transformed sphere's or plane's hit normal in world space: unit(N · n) per level,
        innermost first, N the course's ((M3)^-1)^T (to_world_normal)."""
        for inverse, normal in reversed(list(zip(xf.inverses, xf.normal_matrices))):
            n = unit(self.through_level([mat3_mul(m.tolist(), n) for m in
                                         self.normal_options(inverse, normal)]))
        return n

    def _sphere_root(self, t_minus, t_plus):
        """The t of a sphere hit from its two roots: the nearer one in front of the ray, else
        the farther where the ray starts inside, else SPHERE_FALLBACK_T (spec §5)."""
        dr = self.dr
        near = self.site_deleted(Site.SPHERE_NEAR_ROOT,
                                 self.site_compare(Site.SPHERE_NEAR_ROOT, t_minus, 0.0),
                                 lambda: self.T.Bool(True))
        return dr.select(near, t_minus,
                         dr.select((t_plus > 0.0) & (t_minus < 0.0), t_plus, SPHERE_FALLBACK_T))

    def _sphere_test(self, ps, o, d, hit: Hit, need_normal: bool) -> None:
        """The course's sphere test (spec §5) of the ray in the sphere's space."""
        dr, A3 = self.dr, self.T.Array3f
        s = ps.sphere
        c = A3(*s.center)
        oc = self.site_arithmetic(Site.SPHERE_OFFSET, o - c, {Operator.PLUS: lambda: o + c})
        a = dot(d, d)
        b = self.site_sign(Site.SPHERE_B,
                           self.site_constant(Site.SPHERE_B_FACTOR, 2.0) * dot(d, oc))
        radius = np.float32(s.radius)
        squared = dot(oc, oc)
        r2 = self.site_unsquared(Site.SPHERE_RADIUS, float(radius * radius),
                                 lambda: dr.opaque(self.T.Float, float(radius)))
        cc = self.site_arithmetic(Site.SPHERE_C_TERM, squared - r2, {
            Operator.PLUS: lambda: squared + r2, Operator.TIMES: lambda: squared * r2,
            Operator.DIVIDED: lambda: squared / r2})
        # opaque where a mistake may use it: else a literal the kernel would fold
        r = dr.opaque(self.T.Float, float(radius)) \
            if self.site_compiled(Site.SPHERE_RADIUS_PRODUCT) else float(radius)
        cc = self.site_arithmetic(Site.SPHERE_RADIUS_PRODUCT, cc, {
            Operator.PLUS: lambda: (squared - r) + r, Operator.MINUS: lambda: (squared - r) - r,
            Operator.DIVIDED: lambda: squared - r / r})
        factor = self.site_constant(Site.SPHERE_DISC_FACTOR, 4.0)
        four_a = self.site_arithmetic(Site.SPHERE_DISC_PRODUCT, factor * a, {
            Operator.PLUS: lambda: factor + a, Operator.MINUS: lambda: factor - a,
            Operator.DIVIDED: lambda: factor / a})
        disc = self.site_arithmetic(Site.SPHERE_DISC, b * b - four_a * cc, {
            Operator.PLUS: lambda: b * b + four_a * cc,
            Operator.TIMES: lambda: b * b * four_a * cc,  # C++: ((b * b) * (4a)) * c
            Operator.DIVIDED: lambda: b * b / four_a * cc})
        root = self.site_deleted(Site.SPHERE_SQRT, dr.sqrt(disc), lambda: disc)
        t_minus = self.site_arithmetic(Site.SPHERE_NEAR_TERM, -b - root, {
            Operator.TIMES: lambda: -b * root, Operator.DIVIDED: lambda: -b / root}) / (
            self.site_constant(Site.SPHERE_NEAR_DIVISOR, 2.0) * a)
        t_plus = self.site_arithmetic(Site.SPHERE_FAR_TERM, -b + root, {
            Operator.TIMES: lambda: -b * root, Operator.DIVIDED: lambda: -b / root}) / (
            self.site_constant(Site.SPHERE_FAR_DIVISOR, 2.0) * a)
        t = self._sphere_root(t_minus, t_plus)
        missed = self.site_compare(Site.SPHERE_DISC_THRESHOLD, disc,
                                   self.site_constant(Site.SPHERE_DISC_THRESHOLD, 0.0))
        behind = self.site_deleted(Site.SPHERE_BEHIND, (t_minus < 0.0) & (t_plus < 0.0),
                                   lambda: self.T.Bool(False))
        ok = ~missed & ~behind & self._replaces(Site.SPHERE_CLOSER, t, ps.order, hit)
        normal = None
        if need_normal:
            p = o + t * d
            v = self.site_sign(Site.SPHERE_NORMAL, self.site_arithmetic(
                Site.SPHERE_NORMAL_CENTER, p - c, {Operator.PLUS: lambda: p + c,
                                                   Operator.TIMES: lambda: p * c}))
            normal = self.site_deleted(Site.SPHERE_NORMAL_UNIT, normalize(v), lambda: v)
            if ps.xform is not None:
                normal = self._world_normal(ps.xform, normal)
        self._take(ok, t, ps.order, normal, s.material, hit)

    def _plane(self, pp, o, d, hit: Hit, need_normal: bool) -> None:
        A3 = self.T.Array3f
        p = pp.plane
        if pp.xform is not None:
            o, d = self._object_ray(pp.xform, o, d)
        normal_in, offset = self._plane_equation(p)
        n = A3(*normal_in)
        on = self.site_sign(Site.PLANE_ORIGIN_TERM, dot(o, n))
        t = self.site_arithmetic(Site.PLANE_NUMERATOR, offset - on, {
            Operator.TIMES: lambda: offset * on, Operator.DIVIDED: lambda: offset / on}) / dot(d, n)
        ok = ~self.site_compare(Site.PLANE_BEHIND, t, 0.0) & \
            self._replaces(Site.PLANE_CLOSER, t, pp.order, hit)
        normal = geom = None
        if need_normal:
            normal, geom = self._plane_normals(pp, n)
        self._take(ok, t, pp.order, normal, p.material, hit, geom)

    def _plane_normals(self, pp, n):
        """(shading normal, geometric normal or None) of a plane with normal n: the course
        keeps the scene's raw normal where the plane is not transformed (spec §5)."""
        return (n if pp.xform is None else self._world_normal(pp.xform, n)), None

    def _plane_equation(self, plane) -> tuple[tuple[float, ...], float]:
        """(n, offset) of the plane n·p = offset the test intersects: the scene's, n raw
        (spec §5)."""
        return plane.normal, plane.offset

    def occluded(self, o, d, dist, active=None, grid=None):
        """Whether the course's shadow test finds a blocker: the closest hit has t <= dist,
        i.e. some primitive is hit at a t <= dist (and below FLT_MAX). Triangles stop at the
        first such hit; lanes outside `active` (if given) skip the triangles (their result is
        then unspecified). grid: the triangles' shadow grid for d (TriangleSet.shadow_grid)."""
        dr = self.dr
        dist = self._shadow_distance(dist)
        hit = self.closest(o, d, need_normal=False, skip_triangles=True)
        blocked = hit.found() & (hit.t <= dist)
        if self.triangles.count:
            blocked |= self.triangles.any_hit(o, d, dr.select(blocked, -1.0, dist), active,
                                              grid)
        return blocked

    def _shadow_distance(self, dist):
        """The distance blockers count up to: the course tests "not t > dist", so with a NaN
        distance (a NaN hit point) any hit blocks the light."""
        return self.dr.select(self.dr.isnan(dist), FLT_MAX, dist)
