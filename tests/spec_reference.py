"""Independent, slow reference implementation of docs/course-format.md, used by tests only.

Written from the spec alone (it does not read or import any tracer module other than the scene
parser's data classes, which are its input). Everything is scalar ``np.float32`` arithmetic,
one pixel and one ray at a time, with every formula evaluated in the order the spec writes it:

* ``normalize(v) = v / sqrt(v·v)`` with ``a·b = (ax*bx + ay*by) + az*bz``;
* camera §4 with ``dist = 1 / tanf(A/2)``, ``A = float32(pi*deg/180)`` computed in double and
  ``tanf`` taken from libm through ctypes;
* sphere / plane / triangle §5 (the triangle's barycentrics through the cofactor inverse);
  transforms act on the ray, one after the other (``M⁻¹`` the float32 cofactor inverse), normals
  go back through ``normalize(((M₃ₓ₃)⁻¹)ᵀ n)``; meshes through the octree of §5.1;
* the Whitted recursion §6, written recursively; ``powf`` is float64 ``pow`` rounded to float32;
* cube-map lookup §7, output values §8 and the ``-filter`` kernel §9 (jitter is not modelled).

Array layout of the results matches the tracer's RenderResult: row 0 is the TOP of the image,
i.e. spec pixel y = h - 1 - row.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import math

import numpy as np

from raycheck.tracer.scene.model import Group, Mesh, Plane, Scene, Sphere, Transform, Triangle

F = np.float32
FLT_MAX = F(np.finfo(np.float32).max)
ZERO = F(0.0)
ONE = F(1.0)
TWO = F(2.0)
HALF_OFFSET = F(0.01)  # shadow / reflection ray offset
HALF = F(0.5)

_libm = ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6")
_libm.tanf.restype = ctypes.c_float
_libm.tanf.argtypes = [ctypes.c_float]


def tanf(x) -> np.float32:
    return F(_libm.tanf(float(F(x))))


def powf(x, y) -> np.float32:
    x = F(x)
    y = F(y)
    if y == 0:
        return ONE
    return F(math.pow(float(x), float(y)))


# ----------------------------------------------------------------------------- vector helpers
def vec(t) -> tuple:
    return (F(t[0]), F(t[1]), F(t[2]))


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mul(a, b):  # component-wise
    return (a[0] * b[0], a[1] * b[1], a[2] * b[2])


def scale(s, a):
    s = F(s)
    return (s * a[0], s * a[1], s * a[2])


def div(a, s):
    return (a[0] / s, a[1] / s, a[2] / s)


def dot(a, b):
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def length(a):
    return F(np.sqrt(dot(a, a)))


def normalize(a):
    return div(a, length(a))


ZERO3 = (ZERO, ZERO, ZERO)


# ----------------------------------------------------------------------------- camera §4
class Camera:
    def __init__(self, cam):
        d = vec(cam.direction)
        up = vec(cam.up)
        self.center = vec(cam.center)
        self.w = normalize(d)
        self.u = normalize(cross(d, up))
        self.v = up
        angle = F(math.pi * float(F(cam.angle_deg)) / 180.0)
        self.dist = ONE / tanf(angle / TWO)

    @staticmethod
    def ndc(i: int, n: int) -> np.float32:
        """ndc = 2*(i/(n-1.0f)) - 1 for integer pixel coordinate i."""
        return TWO * (F(i) / (F(n) - ONE)) - ONE

    def direction(self, ndcx, ndcy):
        s = add(add(scale(self.dist, self.w), scale(ndcx, self.u)), scale(ndcy, self.v))
        return normalize(s)


# ----------------------------------------------------------------------------- hits §5
class Hit:
    __slots__ = ("t", "material", "normal")

    def __init__(self):
        self.t = FLT_MAX
        self.material = None
        self.normal = ZERO3


def _inverse4(m):
    """The inverse of a 4x4 matrix (rows) by cofactors: 3x3 minors expanded along their
    first row, the determinant along the first row, each entry cofactor · (1/det)."""
    def det3(a):
        return ((a[1][1] * a[2][2] - a[1][2] * a[2][1]) * a[0][0]
                - (a[1][0] * a[2][2] - a[1][2] * a[2][0]) * a[0][1]
                + (a[1][0] * a[2][1] - a[1][1] * a[2][0]) * a[0][2])

    with np.errstate(all="ignore"):
        # minor (i, j): rows i+1.., columns j+1.. taken cyclically (the course's order)
        cof = [[det3([[m[(i + 1 + a) % 4][(j + 1 + b) % 4] for b in range(3)] for a in range(3)])
                * (ONE if (i + j) % 2 == 0 else F(-1.0)) for j in range(4)] for i in range(4)]
        det = ((m[0][0] * cof[0][0] + m[0][1] * cof[0][1]) + m[0][2] * cof[0][2]) \
            + m[0][3] * cof[0][3]
        r = ONE / det
        return [[cof[j][i] * r for j in range(4)] for i in range(4)]


def _inv3_transpose_apply(minv, n):
    """(M⁻¹₃ₓ₃)ᵀ · n."""
    return tuple((minv[0][i] * n[0] + minv[1][i] * n[1]) + minv[2][i] * n[2] for i in range(3))


def _mat_apply3(m, d):
    return tuple((m[i][0] * d[0] + m[i][1] * d[1]) + m[i][2] * d[2] for i in range(3))


def _mat_apply_point(m, o):
    x, y, z, w = (((m[i][0] * o[0] + m[i][1] * o[1]) + m[i][2] * o[2]) + m[i][3]
                  for i in range(4))
    return (x / w, y / w, z / w)


class _TriangleData:
    __slots__ = ("v0", "v1", "v2", "n0", "n1", "n2", "material")

    def __init__(self, v0, v1, v2, n0, n1, n2, material):
        self.v0, self.v1, self.v2 = v0, v1, v2
        self.n0, self.n1, self.n2 = n0, n1, n2
        self.material = material


def mesh_vertex_normals(vertices, faces):
    """§3: sum of unit face normals per vertex (faces in file order), then normalized."""
    verts = [vec(v) for v in np.asarray(vertices, dtype=np.float32)]
    sums = [ZERO3 for _ in verts]
    for a, b, c in np.asarray(faces):
        va, vb, vc = verts[a], verts[b], verts[c]
        fn = normalize(cross(sub(vb, va), sub(vc, va)))
        for k in (a, b, c):
            sums[k] = add(sums[k], fn)
    return verts, [normalize(s) for s in sums]


def _prepare(obj):
    """Convert scene objects to lightweight float32 tuples (recursive)."""
    if isinstance(obj, Group):
        return ("group", [_prepare(o) for o in obj.objects])
    if isinstance(obj, Sphere):
        return ("sphere", vec(obj.center), F(obj.radius), obj.material)
    if isinstance(obj, Plane):
        return ("plane", vec(obj.normal), F(obj.offset), obj.material)
    if isinstance(obj, Triangle):
        v0, v1, v2 = vec(obj.v0), vec(obj.v1), vec(obj.v2)
        n = normalize(cross(sub(v1, v0), sub(v2, v0)))
        return ("tris", [_TriangleData(v0, v1, v2, n, n, n, obj.material)])
    if isinstance(obj, Mesh):
        verts, normals = mesh_vertex_normals(obj.vertices, obj.faces)
        tris = [_TriangleData(verts[a], verts[b], verts[c], normals[a], normals[b], normals[c],
                              obj.material)
                for a, b, c in np.asarray(obj.faces)]
        return ("mesh", tris, OctreeModel(tris))
    if isinstance(obj, Transform):
        m = [[F(x) for x in row] for row in np.asarray(obj.matrix, dtype=np.float32)]
        # singular M: det 0 makes the inverse inf/NaN, and so the rays into the child
        minv = _inverse4(m)
        nmat = _inverse3([[m[i][j] for i in range(3)] for j in range(3)])
        return ("transform", minv, nmat, _prepare(obj.child))
    raise TypeError(f"unknown scene object {obj!r}")


def _intersect_sphere(c, r, mat, o, d, tmin, hit):
    oc = sub(o, c)
    a = dot(d, d)
    b = TWO * dot(d, oc)
    cc = dot(oc, oc) - r * r
    disc = b * b - F(4.0) * a * cc
    if disc < 0:
        return False
    sq = F(np.sqrt(disc))
    t_minus = (-b - sq) / (TWO * a)
    t_plus = (-b + sq) / (TWO * a)
    if t_minus < tmin and t_plus < tmin:
        return False
    if t_minus > tmin:
        t = t_minus
    elif t_plus > tmin and t_minus < tmin:
        t = t_plus
    else:  # no root strictly on either side of tmin (NaN roots, a root at tmin): t = 10000
        t = F(10000.0)
    if not (t < hit.t):
        return False
    p = add(o, scale(t, d))
    hit.t = t
    hit.material = mat
    hit.normal = normalize(sub(p, c))
    return True


def _intersect_plane(n, off, mat, o, d, tmin, hit):
    t = (off - dot(o, n)) / dot(d, n)
    if t < tmin:
        return False
    if not (t < hit.t):
        return False
    hit.t = t
    hit.material = mat
    hit.normal = n
    return True


def _inverse3(cols):
    """The inverse of the 3x3 matrix with these columns: cofactors m_a·m_d - m_b·m_c, the
    determinant along the first row, each entry cofactor · (1/det)."""
    m = [[cols[j][i] for j in range(3)] for i in range(3)]
    cof = [[F(0)] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(3):
            r0, r1 = [r for r in range(3) if r != i]
            c0, c1 = [c for c in range(3) if c != j]
            minor = m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
            cof[i][j] = minor if (i + j) % 2 == 0 else -minor
    r = ONE / ((m[0][0] * cof[0][0] + m[0][1] * cof[0][1]) + m[0][2] * cof[0][2])
    return [[cof[j][i] * r for j in range(3)] for i in range(3)]


def _intersect_triangle(tri, o, d, tmin, hit):
    e1 = sub(tri.v1, tri.v0)
    e2 = sub(tri.v2, tri.v0)
    n = normalize(cross(e1, e2))
    off = dot(tri.v0, n)
    t = (off - dot(o, n)) / dot(d, n)
    if not (t >= tmin):  # rejects t < tmin and NaN
        return False
    if not (t < hit.t):
        return False
    p = add(o, scale(t, d))
    rhs = sub(p, tri.v0)
    # (u, v, w) = [e1 e2 N]^-1 · rhs, the inverse by cofactors (adjugate / det), §5
    u, v, w = _mat_apply3(_inverse3((e1, e2, n)), rhs)
    if float(abs(w)) > 1e-3 or u < 0 or u > 1 or v < 0 or v > 1 or u + v > 1:
        return False
    s = (ONE - u) - v
    shading = normalize(add(add(scale(s, tri.n0), scale(u, tri.n1)), scale(v, tri.n2)))
    hit.t = t
    hit.material = tri.material
    hit.normal = shading
    return True


def intersect(node, o, d, tmin, hit) -> bool:
    kind = node[0]
    if kind == "group":
        any_hit = False
        for child in node[1]:
            if intersect(child, o, d, tmin, hit):
                any_hit = True
        return any_hit
    if kind == "sphere":
        return _intersect_sphere(node[1], node[2], node[3], o, d, tmin, hit)
    if kind == "plane":
        return _intersect_plane(node[1], node[2], node[3], o, d, tmin, hit)
    if kind == "mesh":
        return node[2].intersect(o, d, tmin, hit)
    if kind == "tris":
        any_hit = False
        for tri in node[1]:
            if _intersect_triangle(tri, o, d, tmin, hit):
                any_hit = True
        return any_hit
    if kind == "transform":
        minv, nmat = node[1], node[2]
        o2 = _mat_apply_point(minv, o)
        d2 = _mat_apply3(minv, d)
        if intersect(node[3], o2, d2, tmin, hit):
            hit.normal = normalize(_inv3_transpose_apply(nmat, hit.normal))
            return True
        return False
    raise TypeError(kind)


# ----------------------------------------------------------------------------- mesh octree §5
def _cmp_min(a, b):  # the course's box updates: replace where the new value compares smaller
    return tuple(b[k] if a[k] > b[k] else a[k] for k in range(3))


def _cmp_max(a, b):
    return tuple(b[k] if b[k] > a[k] else a[k] for k in range(3))


def _std_max(a, b):  # std::max / std::min: the first argument unless the second compares past it
    return b if a < b else a


def _std_min(a, b):
    return b if b < a else a


class _OctNode:
    __slots__ = ("children", "tris")

    def __init__(self):
        self.children = None
        self.tris = []


class OctreeModel:
    """§5 (meshes): the octree the course builds over a mesh and Revelles et al.'s parametric
    traversal, NaN behaviour included; the leaves' triangles are tested with the ray."""
    MAX_LEVEL, LEAF_SIZE = 8, 7

    def __init__(self, tris):
        self.tris = tris
        self.boxes = []
        for t in tris:
            lo = hi = t.v0
            for v in (t.v1, t.v2):
                lo, hi = _cmp_min(lo, v), _cmp_max(hi, v)
            self.boxes.append((lo, hi))
        lo = hi = tris[0].v0
        for t in tris:
            for v in (t.v0, t.v1, t.v2):
                lo, hi = _cmp_min(lo, v), _cmp_max(hi, v)
        self.lo, self.hi = lo, hi
        self.root = _OctNode()
        self._build(self.root, lo, hi, list(range(len(tris))), 0)

    def _touches(self, i, lo, hi):
        tlo, thi = self.boxes[i]
        inside = all(not (lo[k] > tlo[k]) and not (thi[k] > hi[k]) for k in range(3))
        overlap = all(not (tlo[k] > hi[k]) and thi[k] >= lo[k] for k in range(3))
        return inside or overlap

    def _build(self, node, lo, hi, tris, level):
        if len(tris) <= self.LEAF_SIZE or level >= self.MAX_LEVEL:
            node.tris = tris
            return
        mid = tuple((lo[k] + hi[k]) / TWO for k in range(3))
        node.children = []
        for j in range(8):
            up = ((j >> 2) & 1, (j >> 1) & 1, j & 1)
            clo = tuple(mid[k] if up[k] else lo[k] for k in range(3))
            chi = tuple(hi[k] if up[k] else mid[k] for k in range(3))
            child = _OctNode()
            node.children.append(child)
            self._build(child, clo, chi, [i for i in tris if self._touches(i, clo, chi)],
                        level + 1)

    def intersect(self, o, d, tmin, hit) -> bool:
        self._query = (o, d)  # the leaves' triangles are tested with the ray itself
        d = list(normalize(d))
        o = list(o)
        self._a = 0  # the axes mirrored to make every direction component non-negative
        for k, bit in ((0, 4), (1, 2), (2, 1)):
            if d[k] < 0:
                o[k] = (self.lo[k] + self.hi[k]) - o[k]
                d[k] = -d[k]
                self._a |= bit
        inv = [ONE / d[k] for k in range(3)]
        t0 = [(self.lo[k] - o[k]) * inv[k] for k in range(3)]
        t1 = [(self.hi[k] - o[k]) * inv[k] for k in range(3)]
        if _std_min(_std_min(t1[0], t1[1]), t1[2]) >= _std_max(_std_max(t0[0], t0[1]), t0[2]):
            return self._proc(t0, t1, self.root, tmin, hit)
        return False

    @staticmethod
    def _first_node(t0, tm):
        (x0, y0, z0), (xm, ym, zm) = t0, tm
        if x0 > y0:
            if x0 > z0:
                return (2 if x0 > ym else 0) | (1 if x0 > zm else 0)
        elif y0 > z0:
            return (4 if y0 > xm else 0) | (1 if y0 > zm else 0)
        return (4 if z0 > xm else 0) | (2 if z0 > ym else 0)

    @staticmethod
    def _new_node(ex, cx, ey, cy, ez, cz):
        if ey > ex:
            return cx if ez > ex else cz
        return cy if ez > ey else cz

    def _proc(self, t0, t1, node, tmin, hit) -> bool:
        if t1[0] < 0 or t1[1] < 0 or t1[2] < 0:
            return False
        if node.children is None:
            found = False
            for i in node.tris:
                found = _intersect_triangle(self.tris[i], *self._query, tmin, hit) or found
            return found
        tm = [HALF * (t0[k] + t1[k]) for k in range(3)]
        cur = self._first_node(t0, tm)
        found = False
        while cur < 8:
            up = ((cur >> 2) & 1, (cur >> 1) & 1, cur & 1)
            c0 = [tm[k] if up[k] else t0[k] for k in range(3)]
            c1 = [t1[k] if up[k] else tm[k] for k in range(3)]
            found = self._proc(c0, c1, node.children[cur ^ self._a], tmin, hit) or found
            ex = [t1[k] if up[k] else tm[k] for k in range(3)]
            code = [8 if up[k] else cur | (4, 2, 1)[k] for k in range(3)]
            cur = self._new_node(ex[0], code[0], ex[1], code[1], ex[2], code[2])
        return found


