"""Grids of the triangles a directional light's shadow rays can hit: the candidates of their
any-hit test, found without the BVH.

A directional light's shadow rays all run along one direction d (in the space the triangles
are tested in: world space, or the one instance's space where every triangle is in one
transformed mesh), so a ray's line is fixed by where its origin lands on a plane across d.
Every triangle is projected onto that plane (in float64) and listed in each cell of a grid its
projected region reaches, widened by a margin for the float32 rounding of the ray and the
triangle test. A lane tests its cell's triangles with the BVH's triangle test, so it finds a
blocker where the BVH finds one: the lists hold every triangle the ray could be accepted by.
(Camera rays, which all start at the eye, have screen tiles for the same reason: screen_tiles.py.)

The region a triangle test accepts. It computes t from the record's plane (N, offset), the hit
p = o + t·d, and u, v, w as the rows g0, g1, g2 of the record's float32 M = [e1 e2 N]^-1 times
p - v0, and accepts 0 <= u, v and u + v <= 1. So it accepts the points of the plane inside the
triangle T' whose corners are v0, v0 + e1', v0 + e2' moved along N' onto the plane ([e1' e2'
N'] the inverse of M as stored, in float64), up to rounding: p is off the ray and the plane by
a few float32 ulps of S (the size of the coordinates in play: |o|, |p|, |v0|), and u and v each
by a few ulps of |p - v0|·|g0| and |p - v0|·|g1|, which moves the accepted point by that times
|e1'| and |e2'| (p - v0 = u·e1' + v·e2' + w·N'): by a few ulps of S times the triangle's
factor |g0|·|e1'| + |g1|·|e2'| + 1/cos(N, N'), the last for p's distance from the plane, taken
along N'. The factor is about 3 for a well-made triangle and grows with its aspect where its
sharp corner is v0 (the rows g0 and g1 grow, their terms cancel in u + v). Projecting along d
never lengthens a distance, and p's error along d does not move its projection, so every
accepted triangle's projection lies within RELATIVE_ERROR·S·factor of T''s, widened so.

No grid is made, and the BVH answers, where that bound could not be trusted or the lists would
be long: a record that is not finite, a factor over MAX_FACTOR (the relative error of u and v
would no longer be small), a direction that a transform would turn by more than float32
rounding (MAX_CONDITION), fewer than MIN_TRIANGLES or more than MAX_TRIANGLES triangles, or
more than MAX_PER_CELL entries a cell on average. Lanes whose origin lies beyond BOUND times the
triangles' extent take the BVH too: the margin grows with |o|.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kernel.backend import import_drjit
from ..kernel.uniforms import uniform
from ..kernel.vecmath import Types, dot
from .memo import kept
from .screen_tiles import bin_cells, device_lists, entries

# A few float32 ulps (6e-8) of S for the ray, the hit point and the test's dot products;
# 1e-5 leaves a factor of about 20 for all of them together (times each triangle's factor).
RELATIVE_ERROR = 1e-5
BOUND = 4.0  # lanes with max|o| above BOUND x the triangles' max coordinate take the BVH
# beyond it a few ulps of |p - v0|·|g| are no longer small against u and v (1e4 x 6e-8)
MAX_FACTOR = 1e4
MAX_CONDITION = 16.0  # of a transform's 3x3 part: the move of d errs by cond x ulps
# below this many triangles the BVH answers: its root box is missed by most shadow rays
# (cube_directional's 12-triangle cube rendered 1.24x slower with a grid)
MIN_TRIANGLES = 64
MAX_TRIANGLES = 1 << 14  # (larger meshes: the BVH)
CELLS_PER_TRIANGLE = 4
MAX_PER_CELL = 16  # list entries a cell on average
MAX_TOTAL = 1 << 21  # list entries in all (making them holds ~50 bytes an entry for a moment)
# a ray's direction off the grid's by more than this (relative, across it) or against it takes
# the BVH: a mistake's reversed or moved light; the course's rays are off by rounding alone
ALONG_TOLERANCE = 1e-6


@dataclass
class ShadowGrid:
    """Cell (row, column) -> its candidates' device indices: triangles[starts[k]:starts[k + 1]]
    for cell k = row * columns + column. A ray's origin o (in the triangles' space) lies in
    column floor((o·u_axis - u0)·inv_cell), row floor((o·v_axis - v0)·inv_cell); lanes with
    max|o| > bound take the BVH."""

    u_axis: np.ndarray  # float32 (3,)
    v_axis: np.ndarray  # float32 (3,)
    u0: float
    v0: float
    inv_cell: float  # float32 value
    columns: int
    rows: int
    bound: float
    w_axis: np.ndarray  # float32 (3,): the unit direction
    starts: np.ndarray  # uint32, cells + 1
    triangles: np.ndarray  # uint32
    tops: np.ndarray  # float32 per entry: above any point its triangle accepts, along w_axis


def _across(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit axes across the unit direction w (float64)."""
    k = int(np.argmin(np.abs(w)))
    u = np.cross(w, np.eye(3)[k])
    u /= np.linalg.norm(u)
    return u, np.cross(w, u)


