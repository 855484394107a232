"""The course's mesh octree, built on the host exactly as the course builds it (spec §5.1).

The course intersects a TriangleMesh through an octree traversed with Revelles et al.'s
parametric algorithm. For rays with a direction component of exactly zero that traversal is
degenerate (0·inf = NaN, and a NaN midpoint never moves to the upper half), and which
triangles such a ray is tested against depends on which octree leaves hold them. The tracer
traverses its BVH for every other ray (the same hits: the octree visits every leaf the ray
crosses) and this octree for those rays only (tracer.accel.octree_traversal).

Build (per mesh, in the mesh's object space): the root box is the exact bounding box of the
vertices; a node with at most LEAF_SIZE triangles, or at MAX_LEVEL, is a leaf; otherwise its
box is split at mid = (lo + hi) / 2 into eight children, child j taking the upper half along x
if j & 4, along y if j & 2, along z if j & 1, and each child gets, in order, the triangles
whose bounding box touches its box (closed intervals). Levels are built at once (numpy).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .memo import kept

MAX_LEVEL = 8
LEAF_SIZE = 7
INNER = 0xFFFFFFFF  # the count slot of an inner node
F32 = np.float32


@dataclass(frozen=True)
class Octree:
    lo: np.ndarray  # (3,) float32 root box
    hi: np.ndarray
    nodes: np.ndarray  # (N, 2) uint32: (first child, INNER) or (first of tris, count)
    tris: np.ndarray  # (K,) int64 triangle numbers of the leaves, leaf after leaf


def _triangle_boxes(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per triangle (T,3,3) the box the course computes: start at vertex 0, then take a
    vertex coordinate where it compares smaller (larger), so NaN coordinates are skipped."""
    lo, hi = v[:, 0].copy(), v[:, 0].copy()
    with np.errstate(invalid="ignore"):
        for k in (1, 2):
            lo = np.where(lo > v[:, k], v[:, k], lo)
            hi = np.where(v[:, k] > hi, v[:, k], hi)
    return lo, hi


def _root_box(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The same rule over all vertices in file order: the NaN-ignoring min and max, unless the
    first vertex is NaN (then that coordinate stays NaN)."""
    first = v[0, 0]
    flat = v.reshape(-1, 3)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN coordinate
        lo, hi = np.nanmin(flat, axis=0), np.nanmax(flat, axis=0)
    nan = np.isnan(first)
    return np.where(nan, first, lo).astype(F32), np.where(nan, first, hi).astype(F32)


def _touches(tlo, thi, clo, chi) -> np.ndarray:
    """The course's test for a triangle box in a child box: inside, or overlapping on every
    axis (closed intervals), with its NaN behaviour."""
    with np.errstate(invalid="ignore"):
        inside = (~(clo > tlo) & ~(thi > chi)).all(axis=-1)
        overlap = (~(tlo > chi) & (thi >= clo)).all(axis=-1)
    return inside | overlap


def _child_touches(tlo, thi, mid) -> np.ndarray:
    """(P, 8) _touches of triangles without NaN in their parent's children: such a triangle
    touches its parent on every axis (the parent holds it), and then a child where it reaches
    the child's half on every axis: lo <= mid for a lower half, hi >= mid for an upper one."""
    low = ~(tlo > mid)
    high = thi >= mid
    out = np.empty((len(tlo), 8), bool)
    for j in range(8):
        x, y, z = (high[:, k] if (j >> (2 - k)) & 1 else low[:, k] for k in range(3))
        out[:, j] = x & y & z
    return out


@kept(16)  # a scene's meshes, for a cause search's renders (memo.py)
def build_octree(vertices: np.ndarray) -> Octree:
    """vertices: (T,3,3) float32 triangles of one mesh in face order (T >= 1)."""
    v = np.asarray(vertices, F32)
    tlo, thi = _triangle_boxes(v)
    lo, hi = _root_box(v)
    box_lo, box_hi = lo[None, :], hi[None, :]
    pair_node = np.zeros(len(v), np.int64)  # (node of this level, triangle) pairs, sorted
    pair_tri = np.arange(len(v), dtype=np.int64)
    levels: list[np.ndarray] = []  # per level: (m, 2) records with level-local child numbers
    leaf_tris: list[np.ndarray] = []
    tri_base = 0
    level = 0
    while len(box_lo):
        m = len(box_lo)
        count = np.bincount(pair_node, minlength=m)
        leaf = (count <= LEAF_SIZE) | (level >= MAX_LEVEL)
        rec = np.zeros((m, 2), np.int64)
        in_leaf = leaf[pair_node]
        leaf_tris.append(pair_tri[in_leaf])
        leaf_count = np.where(leaf, count, 0)
        rec[leaf, 0] = tri_base + (np.cumsum(leaf_count) - leaf_count)[leaf]
        rec[leaf, 1] = count[leaf]
        tri_base += int(leaf_count.sum())
        inner = np.flatnonzero(~leaf)
        rank = np.full(m, -1, np.int64)
        rank[inner] = np.arange(len(inner))
        rec[inner, 0] = 8 * np.arange(len(inner))  # level-local; offset below
        rec[inner, 1] = INNER
        levels.append(rec)
        # the children of the inner nodes, 8 per node, in child order
        mid = ((box_lo[inner] + box_hi[inner]) / F32(2)).astype(F32)
        bits = np.array([[(j >> 2) & 1, (j >> 1) & 1, j & 1] for j in range(8)], bool)
        c_lo = np.where(bits[None], mid[:, None], box_lo[inner][:, None]).reshape(-1, 3)
        c_hi = np.where(bits[None], box_hi[inner][:, None], mid[:, None]).reshape(-1, 3)
        keep = ~in_leaf
        p_node, p_tri = rank[pair_node[keep]], pair_tri[keep]
        child = 8 * p_node[:, None] + np.arange(8)[None, :]  # (P, 8)
        hit = _child_touches(tlo[p_tri], thi[p_tri], mid[p_node])
        odd = np.flatnonzero(np.isnan(tlo[p_tri]).any(axis=1) | np.isnan(thi[p_tri]).any(axis=1))
        if len(odd):
            hit[odd] = _touches(tlo[p_tri[odd]][:, None], thi[p_tri[odd]][:, None],
                                c_lo[child[odd]], c_hi[child[odd]])
        hit_child = child[hit]
        order = np.argsort(hit_child, kind="stable")  # child-major, triangles ascending
        pair_node = hit_child[order]
        pair_tri = np.broadcast_to(p_tri[:, None], child.shape)[hit][order]
        box_lo, box_hi = c_lo, c_hi
        level += 1
    # global node numbers: levels one after the other
    base = np.concatenate([[0], np.cumsum([len(r) for r in levels])])
    for i, rec in enumerate(levels):
        inner = rec[:, 1] == INNER
        rec[inner, 0] += base[i + 1]
    nodes = np.concatenate(levels).astype(np.uint32)
    return Octree(lo, hi, nodes, np.concatenate(leaf_tris))