# ----------------------------------------------------------------------------- cube map §7
def _face_fetch(face: np.ndarray, u, v):
    h, w = face.shape[0], face.shape[1]
    x = u * F(w)
    y = (ONE - v) * F(h)
    i = int(x)  # truncation toward zero, like a C float->int cast
    j = int(y)
    a = x - F(i)
    b = y - F(j)

    def texel(ii, jj):
        ii = min(max(ii, 0), w - 1)
        jj = min(max(jj, 0), h - 1)
        return vec(face[jj, ii])

    t00, t10, t01, t11 = texel(i, j), texel(i + 1, j), texel(i, j + 1), texel(i + 1, j + 1)
    w00 = (ONE - a) * (ONE - b)
    w10 = a * (ONE - b)
    w01 = (ONE - a) * b
    w11 = a * b
    return add(add(add(scale(w00, t00), scale(w10, t10)), scale(w01, t01)), scale(w11, t11))


def cube_map_lookup(cube, d):
    x, y, z = normalize(d)
    ax, ay, az = abs(x), abs(y), abs(z)
    if ax >= ay and ax >= az:
        if x == 0:
            return ZERO3
        if x > 0:
            return _face_fetch(cube.faces["right"], (z / x + ONE) / TWO, (y / x + ONE) / TWO)
        return _face_fetch(cube.faces["left"], (z / x + ONE) / TWO, ONE - (y / x + ONE) / TWO)
    if ay >= az:
        if y == 0:
            return ZERO3
        if y > 0:
            return _face_fetch(cube.faces["up"], (x / y + ONE) / TWO, (z / y + ONE) / TWO)
        return _face_fetch(cube.faces["down"], ONE - (x / y + ONE) / TWO,
                           ONE - (z / y + ONE) / TWO)
    if z == 0:
        return ZERO3
    if z > 0:
        return _face_fetch(cube.faces["front"], ONE - (x / z + ONE) / TWO, (y / z + ONE) / TWO)
    return _face_fetch(cube.faces["back"], (x / z + ONE) / TWO, ONE - (y / z + ONE) / TWO)


