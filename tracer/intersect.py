"""Closest-hit queries over the flattened scene, traced into the render kernel (spec §5).

Only the primitive kinds the scene has are traced. Spheres and planes are few and are unrolled
with their parameters as literals; triangles are read from arrays in a symbolic loop.
Every test keeps the spec's comparison semantics, including how NaN falls through them.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .bvh import build_bvh
from .geometry import FlatScene, ObjectTransform
from .triangles import FLT_MAX, NO_TRIANGLE, TriangleSet
from .vecmath import Types, dot, inverse_ray, mat3_mul, normalize, normalize_safe

# The course's sphere test starts from this t and only rejects a sphere when both roots are below
# tmin: where neither root is strictly on its side of tmin (NaN roots of a NaN ray, a root exactly
# at 0) the sphere is hit at t = 10000 (spec §5).
SPHERE_FALLBACK_T = 10000.0


@dataclass
class Hit:
    t: Any  # FLT_MAX where nothing was hit
    order: Any  # file-order number of the primitive hit (ties in t go to the earlier one)
    normal: Any  # as the course stores it (raw for untransformed planes); zero on a miss
    material: Any
    # robust mode only: the unit geometric normal (the offset direction for new rays), and t
    # in float64 where a sphere set it (two spheres closer than float32's t spacing)
    geom: Any = None
    t64: Any = None

    def found(self):
        return self.t < FLT_MAX


def _to_object_space(xf: ObjectTransform, o, d):
    """The ray in the primitive's space: through each level's M^-1, outermost first (spec §5)."""
    for inverse in xf.inverses:
        o, d = inverse_ray(inverse.tolist(), o, d)
    return o, d


def _to_world_normal(xf: ObjectTransform, n, unit=normalize):
    """A child's hit normal in world space: unit(N · n) per level, innermost first."""
    for nm in reversed(xf.normal_matrices):
        n = unit(mat3_mul(nm.tolist(), n))
    return n


