"""Screen tiles of the triangles a primary ray can hit: the candidates of a camera ray's closest
hit, found without the BVH.

Camera rays all start at the eye and a 16-lane packet of them covers a 4x4 block of sub-pixels
(render.Renderer._lanes), so their closest hits can be looked up by tile: every triangle in
front of the camera is projected onto the image (in float64) and listed in each 4x4 tile its
projected bounds reach, widened by a margin that covers the float32 rounding of the rays, the
jitter offsets and the triangle test. A lane tests its tile's triangles with the same triangle
test and the same closer-or-earlier rule as the BVH traversal (TriangleSet.search), so it finds
the same hit: the lists hold every triangle the ray could be accepted by. In a packet all lanes
read the same list, where the BVH's lanes each walk their own stack. (Embree gets the same
effect for coherent packets by traversing them together, which a Dr.Jit kernel, with no
operation across a packet's lanes, cannot do.)

The lists are not made, and the BVH answers, where the margin could not be trusted or the
lists would be long: a non-finite or ill-conditioned camera frame, a non-finite vertex, a side
of one sub-pixel, more than MAX_BEHIND triangles reaching behind the eye (each is listed in
every tile: its projection is unbounded), coordinates far larger than their distance to the
eye (MAX_SPREAD), a transformed triangle whose world position its course inverse does not
reproduce, more than MAX_ENTRIES entries a sub-pixel or MAX_TOTAL in all, or none at all.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..shade.camera import CameraFrame
from .flat_scene import ObjectTransform, TriangleSoup
from .memo import kept

TILE = 4  # sub-pixels per tile side: the lane blocks of render.Renderer._lanes
# A hit's rounding error, relative to |vertex| + |eye|: the float32 ray direction, the move into
# an instance and the triangle test each err by a few float32 ulps (6e-8) of the coordinates;
# 1e-5 leaves a factor of about 30. On the image it is magnified by |B^-1| / a (B the frame's
# forward, right and up; a the point's forward coordinate) and (W - 1)/2.
RELATIVE_ERROR = 1e-5
MAX_SPREAD = 1e4  # |B^-1| (|vertex| + |eye|) / a beyond which the margin is not trusted
MAX_CONDITION = 1e3  # of B (an up nearly along the view, a field of view near 0 or 180 degrees)
MAX_BEHIND = 16  # triangles reaching behind the eye (listed in every tile)
MAX_ENTRIES = 1  # list entries per sub-pixel: 16 triangle tests a ray on average
# and in all: making them holds ~50 bytes an entry for a moment (render memory budgets count
# the image, not this), 200 MiB at this many
MAX_TOTAL = 1 << 22
INSTANCE_TOLERANCE = 1e-4  # relative: object-space vertices against the inverse of world ones


@dataclass
class ScreenTiles:
    """Tile (row from the top, column) -> its candidates' device indices:
    triangles[starts[k]:starts[k + 1]] for tile k = row * columns + column."""

    columns: int
    starts: np.ndarray  # uint32, tiles + 1
    triangles: np.ndarray  # uint32


@kept(4)  # per camera and image size (memo.py)
def screen_tiles(frame: CameraFrame, tris: TriangleSoup, instances: list[ObjectTransform],
                 device_index: np.ndarray, sub_w: int, sub_h: int) -> ScreenTiles | None:
    """The tiles of a sub_w x sub_h sub-pixel image, or None where the BVH should answer.
    device_index: each soup triangle's index on the device (the BVH's order)."""
    if sub_w < 2 or sub_h < 2 or not 0 < len(tris) <= min(MAX_ENTRIES * sub_w * sub_h,
                                                             MAX_TOTAL):
        return None  # (more triangles than entries allowed: judged without projecting them)
    basis = np.stack([frame.forward, frame.right, frame.up], axis=1).astype(np.float64)
    eye = frame.center.astype(np.float64)
    world = (tris.vertices if tris.bounds is None else tris.bounds).astype(np.float64)
    if not (np.isfinite(basis).all() and np.isfinite(eye).all() and np.isfinite(world).all()):
        return None
    if np.linalg.cond(basis) > MAX_CONDITION or not _instances_consistent(tris, instances):
        return None
    inverse = np.linalg.inv(basis)
    # p - eye = a·forward + b·right + c·up: the ray through ndc (b/a, c/a) meets p at a
    coef = np.einsum("ij,tkj->tki", inverse, world - eye)
    a = coef[..., 0]
    size = np.abs(world).max(axis=2) + np.abs(eye).max()  # |vertex| + |eye| (T, 3)
    tiny = RELATIVE_ERROR * np.linalg.norm(inverse, 2) * size.max(axis=1)
    front = a.min(axis=1) > tiny
    behind = ~front & (a.max(axis=1) >= -tiny)  # wholly behind the eye: no hit at t >= 0
    if behind.sum() > MAX_BEHIND:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        spread = np.where(front, (np.linalg.norm(inverse, 2) * size / a).max(axis=1), 0.0)
        ndc_x = coef[..., 1] / a
        ndc_y = coef[..., 2] / a
    if spread.max(initial=0.0) > MAX_SPREAD:
        return None
    # sub-pixel x = (ndc + 1)(W - 1)/2 (y counted from the bottom); a lane at integer x casts
    # x + ξ, ξ in [0, 1): it can meet [lo, hi] where lo - 1 <= x <= hi
    margin = 1.0 + RELATIVE_ERROR * spread * max(sub_w, sub_h)
    x = (ndc_x + 1.0) * ((sub_w - 1) / 2.0)
    y = (ndc_y + 1.0) * ((sub_h - 1) / 2.0)
    with np.errstate(invalid="ignore"):
        x0 = np.floor(x.min(axis=1) - margin - 1.0)
        x1 = np.floor(x.max(axis=1) + margin)
        y0 = np.floor(y.min(axis=1) - margin - 1.0)
        y1 = np.floor(y.max(axis=1) + margin)
    columns, rows = -(-sub_w // TILE), -(-sub_h // TILE)
    seen = front & (x1 >= 0) & (x0 <= sub_w - 1) & (y1 >= 0) & (y0 <= sub_h - 1)
    x0, x1, y0, y1 = (np.where(seen, v, 0.0) for v in (x0, x1, y0, y1))
    # columns and rows (from the top) of tiles, clipped to the image
    c0 = np.clip(x0, 0, sub_w - 1).astype(np.int64) // TILE
    c1 = np.clip(x1, 0, sub_w - 1).astype(np.int64) // TILE
    r0 = (sub_h - 1 - np.clip(y1, 0, sub_h - 1).astype(np.int64)) // TILE
    r1 = (sub_h - 1 - np.clip(y0, 0, sub_h - 1).astype(np.int64)) // TILE
    lists = bin_cells(c0, c1, r0, r1, seen, columns, rows, device_index, np.flatnonzero(behind),
                      min(MAX_ENTRIES * sub_w * sub_h, MAX_TOTAL))
    return None if lists is None else ScreenTiles(columns, *lists)


def bin_cells(c0, c1, r0, r1, keep, columns: int, rows: int, device_index: np.ndarray,
              everywhere: np.ndarray, limit: int) -> tuple[np.ndarray, np.ndarray] | None:
    """(starts, triangles): the lists of a columns x rows grid, cell k = row * columns +
    column, in which kept triangle i is listed in columns c0[i]..c1[i] of rows r0[i]..r1[i]
    and the `everywhere` triangles in every cell, by device index; None where that is more
    than `limit` entries, or none."""
    per = np.where(keep, (c1 - c0 + 1) * (r1 - r0 + 1), 0)
    total = int(per.sum()) + len(everywhere) * columns * rows
    if not 0 < total <= limit:
        return None  # none: no ray hits a triangle, and an empty list array has none
    owner = np.repeat(np.arange(len(per)), per)
    k = np.arange(len(owner)) - np.repeat(np.cumsum(per) - per, per)
    width = (c1 - c0 + 1)[owner]
    cell = (r0[owner] + k // width) * columns + c0[owner] + k % width
    if len(everywhere):
        cell = np.concatenate([cell, np.repeat(np.arange(columns * rows), len(everywhere))])
        owner = np.concatenate([owner, np.tile(everywhere, columns * rows)])
    device = device_index[owner].astype(np.uint32)
    order = np.lexsort((device, cell))  # by cell, then device index (nearby records)
    starts = np.zeros(columns * rows + 1, np.int64)
    np.cumsum(np.bincount(cell, minlength=columns * rows), out=starts[1:])
    return starts.astype(np.uint32), device[order]


def _instances_consistent(tris: TriangleSoup, instances: list[ObjectTransform]) -> bool:
    """Whether each transformed triangle's object-space vertices are its world-space ones
    through its instance's course inverses (M^-1 per level, outermost first), within
    INSTANCE_TOLERANCE: where they are not (a nearly singular transform), a ray's hit in
    object space may lie far from where the world-space vertices put it."""
    if tris.bounds is None:
        return True
    for index in np.unique(tris.instance):
        if index >= len(instances):
            continue  # not transformed (NO_INSTANCE)
        mine = tris.instance == index
        p = tris.bounds[mine].astype(np.float64)
        for inverse in instances[index].inverses:
            m = inverse.astype(np.float64)
            p = np.einsum("ij,tkj->tki", m[:3, :3], p) + m[:3, 3]
        expected = tris.vertices[mine].astype(np.float64)
        size = np.abs(expected).max() + 1e-30
        if not np.isfinite(p).all() or np.abs(p - expected).max() > INSTANCE_TOLERANCE * size:
            return False
    return True


def device_lists(T, starts: np.ndarray, triangles: np.ndarray) -> tuple:
    """The lists as Dr.Jit arrays."""
    return T.UInt32(starts), entries(T.UInt32, triangles)


def entries(array_type, values: np.ndarray):
    """Per-entry values of lists as a Dr.Jit array, never of one element: Dr.Jit reads a
    one-element array as a broadcast value, another kernel than a gather (a camera change
    would compile again); the pad is never read."""
    if len(values) == 1:
        values = np.append(values, values[:1])
    return array_type(values)