# ----------------------------------------------------------------------------- shading §6
class ReferenceTracer:
    def __init__(self, scene: Scene, shadows: bool = False):
        self.scene = scene
        self.shadows = shadows
        self.camera = Camera(scene.camera)
        self.root = _prepare(scene.root)
        self.materials = [(vec(m.diffuse), vec(m.specular), F(m.shininess))
                          for m in scene.materials]
        bg = scene.background
        self.bg_color = vec(bg.color)
        self.cube = bg.cube_map
        # No light at all: the ambient light is forced to (1, 1, 1).
        self.ambient = vec(bg.ambient) if scene.lights else (ONE, ONE, ONE)
        self.lights = []
        for light in scene.lights:
            if hasattr(light, "direction"):
                self.lights.append(("dir", vec(light.direction), vec(light.color)))
            else:
                self.lights.append(("point", vec(light.position), vec(light.color),
                                    F(light.falloff)))

    def closest_hit(self, o, d, tmin=ZERO):
        hit = Hit()
        intersect(self.root, o, d, F(tmin), hit)
        return hit

    def background(self, d):
        if self.cube is not None:
            return cube_map_lookup(self.cube, d)
        return self.bg_color

    def illumination(self, light, p):
        if light[0] == "dir":
            direction, color = light[1], light[2]
            return scale(F(-1.0), direction), color, FLT_MAX
        position, color, falloff = light[1], light[2], light[3]
        to_light = sub(position, p)
        dist = length(to_light)
        L = div(to_light, dist)
        denom = (dist * falloff) * dist
        return L, div(color, denom), dist

    @staticmethod
    def shade(rd, n, L, I, kd, ks, shininess):
        """The diffuse and the specular term of one light."""
        diffuse = mul(scale(max(dot(n, L), ZERO), I), kd)
        R = sub(rd, scale(TWO * dot(n, rd), n))
        specular = mul(scale(powf(max(dot(R, L), ZERO), shininess), I), ks)
        return diffuse, specular

    def parts(self, ro, rd, bounces: int, hit: Hit | None = None) -> dict | None:
        """The terms of the color at the closest hit (None on a miss): per light its diffuse
        and specular term and whether its shadow ray is blocked, the reflected color ks ⊙
        trace(R) (None without a mirror bounce) and the ambient term."""
        if hit is None:
            hit = self.closest_hit(ro, rd)
        if hit.material is None:
            return None
        kd, ks, shininess = self.materials[hit.material]
        p = add(ro, scale(hit.t, rd))
        n = hit.normal
        lights = []
        for light in self.lights:
            L, I, dist = self.illumination(light, p)
            blocked = False
            if self.shadows:
                sh = self.closest_hit(add(p, scale(HALF_OFFSET, L)), L)
                blocked = sh.material is not None and not sh.t > dist  # NaN dist: blocked
            lights.append(self.shade(rd, n, L, I, kd, ks, shininess) + (blocked,))
        reflection = None
        if length(ks) > F(0.1) and bounces > 0:
            R = sub(rd, scale(TWO * dot(n, rd), n))
            reflection = mul(ks, self.trace(add(p, scale(HALF_OFFSET, R)), R, bounces - 1))
        return {"material": hit.material, "lights": lights, "reflection": reflection,
                "ambient": mul(self.ambient, kd)}

    def trace(self, ro, rd, bounces: int, hit: Hit | None = None):
        parts = self.parts(ro, rd, bounces, hit)
        if parts is None:
            return self.background(rd)
        color = ZERO3
        for diffuse, specular, blocked in parts["lights"]:
            if not blocked:
                color = add(color, add(diffuse, specular))
        if parts["reflection"] is not None:
            color = add(color, parts["reflection"])
        return add(color, parts["ambient"])

    def primary_ray(self, x: int, y: int, w: int, h: int):
        cam = self.camera
        return cam.center, cam.direction(Camera.ndc(x, w), Camera.ndc(y, h))

    def primary(self, x: int, y: int, w: int, h: int, bounces: int):
        """Color, normal and t of spec pixel (x, y) (y = 0 bottom) of a w x h image."""
        cam = self.camera
        d = self.primary_ray(x, y, w, h)[1]
        hit = self.closest_hit(cam.center, d)
        color = self.trace(cam.center, d, bounces, hit)
        normal = hit.normal if hit.material is not None else ZERO3
        return color, normal, hit.t