class Intersector(TriangleSet):
    """Closest hits and shadow tests over the whole scene: spheres and planes unrolled, and
    every triangle in one set (its arrays are the Intersector's own attributes), transformed
    ones entered through their instances in course mode."""

    def __init__(self, flat: FlatScene, types: Types, accel: str = "bvh",
                 robust: bool = False) -> None:
        # the course's mesh octrees matter in course mode only (float32, where the images are
        # compared byte for byte); robust mode and float64 keep the brute-force answer
        octrees = not robust and types.precision == "single"
        super().__init__(flat.triangles, types, accel, robust, octrees, build_bvh,
                         flat.instances)
        self.flat = flat

    # ------------------------------------------------------------------------------------
    def closest(self, o, d, need_normal: bool = True, skip_triangles: bool = False,
                active=None, candidates=None) -> Hit:
        """The closest hit along o + t·d. Lanes outside `active` (if given) skip the BVH
        traversal; their result is unspecified. candidates: camera rays' triangle lists
        (TriangleSet.search)."""
        T, dr = self.T, self.dr
        hit = Hit(
            t=dr.full(T.Float, FLT_MAX, dr.width(o)),
            order=dr.full(T.UInt32, 0xFFFFFFFF, dr.width(o)),
            normal=dr.zeros(T.Array3f, dr.width(o)),
            material=dr.zeros(T.UInt32, dr.width(o)),
        )
        if self.robust and need_normal:
            hit.geom = dr.zeros(T.Array3f, dr.width(o))
        if self.robust and self.flat.spheres:
            hit.t64 = dr.full(T.Float64, FLT_MAX, dr.width(o))
        for ps in self.flat.spheres:
            self._sphere(ps, o, d, hit, need_normal)
        for pp in self.flat.planes:
            self._plane(pp, o, d, hit, need_normal)
        if self.count and not skip_triangles:
            self._triangles(o, d, hit, need_normal, active, candidates)
        return hit

    def _triangles(self, o, d, hit: Hit, need_normal: bool, active, candidates=None) -> None:
        T, dr = self.T, self.dr
        state = self.search(o, d, hit.t, hit.order, active, candidates)
        found = state.tri != NO_TRIANGLE
        if hit.t64 is not None:
            hit.t64 = dr.select(found, T.Float64(state.t), hit.t64)
        hit.t, hit.order = state.t, state.order
        mat, normal, geom = self.hit_data(state, found, need_normal)
        hit.material = dr.select(found, mat, hit.material)
        if normal is not None:
            hit.normal = dr.select(found, normal, hit.normal)
        if hit.geom is not None and geom is not None:
            hit.geom = dr.select(found, geom, hit.geom)

    def _closer(self, t, order: int, hit: Hit):
        return (t < hit.t) | ((t == hit.t) & (hit.order > order))

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
        dr, A3 = self.dr, self.T.Array3f
        s = ps.sphere
        if ps.xform is not None:
            o, d = _to_object_space(ps.xform, o, d)
        if self.robust:
            return self._sphere_robust(ps, o, d, hit, need_normal)
        c = A3(*s.center)
        oc = o - c
        a = dot(d, d)
        b = 2.0 * dot(d, oc)
        cc = dot(oc, oc) - float(np.float32(s.radius) * np.float32(s.radius))
        disc = b * b - (4.0 * a) * cc
        root = dr.sqrt(disc)
        t_minus = (-b - root) / (2.0 * a)
        t_plus = (-b + root) / (2.0 * a)
        t = dr.select(t_minus > 0.0, t_minus,
                      dr.select((t_plus > 0.0) & (t_minus < 0.0), t_plus, SPHERE_FALLBACK_T))
        ok = ~(disc < 0.0) & ~((t_minus < 0.0) & (t_plus < 0.0)) & self._closer(t, ps.order, hit)
        normal = None
        if need_normal:
            normal = normalize((o + t * d) - c)
            if ps.xform is not None:
                normal = _to_world_normal(ps.xform, normal)
        self._take(ok, t, ps.order, normal, s.material, hit)

    def _sphere_robust(self, ps, o, d, hit: Hit, need_normal: bool) -> None:
        """Robust mode. Fixes: the course's b² - 4ac cancels catastrophically for small or far
        spheres (distance/radius 1e5: the discriminant is rounding noise and every ray hits), and
        (-b ± √disc)/2a loses the near root to cancellation. Here (Hearn-Baker; Ray Tracing Gems
        ch. 7): f = o - c, b' = f·d, l = f - (b'/a) d is the closest-approach vector, computed
        without cancellation, disc = a (r² - l·l); q = -(b' + copysign(√disc, b')), and the roots
        c'/q and q/a, each without subtracting nearly equal numbers."""
        # Evaluated in float64 whatever the render precision: a sphere whose radius is a few
        # float32 ulps of its distance (distance/radius 1e7) is decided by float32 rounding
        # otherwise. Spheres are few; the cost is small.
        dr = self.dr
        D3 = self.T.ns.Array3f64
        s = ps.sphere
        c = D3(*s.center)
        r = float(np.float32(s.radius))
        o64, d64 = D3(o), D3(d)
        f = o64 - c
        a = dot(d64, d64)
        bp = dot(f, d64)
        l = f - (bp / a) * d64
        disc = a * (r * r - dot(l, l))
        q = -(bp + dr.copysign(dr.sqrt(dr.maximum(disc, 0.0)), bp))
        cc = dot(f, f) - r * r
        r0, r1 = cc / q, q / a
        t_near, t_far = dr.minimum(r0, r1), dr.maximum(r0, r1)
        t64 = dr.select(t_near > 0.0, t_near, t_far)
        t = self.T.Float(t64)
        closer = (t64 < hit.t64) | ((t64 == hit.t64) & (hit.order > ps.order))
        ok = (disc >= 0.0) & (t64 > 0.0) & (t64 < FLT_MAX) & closer
        normal = None
        if need_normal:
            normal = self.T.Array3f(normalize_safe(f + t64 * d64))
            if ps.xform is not None:
                normal = _to_world_normal(ps.xform, normal, normalize_safe)
        self._take(ok, t, ps.order, normal, s.material, hit, normal, t64)

    def _plane(self, pp, o, d, hit: Hit, need_normal: bool) -> None:
        A3 = self.T.Array3f
        p = pp.plane
        if pp.xform is not None:
            o, d = _to_object_space(pp.xform, o, d)
        n = A3(*p.normal)
        t = (p.offset - dot(o, n)) / dot(d, n)
        ok = ~(t < 0.0) & self._closer(t, pp.order, hit)
        normal = geom = None
        if need_normal:
            normal = n if pp.xform is None else _to_world_normal(pp.xform, n)
            if self.robust:
                # Robust: a unit normal (the course keeps the plane's raw normal, so a normal
                # written with length 2 doubles the lighting and bends mirror reflections).
                normal = geom = normalize_safe(n) if pp.xform is None else _to_world_normal(
                    pp.xform, n, normalize_safe)
        self._take(ok, t, pp.order, normal, p.material, hit, geom)

    def occluded(self, o, d, dist, active=None, grid=None):
        """Whether the course's shadow test finds a blocker: the closest hit has t <= dist,
        i.e. some primitive is hit at a t <= dist (and below FLT_MAX). Triangles stop at the
        first such hit; lanes outside `active` (if given) skip the triangles (their result is
        then unspecified). grid: the triangles' shadow grid for d (TriangleSet.shadow_grid)."""
        dr = self.dr
        if not self.robust:
            # the course tests "not t > dist": with a NaN distance (a NaN hit point) any hit
            # blocks the light
            dist = dr.select(dr.isnan(dist), FLT_MAX, dist)
        hit = self.closest(o, d, need_normal=False, skip_triangles=True)
        blocked = hit.found() & (hit.t <= dist)
        if self.count:
            blocked |= self.any_hit(o, d, dr.select(blocked, -1.0, dist), active, grid)
        return blocked
