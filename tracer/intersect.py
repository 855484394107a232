"""Closest-hit queries over the flattened scene, traced into the render kernel (spec §5).

Only the primitive kinds the scene has are traced. Spheres and planes are few and are unrolled
with their parameters as literals; triangles are read from arrays in a symbolic loop.
Every test keeps the spec's comparison semantics, including how NaN falls through them.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .backend import import_drjit
from .geometry import FlatScene, ObjectTransform
from .vecmath import Types, cross, dot, mat3_mul, normalize

FLT_MAX = float(np.finfo(np.float32).max)
TRIANGLE_W_TOLERANCE = 1e-3


@dataclass
class Hit:
    t: Any  # FLT_MAX where nothing was hit
    order: Any  # file-order number of the primitive hit (ties in t go to the earlier one)
    normal: Any  # as the course stores it (raw for untransformed planes); zero on a miss
    material: Any

    def found(self):
        return self.t < FLT_MAX


def _to_object_space(xf: ObjectTransform, o, d):
    m = xf.inverse.tolist()
    p = mat3_mul(m, o)
    p = type(o)(p.x + m[0][3], p.y + m[1][3], p.z + m[2][3])
    w = ((m[3][0] * o.x + m[3][1] * o.y) + m[3][2] * o.z) + m[3][3]
    return p / w, mat3_mul(m, d)


class Intersector:
    def __init__(self, flat: FlatScene, types: Types) -> None:
        self.flat = flat
        self.T = types
        self.dr = import_drjit()
        tris = flat.triangles
        self.triangle_count = len(tris)
        if self.triangle_count:
            self._upload_triangles()

    def _upload_triangles(self) -> None:
        T, dr = self.T, self.dr
        tris = self.flat.triangles
        npf = np.float32
        v = tris.vertices.astype(npf)
        v0, e1, e2 = v[:, 0], v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
        c = np.cross(e1, e2).astype(npf)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            n = c / np.sqrt((c[:, 0] * c[:, 0] + c[:, 1] * c[:, 1]) + c[:, 2] * c[:, 2])[:, None]
            # Cramer's rule for [e1 e2 N](u,v,w) = b: u = b.(e2xN)/det, v = b.(Nxe1)/det,
            # w = b.(e1xe2)/det, det = e1.(e2xN).
            ca = np.cross(e2, n).astype(npf)
            cb = np.cross(n, e1).astype(npf)
            det = ((e1[:, 0] * ca[:, 0] + e1[:, 1] * ca[:, 1]) + e1[:, 2] * ca[:, 2])
            offset = ((v0[:, 0] * n[:, 0] + v0[:, 1] * n[:, 1]) + v0[:, 2] * n[:, 2])
        flt = T.Float

        def arr3(a: np.ndarray):
            return flt(np.ascontiguousarray(a, dtype=T.np_float).ravel())

        self.tv0, self.tn, self.ta, self.tb, self.tc = (arr3(x) for x in (v0, n, ca, cb, c))
        self.tdet = flt(det.astype(T.np_float))
        self.toffset = flt(offset.astype(T.np_float))
        self.tnormals = arr3(tris.normals.reshape(-1, 3))
        self.tmaterial = T.UInt32(tris.material)
        self.torder = T.UInt32(tris.order)
        self.tcount = dr.opaque(T.UInt32, self.triangle_count)

    # ------------------------------------------------------------------------------------
    def closest(self, o, d, need_normal: bool = True) -> Hit:
        T, dr = self.T, self.dr
        hit = Hit(
            t=dr.full(T.Float, FLT_MAX, dr.width(o)),
            order=dr.full(T.UInt32, 0xFFFFFFFF, dr.width(o)),
            normal=dr.zeros(T.Array3f, dr.width(o)),
            material=dr.zeros(T.UInt32, dr.width(o)),
        )
        for ps in self.flat.spheres:
            self._sphere(ps, o, d, hit, need_normal)
        for pp in self.flat.planes:
            self._plane(pp, o, d, hit, need_normal)
        if self.triangle_count:
            self._triangles(o, d, hit, need_normal)
        return hit

    def _closer(self, t, order: int, hit: Hit):
        return (t < hit.t) | ((t == hit.t) & (hit.order > order))

    def _take(self, mask, t, order, normal, material, hit: Hit) -> None:
        dr = self.dr
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
        c = A3(*s.center)
        oc = o - c
        a = dot(d, d)
        b = 2.0 * dot(d, oc)
        cc = dot(oc, oc) - float(np.float32(s.radius) * np.float32(s.radius))
        disc = b * b - (4.0 * a) * cc
        root = dr.sqrt(disc)
        t_minus = (-b - root) / (2.0 * a)
        t_plus = (-b + root) / (2.0 * a)
        t = dr.select(t_minus > 0.0, t_minus, t_plus)
        ok = ~(disc < 0.0) & ((t_minus > 0.0) | (t_plus > 0.0)) & self._closer(t, ps.order, hit)
        normal = None
        if need_normal:
            normal = normalize((o + t * d) - c)
            if ps.xform is not None:
                normal = normalize(mat3_mul(ps.xform.normal_matrix.tolist(), normal))
        self._take(ok, t, ps.order, normal, s.material, hit)

    def _plane(self, pp, o, d, hit: Hit, need_normal: bool) -> None:
        A3 = self.T.Array3f
        p = pp.plane
        if pp.xform is not None:
            o, d = _to_object_space(pp.xform, o, d)
        n = A3(*p.normal)
        t = (p.offset - dot(o, n)) / dot(d, n)
        ok = ~(t < 0.0) & self._closer(t, pp.order, hit)
        normal = None
        if need_normal:
            normal = n if pp.xform is None else normalize(
                mat3_mul(pp.xform.normal_matrix.tolist(), n))
        self._take(ok, t, pp.order, normal, p.material, hit)

    def _triangles(self, o, d, hit: Hit, need_normal: bool) -> None:
        T, dr = self.T, self.dr
        A3, Float, UInt32 = T.Array3f, T.Float, T.UInt32
        width = dr.width(o)
        best = dr.full(UInt32, 0xFFFFFFFF, width)
        bu = dr.zeros(Float, width)
        bv = dr.zeros(Float, width)

        def cond(i, *_):
            return i < self.tcount

        def body(i, t_best, o_best, best, bu, bv):
            n = dr.gather(A3, self.tn, i)
            t = (dr.gather(Float, self.toffset, i) - dot(o, n)) / dot(d, n)
            order = dr.gather(UInt32, self.torder, i)
            b = (o + t * d) - dr.gather(A3, self.tv0, i)
            det = dr.gather(Float, self.tdet, i)
            u = dot(b, dr.gather(A3, self.ta, i)) / det
            v = dot(b, dr.gather(A3, self.tb, i)) / det
            w = dot(b, dr.gather(A3, self.tc, i)) / det
            rejected = ((t < 0.0) | (dr.abs(w) > TRIANGLE_W_TOLERANCE) | (u < 0.0) | (u > 1.0)
                        | (v < 0.0) | (v > 1.0) | (u + v > 1.0))
            ok = ~rejected & ((t < t_best) | ((t == t_best) & (o_best > order)))
            t_best = dr.select(ok, t, t_best)
            o_best = dr.select(ok, order, o_best)
            best = dr.select(ok, i, best)
            bu = dr.select(ok, u, bu)
            bv = dr.select(ok, v, bv)
            return i + 1, t_best, o_best, best, bu, bv

        _, hit.t, hit.order, best, bu, bv = dr.while_loop(
            (dr.zeros(UInt32, width), hit.t, hit.order, best, bu, bv), cond, body)
        found = best != 0xFFFFFFFF
        idx = dr.select(found, best, 0)
        mat = dr.gather(UInt32, self.tmaterial, idx, found)
        hit.material = dr.select(found, mat, hit.material)
        if need_normal:
            base = idx * 3
            n0 = dr.gather(A3, self.tnormals, base, found)
            n1 = dr.gather(A3, self.tnormals, base + 1, found)
            n2 = dr.gather(A3, self.tnormals, base + 2, found)
            n = normalize(((1.0 - bu - bv) * n0 + bu * n1) + bv * n2)
            hit.normal = dr.select(found, n, hit.normal)
