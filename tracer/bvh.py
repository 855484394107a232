"""A bounding volume hierarchy over world-space triangles, built on the host (binned SAH).

Nodes are flattened in depth-first order: an inner node's left child is the next node, its right
child is stored; a leaf stores its first triangle and count in the reordered triangle list.
Boxes are padded by a small relative margin so that no triangle the exact (brute-force) test
accepts can lie outside its box through rounding: traversal then finds exactly the brute-force
hit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BINS = 16
MAX_LEAF = 8  # a node larger than this is always split
TRAVERSAL_COST = 1.0  # relative to one triangle test
BOX_PAD = 1e-5  # relative to the node's extent and coordinate magnitude
STACK_SIZE = 64  # traversal stack entries per lane; the build keeps the depth below it
MEDIAN_DEPTH = 38  # from this depth on, median splits: depth <= 38 + log2(2^24 triangles)


@dataclass(frozen=True)
class BVH:
    lo: np.ndarray  # (N,3) float32 padded node bounds
    hi: np.ndarray
    right_or_first: np.ndarray  # (N,) uint32: right child (inner) or first triangle (leaf)
    count: np.ndarray  # (N,) uint32: 0 for inner nodes, triangle count for leaves
    order: np.ndarray  # (T,) permutation: leaf triangle k is input triangle order[k]
    depth: int

    @property
    def node_count(self) -> int:
        return len(self.count)

    @property
    def nbytes(self) -> int:
        return self.lo.nbytes + self.hi.nbytes + self.right_or_first.nbytes + self.count.nbytes


def _area(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    e = np.maximum(hi - lo, 0.0)
    return 2.0 * (e[..., 0] * e[..., 1] + e[..., 1] * e[..., 2] + e[..., 2] * e[..., 0])


def _best_split(c: np.ndarray, lo: np.ndarray, hi: np.ndarray
                ) -> tuple[float, int, np.ndarray] | None:
    """(SAH cost, last bin of the left side, bin of every triangle) of the best binned split
    over the three axes, or None if the centroids coincide. The cost is Σ count·area of the
    two sides (divide by the parent's area for triangle tests per ray)."""
    cmin, cmax = c.min(axis=0), c.max(axis=0)
    best = None
    n = len(c)
    for axis in range(3):
        extent = cmax[axis] - cmin[axis]
        if not extent > 0:
            continue
        k = np.minimum(((c[:, axis] - cmin[axis]) * (BINS / extent)).astype(np.int64), BINS - 1)
        counts = np.bincount(k, minlength=BINS)
        blo = np.full((BINS, 3), np.inf)
        bhi = np.full((BINS, 3), -np.inf)
        np.minimum.at(blo, k, lo)
        np.maximum.at(bhi, k, hi)
        left_lo = np.minimum.accumulate(blo)[:-1]
        left_hi = np.maximum.accumulate(bhi)[:-1]
        right_lo = np.minimum.accumulate(blo[::-1])[::-1][1:]
        right_hi = np.maximum.accumulate(bhi[::-1])[::-1][1:]
        left_n = np.cumsum(counts)[:-1]
        right_n = n - left_n
        cost = left_n * _area(left_lo, left_hi) + right_n * _area(right_lo, right_hi)
        cost[(left_n == 0) | (right_n == 0)] = np.inf
        s = int(np.argmin(cost))
        if np.isfinite(cost[s]) and (best is None or cost[s] < best[0]):
            best = (float(cost[s]), s, k)
    return best


def build_bvh(vertices: np.ndarray) -> BVH:
    """vertices: (T,3,3) world-space triangles."""
    v = vertices.astype(np.float64)
    tri_lo, tri_hi = v.min(axis=1), v.max(axis=1)
    # Degenerate or non-finite triangles can never be hit; they still need a finite box.
    bad = ~np.isfinite(tri_lo).all(axis=1) | ~np.isfinite(tri_hi).all(axis=1)
    tri_lo[bad] = 0.0
    tri_hi[bad] = 0.0
    cent = 0.5 * (tri_lo + tri_hi)
    count = len(v)
    lo_out, hi_out, a_out, n_out = [], [], [], []
    order_chunks: list[np.ndarray] = []
    placed = 0
    max_depth = 0
    # (triangle indices, parent index whose right child this is or -1, depth)
    stack: list[tuple[np.ndarray, int, int]] = [(np.arange(count), -1, 0)]
    while stack:
        idx, parent, depth = stack.pop()
        max_depth = max(max_depth, depth)
        me = len(n_out)
        if parent >= 0:
            a_out[parent] = me
        lo, hi = tri_lo[idx].min(axis=0), tri_hi[idx].max(axis=0)
        lo_out.append(lo)
        hi_out.append(hi)
        n = len(idx)
        split = None
        if 1 < n and depth < MEDIAN_DEPTH:
            split = _best_split(cent[idx], tri_lo[idx], tri_hi[idx])
        leaf_cost = float(n)
        if split is not None:
            parent_area = float(_area(lo, hi)) or 1.0
            split_cost = TRAVERSAL_COST + split[0] / parent_area
        if split is None and n > MAX_LEAF:
            # Coincident centroids or a deep branch: halve at the median of the widest axis,
            # which bounds the depth (and so the traversal stack).
            c = cent[idx]
            axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
            half = n // 2
            part = np.argpartition(c[:, axis], half)
            left, right = idx[part[:half]], idx[part[half:]]
        elif split is None or (n <= MAX_LEAF and leaf_cost <= split_cost):
            a_out.append(placed)
            n_out.append(n)
            order_chunks.append(idx)
            placed += n
            continue
        else:
            _, last_left_bin, bins = split
            left, right = idx[bins <= last_left_bin], idx[bins > last_left_bin]
        a_out.append(0)  # patched when the right child is created
        n_out.append(0)
        stack.append((right, me, depth + 1))
        stack.append((left, -1, depth + 1))
    lo = np.array(lo_out)
    hi = np.array(hi_out)
    pad = BOX_PAD * ((hi - lo).max(axis=1, keepdims=True) + np.maximum(np.abs(lo), np.abs(hi)))
    return BVH(
        lo=(lo - pad).astype(np.float32),
        hi=(hi + pad).astype(np.float32),
        right_or_first=np.array(a_out, np.uint32),
        count=np.array(n_out, np.uint32),
        order=np.concatenate(order_chunks) if order_chunks else np.zeros(0, np.int64),
        depth=max_depth,
    )