# ----------------------------------------------------------------------------- filter §9
KERNEL = ((1, 2, 1), (2, 4, 2), (1, 2, 1))


def filter_3x3(big: np.ndarray) -> np.ndarray:
    """Σ_j Σ_i K[j][i]·big(3x+i, 3y+j) / 16 in float32 (j outer, i inner).

    ``big`` has row 0 = top; the kernel is symmetric so the block of output row r is big rows
    3r..3r+2 whichever way the rows are counted."""
    big = np.asarray(big, dtype=np.float32)
    H, W = big.shape[0], big.shape[1]
    h, w = H // 3, W // 3
    out = np.zeros((h, w) + big.shape[2:], dtype=np.float32)
    with np.errstate(all="ignore"):
        for r in range(h):
            for c in range(w):
                acc = np.zeros(big.shape[2:], dtype=np.float32)
                for j in range(3):
                    # spec row offset j counts upward: top-based row 3r + 2 - j
                    for i in range(3):
                        acc = acc + F(KERNEL[j][i]) * big[3 * r + 2 - j, 3 * c + i]
                out[r, c] = acc / F(16.0)
    return out


# ----------------------------------------------------------------------------- entry point
def render_reference(scene: Scene, width: int, height: int, bounces: int = 0,
                     shadows: bool = False, filter: bool = False, depth_min: float = 0.0,
                     depth_max: float = 1.0):
    """(color, normals_value, depth_value) float32 arrays, row 0 = top of the image."""
    tracer = ReferenceTracer(scene, shadows=shadows)
    W, H = (3 * width, 3 * height) if filter else (width, height)
    color = np.zeros((H, W, 3), dtype=np.float32)
    normals = np.zeros((H, W, 3), dtype=np.float32)
    depth = np.zeros((H, W), dtype=np.float32)
    dmin = F(depth_min)
    drange = F(depth_max) - dmin
    with np.errstate(all="ignore"):
        for y in range(H):
            row = H - 1 - y
            for x in range(W):
                c, n, t = tracer.primary(x, y, W, H, bounces)
                color[row, x] = c
                normals[row, x] = [(n[k] + ONE) / TWO for k in range(3)]
                depth[row, x] = (t - dmin) / drange
    if filter:
        return filter_3x3(color), filter_3x3(normals), filter_3x3(depth)
    return color, normals, depth


# ----------------------------------------------------------------------------- quantisation §8
def quantize_reference(values) -> np.ndarray:
    """v = c*255.0f in float32; x86 cvttss2si (NaN, ±inf, out of range -> INT_MIN); clamp."""
    with np.errstate(all="ignore"):
        v = np.asarray(values, dtype=np.float32) * np.float32(255.0)
        v64 = v.astype(np.float64)
        ok = np.isfinite(v64) & (v64 >= -2.0 ** 31) & (v64 < 2.0 ** 31)
        out = np.full(v.shape, -(2 ** 31), dtype=np.int64)
        out[ok] = np.trunc(v64[ok]).astype(np.int64)
    return np.clip(out, 0, 255).astype(np.uint8)
