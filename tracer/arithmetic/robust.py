"""Robust mode (--mode robust): the course's arithmetic with its numerical failures fixed, as
subclasses of the course's parts that override what they compute differently (ray offsets,
normalisation, the sphere and triangle tests, light terms, the camera frame and the cube-map
lookup). arithmetic/__init__.py chooses one set per render; each method says what it fixes."""
from __future__ import annotations

import numpy as np

from ..accel.intersect import FLT_MAX, Hit, Intersector, to_world_normal
from ..accel.triangles import TriangleSet
from ..kernel.backend import aligned_zeros
from ..kernel.vecmath import div3, dot, normalize_safe, offset_ray_origin
from ..scene.model import Camera
from ..shade.background import Background
from ..shade.camera import F32, CameraFrame, frame_vectors, tanf
from ..shade.shading import Shader, reflect

MIN_DIST = 1e-15  # a point light closer than this is taken at this distance
MAX_INTENSITY = 1e30  # |light intensity| per channel is clamped to this
SHADOW_SHRINK = 1.0 - 1.0 / 4096.0  # blockers this close to a point light are ignored
COLOR_MAX = float(np.finfo(np.float32).max)


def robust_camera_frame(cam: Camera) -> CameraFrame:
    """Fixes: angle 0 gives dist = 1/tanf(0) = inf and inf·0 = NaN in every camera ray; a zero
    direction or an up parallel to it gives NaN w or u. Here non-finite frame vectors become
    zero, and where dist is not finite the frame is scaled by 1/dist instead (forward w, right
    tan(A/2)·u, up tan(A/2)·v): the same directions where both are finite, and for angle 0
    every ray is w."""
    def fin(v):
        v = np.asarray(v, F32)
        return v if np.isfinite(v).all() else np.zeros(3, F32)

    vec = frame_vectors(cam)
    w, u, up = fin(vec.w), fin(vec.u), fin(vec.up)
    if np.isfinite(vec.dist) and vec.dist != 0:
        return CameraFrame(fin(cam.center), fin(vec.dist * w), u, up)
    s = tanf(vec.angle / F32(2.0))
    s = s if np.isfinite(s) else F32(0.0)
    return CameraFrame(fin(cam.center), w, fin(s * u), fin(s * up))


class RobustBackground(Background):
    def _black_where_undefined(self, color, major, u, v):
        """A zero, NaN or infinite direction gives black (the course's zero-major rule)
        instead of NaN texel weights; finite texels stay as they are."""
        dr = self.dr
        bad = (major == 0.0) | ~dr.isfinite(major) | ~dr.isfinite(u) | ~dr.isfinite(v)
        return dr.select(bad, self.T.Array3f(0.0), color)