def _regions(records: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The corners of the region each record's test accepts, (T, 3, 3) float64, and each one's
    factor (module docstring); None where a record is not finite or its M is singular."""
    r = records.astype(np.float64)
    v0, offset, normal = r[:, 0:3], r[:, 3], r[:, 4:7]  # the plane the test puts p on
    m = np.stack([r[:, 8:11], r[:, 12:15], r[:, [7, 11, 15]]], axis=1)  # rows g0, g1, g2
    if not np.isfinite(r).all():
        return None
    with np.errstate(all="ignore"):
        det = np.linalg.det(m)
        if not (np.isfinite(det).all() and (det != 0).all()):
            return None
        inv = np.linalg.inv(m)  # columns e1', e2', N'
        e1, e2, nn = inv[:, :, 0], inv[:, :, 1], inv[:, :, 2]
        length = np.linalg.norm
        along = np.einsum("ti,ti->t", nn, normal)
        factor = (length(m[:, 0], axis=1) * length(e1, axis=1)
                  + length(m[:, 1], axis=1) * length(e2, axis=1)
                  + length(nn, axis=1) * length(normal, axis=1) / np.abs(along))
        corner_list = []
        for c in (v0, v0 + e1, v0 + e2):
            # along N' onto the plane
            s = (offset - np.einsum("ti,ti->t", c, normal)) / along
            corner_list.append(c + s[:, None] * nn)
    corners = np.stack(corner_list, axis=1)
    if not (np.isfinite(corners).all() and np.isfinite(factor).all()):
        return None
    return corners, factor


@kept(8)  # per light direction, for a cause search's renders
def shadow_grid(records: np.ndarray, direction: np.ndarray,
                condition: float = 1.0) -> ShadowGrid | None:
    """The grid of triangles `records` (course_records, in device order) for rays along
    `direction` (float64, in the triangles' space; condition: that of the transform that moved
    it there, 1 for world space), or None where the BVH should answer."""
    count = len(records)
    if not MIN_TRIANGLES <= count <= MAX_TRIANGLES or condition > MAX_CONDITION:
        return None
    length = float(np.linalg.norm(direction))
    if not (np.isfinite(direction).all() and length > 0):
        return None
    regions = _regions(records)
    if regions is None or regions[1].max() > MAX_FACTOR:
        return None
    corners, factor = regions
    extent = float(np.abs(corners).max())
    bound = BOUND * max(extent, 1e-30)
    size = 2.0 * np.sqrt(3.0) * (bound + extent)  # S: |o| + |p| + |v0| and the like
    margin = RELATIVE_ERROR * size * (factor + condition)
    u_axis, v_axis = _across(direction / length)
    u_axis, v_axis = u_axis.astype(np.float32), v_axis.astype(np.float32)
    pu = corners @ u_axis.astype(np.float64)
    pv = corners @ v_axis.astype(np.float64)
    lo_u, hi_u = pu.min(axis=1) - margin, pu.max(axis=1) + margin
    lo_v, hi_v = pv.min(axis=1) - margin, pv.max(axis=1) + margin
    u0, v0 = float(np.float32(lo_u.min())), float(np.float32(lo_v.min()))  # as the kernel reads
    span = max(float(hi_u.max()) - u0, float(hi_v.max()) - v0, 1e-30)
    area = (float(hi_u.max()) - u0) * (float(hi_v.max()) - v0)
    side = max(np.sqrt(area / (CELLS_PER_TRIANGLE * count)), span / 4096.0)
    inv_cell = float(np.float32(1.0 / side))
    columns = int((float(hi_u.max()) - u0) * inv_cell) + 1
    rows = int((float(hi_v.max()) - v0) * inv_cell) + 1
    c0 = np.floor((lo_u - u0) * inv_cell).astype(np.int64)
    c1 = np.floor((hi_u - u0) * inv_cell).astype(np.int64)
    r0 = np.floor((lo_v - v0) * inv_cell).astype(np.int64)
    r1 = np.floor((hi_v - v0) * inv_cell).astype(np.int64)
    c0, c1 = np.clip(c0, 0, columns - 1), np.clip(c1, 0, columns - 1)
    r0, r1 = np.clip(r0, 0, rows - 1), np.clip(r1, 0, rows - 1)
    # a cell's entries highest first along the light: a lane stops at the first one whose top
    # lies below its origin, as its test needs t >= 0 (p at or above the origin). bin_cells
    # orders each cell by the index it is given: the triangles' ranks by top, mapped back after
    w_axis = (direction / length).astype(np.float32)
    top = (corners @ w_axis.astype(np.float64)).max(axis=1) + margin
    top = np.nextafter(top.astype(np.float32), np.float32(np.inf))
    by_top = np.argsort(-top, kind="stable")
    rank = np.empty(count, np.int64)
    rank[by_top] = np.arange(count)
    lists = bin_cells(c0, c1, r0, r1, np.ones(count, bool), columns, rows, rank,
                      np.zeros(0, np.int64), min(MAX_PER_CELL * columns * rows, MAX_TOTAL))
    if lists is None:
        return None
    starts, ranks = lists
    triangles = by_top[ranks].astype(np.uint32)
    return ShadowGrid(u_axis, v_axis, u0, v0, inv_cell, columns, rows, bound, w_axis, starts,
                      triangles, top[triangles])


class DeviceGrid:
    """A ShadowGrid on the device: its lists as arrays and its placement as run-time values
    (a moved light or mesh keeps the kernel)."""

    def __init__(self, grid: ShadowGrid, types: Types) -> None:
        dr = import_drjit()
        self.starts, self.triangles = device_lists(types, grid.starts, grid.triangles)
        self.tops = entries(types.Float, grid.tops)
        self.w_axis = uniform(types, grid.w_axis.tolist())
        self.u_axis = uniform(types, grid.u_axis.tolist())
        self.v_axis = uniform(types, grid.v_axis.tolist())
        self.corner = uniform(types, [grid.u0, grid.v0, 0.0])
        self.inv_cell = uniform(types, grid.inv_cell)
        self.bound = uniform(types, grid.bound)
        self.size = uniform(types, [float(grid.columns), float(grid.rows), 0.0])
        self.columns = dr.opaque(types.UInt32, grid.columns)

    def along(self, dr, d):
        """The lanes whose ray direction d (in the triangles' space) is the grid's: its lists
        and the tops they stop at hold for those alone."""
        ahead = dot(d, self.w_axis)
        across = dr.maximum(dr.abs(dot(d, self.u_axis)), dr.abs(dot(d, self.v_axis)))
        return (ahead > 0.0) & (across <= ALONG_TOLERANCE * ahead)

    def cells(self, types: Types, dr, o):
        """(near, inside, cell) for ray origins o in the triangles' space: near, the lanes the
        grid answers (max|o| within its bound); inside, those of them in a cell, and its
        index (0 elsewhere)."""
        # (an origin with a NaN coordinate may pass `near`, as dr.maximum can drop a NaN, and
        # then fails `inside`: no triangle, as through the BVH, where its t is NaN)
        near = dr.maximum(dr.maximum(dr.abs(o.x), dr.abs(o.y)), dr.abs(o.z)) <= self.bound
        column = dr.floor((dot(o, self.u_axis) - self.corner.x) * self.inv_cell)
        row = dr.floor((dot(o, self.v_axis) - self.corner.y) * self.inv_cell)
        inside = (near & (column >= 0.0) & (column < self.size.x) & (row >= 0.0)
                  & (row < self.size.y))
        cell = types.UInt32(row) * self.columns + types.UInt32(column)
        return near, inside, dr.select(inside, cell, 0)
