"""A bounding volume hierarchy over world-space triangles, built on the host (binned SAH).

Nodes are flattened in depth-first order: an inner node's left child is the next node, its right
child is stored; a leaf stores its first triangle and count in the reordered triangle list.
Boxes are padded by a small relative margin so that no triangle the exact (brute-force) test
accepts can lie outside its box through rounding: traversal then finds exactly the brute-force
hit.

The build is vectorised over all nodes of one tree level at a time (no Python loop per node):

* the triangles are sorted once by centroid along each axis; every level keeps, per axis, the
  triangles of each open node as one contiguous run in that axis' order (a stable partition
  carries the order down to the children);
* along each axis, a node of more than BINS triangles bins its centroids (BINS equal intervals
  of the centroid extent). In sorted order a node's bins are contiguous runs, so the bin boxes
  come from one ``np.minimum.reduceat`` (or ``np.minimum.at``) per box row into a dense
  (BINS, 6, nodes) array, and the left/right boxes of every split are running minima over it;
* a node of at most BINS triangles gets an exact sweep instead (every split between consecutive
  centroids): running minima within each node's run, as log-step (Hillis-Steele) scans;
* the SAH cost ``TRAVERSAL_COST + (nl·A_l + nr·A_r) / A`` (in triangle tests) of the best split
  over the three axes is compared with the leaf cost ``n``: nodes of at most MAX_LEAF triangles
  become leaves when that is not more expensive, larger ones are always split;
* from MEDIAN_DEPTH on, and where all centroids coincide, nodes are halved at the median, which
  bounds the depth (and so the traversal stack).

Finally the level-order nodes are renumbered depth-first (subtree sizes, one pass per level).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

BINS = 16  # SAH bins per axis for nodes of more than BINS triangles (smaller nodes: a sweep)
MAX_LEAF = 8  # a node larger than this is always split
TRAVERSAL_COST = 1.0  # one inner-node visit relative to one triangle test
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


def surface_area(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    e = np.maximum(hi - lo, 0.0)
    return 2.0 * (e[..., 0] * e[..., 1] + e[..., 1] * e[..., 2] + e[..., 2] * e[..., 0])


def _area6(box: np.ndarray) -> np.ndarray:
    """Surface areas of boxes stored as rows (lo.xyz, -hi.xyz) along axis -2 (float32; empty
    boxes, +inf rows, give 0)."""
    e = box[..., :3, :] + box[..., 3:, :]  # lo - hi: minus the extent (+inf when empty)
    np.minimum(e, 0.0, out=e)
    ex, ey, ez = e[..., 0, :], e[..., 1, :], e[..., 2, :]
    a = ex * ey
    a += ey * ez
    a += ez * ex
    a *= 2.0
    return a


class _Level:
    """The open nodes of one level. Per axis a: their triangles as contiguous runs sorted by
    centroid along a (ids, box rows lo/-hi, that centroid coordinate)."""

    def __init__(self, perm, box, cent, start, size, gstart):
        self.perm = perm  # 3 x (n,) triangle ids
        self.box = box  # 3 x (6, n) float32 rows lo.xyz, -hi.xyz
        self.cent = cent  # 3 x (n,) float64 centroid coordinate along that axis
        self.start = start  # (m,) run start
        self.size = size  # (m,) triangles per node
        self.gstart = gstart  # (m,) first position of the node's triangles in `order`


def _binned(c, box, seg_of, size, start):
    """Binned SAH along one axis for nodes of more than BINS triangles: per node (Σ n·area
    cost of the best split, inf where none; its left count; node box rows (6, m))."""
    m, n = len(size), len(seg_of)
    cmin = c[start]
    ext = c[start + size - 1] - cmin
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(ext > 0, BINS / ext, 0.0)
    b = ((c - cmin[seg_of]) * scale[seg_of]).astype(np.int64)
    np.minimum(b, BINS - 1, out=b)
    change = np.empty(n, bool)  # the first triangle of each bin (bins are runs: c is sorted)
    change[0] = True
    np.not_equal(b[1:], b[:-1], out=change[1:])
    change[1:] |= seg_of[1:] != seg_of[:-1]
    first = np.flatnonzero(change)
    slot = b * m + seg_of  # bin-major slots: (BINS, 6, m) rows are contiguous per bin
    bins = np.full((6, BINS * m), np.inf, np.float32)
    if 8 * len(first) < n:  # long bins: one reduction per bin
        bins[:, slot[first]] = np.minimum.reduceat(box, first, axis=1)
    else:  # short bins: place one triangle per bin, fold in the others
        bins[:, slot[first]] = box[:, first]
        dup = ~change
        sd = slot[dup]
        for row in range(6):
            np.minimum.at(bins[row], sd, box[row][dup])
    cnt = np.bincount(slot, minlength=BINS * m).reshape(BINS, m)
    bins = bins.reshape(6, BINS, m).transpose(1, 0, 2)  # (BINS, 6, m) view
    pre = np.empty((BINS, 6, m), np.float32)
    suf = np.empty((BINS, 6, m), np.float32)
    pre[0] = bins[0]
    suf[-1] = bins[-1]
    nl = np.empty((BINS - 1, m), np.int64)  # triangles left of the split after bin k
    nl[0] = cnt[0]
    for k in range(1, BINS):
        np.minimum(pre[k - 1], bins[k], out=pre[k])
        np.minimum(suf[BINS - k], bins[BINS - 1 - k], out=suf[BINS - 1 - k])
        if k < BINS - 1:
            np.add(nl[k - 1], cnt[k], out=nl[k])
    nr = size[None, :] - nl
    with np.errstate(invalid="ignore", over="ignore"):
        cost = nl * _area6(pre[:-1]) + nr * _area6(suf[1:])
    cost[(nl == 0) | (nr == 0) | np.isnan(cost)] = np.inf
    j = np.argmin(cost, axis=0)
    cols = np.arange(m)
    return cost[j, cols], nl[j, cols], pre[-1]


def _scan_min(x: np.ndarray, same: list[np.ndarray], reverse: bool) -> np.ndarray:
    """Inclusive running minimum along the columns of x (rows: components) within runs;
    same[i] tells whether columns j and j + 2^i are in one run. Hillis-Steele steps."""
    out = x.copy()
    for i, sm in enumerate(same):
        k = 1 << i
        if reverse:
            np.copyto(out[:, :-k], np.minimum(out[:, :-k], out[:, k:]), where=sm)
        else:
            np.copyto(out[:, k:], np.minimum(out[:, k:], out[:, :-k]), where=sm)
    return out


def _run_masks(seg_of: np.ndarray, longest: int) -> list[np.ndarray]:
    """Hillis-Steele masks: whether columns j and j + 2^i belong to one node."""
    masks = []
    k = 1
    while k < longest:
        masks.append(seg_of[k:] == seg_of[:-k])
        k *= 2
    return masks


def _sweep(box, seg_of, rank, size, start, same):
    """Exact SAH sweep along one axis for nodes of at most BINS triangles (every split between
    consecutive triangles in centroid order): per node (cost, left count, node box rows)."""
    n = len(seg_of)
    pre = _scan_min(box, same, reverse=False)
    suf = _scan_min(box, same, reverse=True)
    last = start + size - 1
    nl = rank[:-1] + 1  # split after triangle i
    nr = size[seg_of[:-1]] - nl
    cost = np.full(n, np.inf)
    with np.errstate(invalid="ignore", over="ignore"):
        cost[:-1] = nl * _area6(pre[:, :-1]) + nr * _area6(suf[:, 1:])
    cost[last] = np.inf
    cost[np.isnan(cost)] = np.inf
    seg_min = np.minimum.reduceat(cost, start)
    hit = np.flatnonzero(cost == seg_min[seg_of])
    first_hit = hit[np.concatenate([[True], seg_of[hit][1:] != seg_of[hit][:-1]])]
    return seg_min, rank[first_hit] + 1, pre[:, last]


def _subset(lvl: _Level, nodes: np.ndarray):
    """Sizes, starts and per-element node numbers of a subset of the open nodes, renumbered."""
    size = lvl.size[nodes]
    start = np.concatenate([[0], np.cumsum(size)[:-1]])
    seg_of = np.repeat(np.arange(len(nodes)), size)
    return size, start, seg_of


def _split_costs(lvl: _Level, a: int, seg_of, rank, small, same):
    """Best SAH split of every open node along axis a: (Σ n·area cost, inf where none;
    left count; node box rows (6, m) float32; centroid extent)."""
    m = len(lvl.start)
    c, box = lvl.cent[a], lvl.box[a]
    ext = c[lvl.start + lvl.size - 1] - c[lvl.start]
    if small.all():
        cost, nl, nbox = _sweep(box, seg_of, rank, lvl.size, lvl.start, same)
        return cost, nl, nbox, ext
    if not small.any():
        cost, nl, nbox = _binned(c, box, seg_of, lvl.size, lvl.start)
        return cost, nl, nbox, ext
    cost = np.empty(m)
    nl = np.empty(m, np.int64)
    nbox = np.empty((6, m), np.float32)
    small_el = small[seg_of]
    large = np.flatnonzero(~small)
    el = ~small_el
    size, start, seg = _subset(lvl, large)
    cost[large], nl[large], nbox[:, large] = _binned(c[el], box[:, el], seg, size, start)
    nodes = np.flatnonzero(small)
    size, start, seg = _subset(lvl, nodes)
    same_s = _run_masks(seg, int(size.max()))
    cost[nodes], nl[nodes], nbox[:, nodes] = _sweep(box[:, small_el], seg, rank[small_el], size,
                                                    start, same_s)
    return cost, nl, nbox, ext


def build_bvh(vertices: np.ndarray) -> BVH:
    """vertices: (T,3,3) world-space triangles."""
    v = np.asarray(vertices, dtype=np.float32)
    count = len(v)
    if count == 0:
        return BVH(np.zeros((1, 3), np.float32), np.zeros((1, 3), np.float32),
                   np.zeros(1, np.uint32), np.zeros(1, np.uint32), np.zeros(0, np.int64), 0)
    with np.errstate(invalid="ignore"):
        tri_lo, tri_hi = v.min(axis=1), v.max(axis=1)
    # Degenerate or non-finite triangles can never be hit; they still need a finite box.
    bad = ~(np.isfinite(tri_lo).all(axis=1) & np.isfinite(tri_hi).all(axis=1))
    tri_lo[bad] = 0.0
    tri_hi[bad] = 0.0
    # rows lo, -hi: one min-reduction gives a box; component-major for contiguous rows
    box6 = np.ascontiguousarray(np.concatenate([tri_lo, -tri_hi], axis=1).T)
    cent = (0.5 * tri_lo.astype(np.float64) + 0.5 * tri_hi.astype(np.float64)).T.copy()
    idx_t: type[np.signedinteger] = np.int32 if count < 2**31 else np.int64

    # level-order node records, appended per level
    n_lo: list[np.ndarray] = []
    n_hi: list[np.ndarray] = []
    n_left: list[np.ndarray] = []  # child ids (the right child is left + 1), -1 for leaves
    n_first: list[np.ndarray] = []
    n_count: list[np.ndarray] = []
    order = np.zeros(count, np.int64)
    is_left_tri = np.zeros(count, bool)
    next_id = 1
    depth = 0

    perm: Sequence[np.ndarray] = [np.argsort(cent[a], kind="stable").astype(idx_t)
                                  for a in range(3)]
    lvl = _Level(perm, [np.take(box6, p, axis=1) for p in perm],
                 [cent[a][perm[a]] for a in range(3)],
                 np.zeros(1, np.int64), np.array([count], np.int64), np.zeros(1, np.int64))
    while True:
        m = len(lvl.start)
        n = len(lvl.perm[0])
        seg_of = np.repeat(np.arange(m, dtype=np.int64), lvl.size)
        run_start = np.repeat(lvl.start, lvl.size)
        rank = np.arange(n, dtype=np.int64) - run_start
        small = lvl.size <= BINS
        best_cost = np.full(m, np.inf)
        best_axis = np.zeros(m, np.int64)
        best_nl = lvl.size // 2
        ext = np.zeros((m, 3))
        node_box = None
        # Hillis-Steele masks for the sweeps when all nodes are small
        same = _run_masks(seg_of, int(lvl.size.max())) if small.all() else []
        if depth >= MEDIAN_DEPTH:  # only the node box and the centroid extents
            for a in range(3):
                c = lvl.cent[a]
                ext[:, a] = c[lvl.start + lvl.size - 1] - c[lvl.start]
            node_box = np.minimum.reduceat(lvl.box[0], lvl.start, axis=1)
            per_axis = []
        else:
            per_axis = [_split_costs(lvl, a, seg_of, rank, small, same) for a in range(3)]
        for a, (cost_a, nl_a, box_a, ext_a) in enumerate(per_axis):
            ext[:, a] = ext_a
            if node_box is None:
                node_box = box_a
            better = cost_a < best_cost
            best_cost = np.where(better, cost_a, best_cost)
            best_axis = np.where(better, a, best_axis)
            best_nl = np.where(better, nl_a, best_nl)

        assert node_box is not None  # set above: by the median branch or the first axis
        lo = node_box[:3].T.astype(np.float64)
        hi = -node_box[3:].T.astype(np.float64)
        parent_area = surface_area(lo, hi)
        parent_area[~(parent_area > 0)] = 1.0
        split_cost = TRAVERSAL_COST + best_cost / parent_area
        has_split = np.isfinite(best_cost)
        leaf = (lvl.size == 1) | ((lvl.size <= MAX_LEAF)
                                  & (~has_split | (lvl.size <= split_cost)))
        # no SAH split (deep, or coincident centroids): median of the widest centroid axis
        median = ~leaf & ~has_split
        best_axis = np.where(median, np.argmax(ext, axis=1), best_axis)
        best_nl = np.where(median, lvl.size // 2, best_nl)

        split = np.flatnonzero(~leaf)
        k = len(split)
        left_id = np.full(m, -1, np.int64)
        left_id[split] = next_id + 2 * np.arange(k)
        n_lo.append(lo)
        n_hi.append(hi)
        n_first.append(lvl.gstart)
        n_count.append(np.where(leaf, lvl.size, 0))
        n_left.append(left_id)

        leaf_el = leaf[seg_of]
        if leaf_el.any():
            order[(lvl.gstart[seg_of] + rank)[leaf_el]] = lvl.perm[0][leaf_el]
        if k == 0:
            break

        # which side each triangle of a split node goes to (decided in its split axis' order)
        nl_el = best_nl[seg_of]
        ax_el = best_axis[seg_of]
        for a in range(3):
            sel = (ax_el == a) & ~leaf_el
            is_left_tri[lvl.perm[a][sel]] = rank[sel] < nl_el[sel]

        # the children, left then right, each as a run in every axis' order
        s_size = lvl.size[split]
        s_nl = best_nl[split]
        c_size = np.empty(2 * k, np.int64)
        c_size[0::2] = s_nl
        c_size[1::2] = s_size - s_nl
        c_start = np.concatenate([[0], np.cumsum(c_size)[:-1]])
        c_gstart = np.empty(2 * k, np.int64)
        c_gstart[0::2] = lvl.gstart[split]
        c_gstart[1::2] = lvl.gstart[split] + s_nl
        new_start = np.zeros(m, np.int64)
        new_start[split] = c_start[0::2]
        nl_of = np.zeros(m, np.int64)
        nl_of[split] = s_nl
        keep = np.flatnonzero(~leaf_el)
        base = new_start[seg_of[keep]]
        right_base = base + nl_of[seg_of[keep]]
        rank_keep = rank[keep]
        n_new = len(keep)

        def partition(a: int):
            """Axis a's order of the children: each node's run split stably into the
            triangles going left, then those going right."""
            p = lvl.perm[a][keep]
            left = is_left_tri[p]
            lefts_before = np.cumsum(left) - left  # exclusive count over the kept elements
            lefts_in_run = lefts_before - lefts_before[base]  # base: the run's first slot
            dest = np.where(left, base + lefts_in_run, right_base + (rank_keep - lefts_in_run))
            src = np.empty(n_new, np.int64)
            src[dest] = keep
            return lvl.perm[a][src], np.take(lvl.box[a], src, axis=1), lvl.cent[a][src]

        perm, box, cent_s = zip(*(partition(a) for a in range(3)))
        lvl = _Level(list(perm), list(box), list(cent_s), c_start, c_size, c_gstart)
        next_id += 2 * k
        depth += 1
    max_depth = depth

    # depth-first renumbering: subtree sizes bottom-up, then positions top-down
    lo_all = np.concatenate(n_lo)
    hi_all = np.concatenate(n_hi)
    left_all = np.concatenate(n_left)
    first_all = np.concatenate(n_first)
    count_all = np.concatenate(n_count)
    total = len(left_all)
    bounds = np.concatenate([[0], np.cumsum([len(x) for x in n_left])])
    size = np.ones(total, np.int64)
    for i in range(len(n_left) - 1, -1, -1):
        ids = np.arange(bounds[i], bounds[i + 1])
        ids = ids[left_all[ids] >= 0]
        size[ids] += size[left_all[ids]] + size[left_all[ids] + 1]
    pos = np.zeros(total, np.int64)
    for i in range(len(n_left) - 1):
        ids = np.arange(bounds[i], bounds[i + 1])
        ids = ids[left_all[ids] >= 0]
        lc = left_all[ids]
        pos[lc] = pos[ids] + 1
        pos[lc + 1] = pos[ids] + 1 + size[lc]
    inner = left_all >= 0
    link = first_all.copy()
    link[inner] = pos[left_all[inner] + 1]

    lo = np.empty_like(lo_all)
    hi = np.empty_like(hi_all)
    lo[pos] = lo_all
    hi[pos] = hi_all
    right_or_first = np.empty(total, np.uint32)
    right_or_first[pos] = link
    cnt = np.empty(total, np.uint32)
    cnt[pos] = count_all
    pad = BOX_PAD * ((hi - lo).max(axis=1, keepdims=True) + np.maximum(np.abs(lo), np.abs(hi)))
    with np.errstate(over="ignore"):  # a bound near ±FLT_MAX padded past it is ±inf
        lo, hi = (lo - pad).astype(np.float32), (hi + pad).astype(np.float32)
    return BVH(
        lo=lo,
        hi=hi,
        right_or_first=right_or_first,
        count=cnt,
        order=order,
        depth=max_depth,
    )