class RobustTriangleSet(TriangleSet):
    """The watertight triangle test on records of the vertices and the geometric normal."""

    SHADOW_GRIDS = False
    unit = staticmethod(normalize_safe)

    def _triangle_records(self, tris, permutation, record, normals):
        """The three vertices for the watertight test and the unit geometric normal: (v0, 0)
        (v1, 0) (v2, 0) (N, 0), the vertices in the render precision (float64 keeps the
        float32 scene values exactly). NaN vertex normals (a degenerate face shares the
        vertex: the course's sum of unit face normals is NaN) fall back to the face's
        geometric normal."""
        T = self.T
        unit_normal = record[:, 4:7]
        vr = tris.vertices[permutation].astype(T.np_float)
        out = aligned_zeros((len(vr), 4, 4), T.np_float)
        out[:, 0, :3], out[:, 1, :3], out[:, 2, :3] = vr[:, 0], vr[:, 1], vr[:, 2]
        with np.errstate(invalid="ignore"):
            out[:, 3, :3] = np.where(np.isfinite(unit_normal), unit_normal, 0.0)
        bad = ~np.isfinite(normals).all(axis=2, keepdims=True)
        normals = np.where(bad, out[:, 3:4, :3].astype(normals.dtype), normals)
        return T.Float(out.ravel()), normals

    def geometric_normal(self, idx, found):
        T, dr = self.T, self.dr
        A4 = T.ns.Array4f if T.precision == "single" else T.ns.Array4f64
        g = dr.gather(A4, self.trecord, idx * 4 + 3, found)
        return T.Array3f(g.x, g.y, g.z)

    def _triangle(self, i, o, d, skip_mesh=None, moved=False):
        """Woop, Benthin and Wald's watertight test (JCGT 2013). Fixes: the course's
        plane-then-barycentric test with its 1e-3 tolerance on w can let rays through shared
        edges and vertices of a closed mesh, or hit a neighbour's plane outside it. Rays are
        sheared so that they run along +z; the 2D edge functions of the vertices are exact in
        sign (computed in double, where products of two floats are exact), so a point on a
        shared edge is inside one of the two triangles. Degenerate triangles (det = 0) miss."""
        T, dr = self.T, self.dr
        A4 = T.ns.Array4f if T.precision == "single" else T.ns.Array4f64
        F64 = T.Float64
        base = i * 4
        kz, kx, ky, sx, sy, sz = self._shear(d)

        def vert(k):
            r = dr.gather(A4, self.trecord, base + k)
            return T.Array3f(r.x, r.y, r.z) - o

        def pick(v, k):
            return dr.select(k == 0, v.x, dr.select(k == 1, v.y, v.z))

        pts = []
        for k in range(3):
            v = vert(k)
            vz = pick(v, kz)
            pts.append((pick(v, kx) - sx * vz, pick(v, ky) - sy * vz, sz * vz))
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = pts
        U = F64(cx) * F64(by) - F64(cy) * F64(bx)
        V = F64(ax) * F64(cy) - F64(ay) * F64(cx)
        W = F64(bx) * F64(ay) - F64(by) * F64(ax)
        outside = ((U < 0.0) | (V < 0.0) | (W < 0.0)) & ((U > 0.0) | (V > 0.0) | (W > 0.0))
        det = U + V + W
        tt = (U * F64(az) + V * F64(bz)) + W * F64(cz)
        safe = dr.select(det == 0.0, 1.0, det)
        t = T.Float(tt / safe)
        ok = ~outside & (det != 0.0) & (t > 0.0) & dr.isfinite(t)
        # the course's u weights n1 (vertex 1), v weights n2
        u, v = T.Float(V / safe), T.Float(W / safe)
        return t, u, v, ok

    def _shear(self, d):
        """Per-ray constants of the watertight test: the axis of |d|'s largest component (kz),
        the other two (kx, ky, swapped to keep the winding when d_kz < 0) and the shear."""
        T, dr = self.T, self.dr
        ax, ay, az = dr.abs(d.x), dr.abs(d.y), dr.abs(d.z)
        kz = dr.select((ax >= ay) & (ax >= az), T.UInt32(0), dr.select(ay >= az, T.UInt32(1),
                                                                        T.UInt32(2)))
        kx = dr.select(kz == 2, T.UInt32(0), kz + 1)
        ky = dr.select(kx == 2, T.UInt32(0), kx + 1)
        dz = dr.select(kz == 0, d.x, dr.select(kz == 1, d.y, d.z))
        swap = dz < 0.0
        kx, ky = dr.select(swap, ky, kx), dr.select(swap, kx, ky)
        dx = dr.select(kx == 0, d.x, dr.select(kx == 1, d.y, d.z))
        dy = dr.select(ky == 0, d.x, dr.select(ky == 1, d.y, d.z))
        return kz, kx, ky, dx / dz, dy / dz, 1.0 / dz


class RobustIntersector(Intersector):
    """Robust tests, and the unit geometric normal of every hit (new rays leave along it)."""

    OCTREES = False  # the course's octrees decide the course's test only
    TRIANGLES = RobustTriangleSet

    def _no_hit(self, width: int, need_normal: bool) -> Hit:
        dr, T = self.dr, self.T
        hit = super()._no_hit(width, need_normal)
        if need_normal:
            hit.geom = dr.zeros(T.Array3f, width)
        if self.flat.spheres:
            hit.t64 = dr.full(T.Float64, FLT_MAX, width)
        return hit

    def _sphere_test(self, ps, o, d, hit: Hit, need_normal: bool) -> None:
        """Fixes: the course's b² - 4ac cancels catastrophically for small or far
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
                normal = to_world_normal(ps.xform, normal, normalize_safe)
        self._take(ok, t, ps.order, normal, s.material, hit, normal, t64)

    def _plane_normals(self, pp, n):
        """A unit normal (the course keeps the plane's raw normal, so a normal written with
        length 2 doubles the lighting and bends mirror reflections)."""
        normal = normalize_safe(n) if pp.xform is None else to_world_normal(pp.xform, n,
                                                                            normalize_safe)
        return normal, normal

    def _shadow_distance(self, dist):
        return dist

class RobustShader(Shader):
    def _clamp_intensity(self, i):
        """Per channel sign(i)·min(|i|, 1e30), NaN -> 0. Fixes: an infinite light color
        (a number over float32's range in the file) or falloff 0 makes ks·I = 0·inf = NaN."""
        dr = self.dr
        m = dr.minimum(dr.abs(i), MAX_INTENSITY)
        m = dr.select(dr.isnan(m), 0.0, m)
        return dr.copysign(m, i)

    def _point_light(self, light, p):
        """A point light's (to_light, intensity, dist). The distance is clamped to at least
        MIN_DIST and the denominator (dist·falloff)·dist to at least 1e-30 in magnitude
        (keeping falloff's sign), then the intensity is clamped. Fixes: a light on the surface
        (dist 0: L = 0/0 = NaN) and falloff 0 or subnormal (color/0 = inf, 0/0 = NaN). Falloff 0
        therefore means a very bright but finite light: lit values quantise to black (> 2^31/255)
        as in the course, without NaN or inf."""
        dr = self.dr
        v = light.position - p
        dist = dr.maximum(dr.sqrt(dot(v, v)), MIN_DIST)
        to_light = div3(v, dist)
        denom = (dist * light.falloff) * dist
        sign = -1.0 if np.signbit(np.float32(light.spec.falloff)) else 1.0
        denom = dr.select(dr.abs(denom) < 1e-30, sign * 1e-30, denom)
        intensity = self._clamp_intensity(div3(light.color, denom))
        return to_light, intensity, dist

    def direct(self, p, n, d, mat, geom=None, scale=None, active=None, record=None):
        """The same Phong terms as the course's with the fixes of _point_light and
        _clamp_intensity (no `record`: auxiliary images are course mode's); R·L clamped to [0, 1]
        before powf (fixes
        powf(1 + ulp, inf) = inf for shininess 1e39); shadow rays start at p offset along the
        geometric normal by Wächter and Binder's method (offset_ray_origin) toward the light's
        side, with tmin 0, and for point lights test blockers up to the distance from that
        origin times SHADOW_SHRINK (a light lying on a surface is not blocked by it)."""
        T, dr = self.T, self.dr
        material = self._material(mat)
        r = reflect(d, n)
        color = dr.zeros(T.Array3f, dr.width(p))
        for light in self.lights:
            if light.directional:
                to_light = normalize_safe(light.to_light)
                intensity = self._clamp_intensity(light.color)
            else:
                to_light, intensity, _ = self._point_light(light, p)
            rl = dr.clip(dot(r, to_light), 0.0, 1.0)
            term = self._phong(n, to_light, dr.select(dr.isnan(rl), 0.0, rl), intensity,
                               material)
            lit = color + term
            if self.shadows:
                side = dr.select(dot(geom, to_light) < 0.0, -1.0, 1.0)
                origin = offset_ray_origin(p, side * geom, T, scale)
                if light.directional:
                    sdir, sdist = to_light, FLT_MAX
                else:
                    v = light.position - origin
                    sdist = dr.sqrt(dot(v, v))
                    sdir = normalize_safe(v)
                    sdist = sdist * SHADOW_SHRINK
                blocked = self.isect.occluded(origin, sdir, sdist,
                                              self._term_matters(term, active))
                color = dr.select(blocked, color, lit)
            else:
                color = lit
        return color

    def error_scale(self, o, t):
        """|o|_max + t: what the rounding error of p = o + t*d is proportional to."""
        dr = self.dr
        return dr.maximum(dr.maximum(dr.abs(o.x), dr.abs(o.y)), dr.abs(o.z)) + dr.abs(t)

    def finished(self, c):
        """The last safeguard on a returned color: NaN -> 0, ±inf -> ±FLT_MAX. Both
        quantise to the same byte as before (black), so no image changes; floats stay finite."""
        dr = self.dr
        c = dr.select(dr.isnan(c), 0.0, c)
        return dr.clip(c, -COLOR_MAX, COLOR_MAX)

    def leaving(self, p, geom, r, scale):
        """The reflected ray leaves from p offset along the geometric normal toward the side r
        points to (Wächter and Binder), tmin 0."""
        side = self.dr.select(dot(geom, r) < 0.0, -1.0, 1.0)
        return offset_ray_origin(p, side * geom, self.T, scale)
