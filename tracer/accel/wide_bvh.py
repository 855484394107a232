"""The BVH's layout for the traversal: the binary tree (bvh.py) collapsed to WIDTH children per
node, each node one 64-byte record of its children's boxes quantised to 8 bits against the
node's box (with the folded test's margin), and child references packing a leaf's first
triangle and count."""
from __future__ import annotations

import numpy as np

from ..kernel.backend import aligned_zeros
from .bvh import BVH, STACK_SIZE, surface_area
from .memo import kept

LEAF_SHIFT = 27  # child references: inner node index, or (count << LEAF_SHIFT) | first triangle
WIDTH = 4  # children per node of the traversal's wide tree
# pushes per wide level x its levels: a wide level spans at least one binary level
WIDE_STACK_SIZE = (WIDTH - 1) * STACK_SIZE
NO_CHILD = 0xFFFFFFFF  # an empty child slot's reference


def _wide_children(bvh: BVH) -> tuple[np.ndarray, np.ndarray]:
    """The binary tree collapsed to WIDTH children per node, greedily by surface area (as
    Embree's and pbrt's wide BVHs are): a wide node starts with its binary node's two
    children, and while it has a free slot its inner child of the largest surface area is
    replaced by that child's two children. Returns (the binary inner nodes that are wide
    nodes, in binary depth-first order; their child slots (I, WIDTH), binary node ids, -1
    where empty, in left-to-right order of the binary tree)."""
    count = bvh.count
    link = bvh.right_or_first.astype(np.int64)
    area = surface_area(bvh.lo.astype(np.float64), bvh.hi.astype(np.float64))
    roots, slots_all = [], []
    frontier = np.zeros(1, np.int64)
    while len(frontier):
        m = len(frontier)
        slots = np.full((m, WIDTH), -1, np.int64)
        slots[:, 0], slots[:, 1] = frontier + 1, link[frontier]
        for filled in range(2, WIDTH):
            valid = slots >= 0
            node = np.where(valid, slots, 0)
            score = np.where(valid & (count[node] == 0), area[node], -1.0)
            j = np.argmax(score, axis=1)
            rows = np.flatnonzero(score[np.arange(m), j] >= 0.0)
            if not len(rows):
                break
            jj, parent = j[rows], slots[rows, j[rows]]
            # keep the binary tree's left-to-right order: shift the slots after j right
            for k in range(filled, 0, -1):
                move = jj < k
                slots[rows[move], k] = slots[rows[move], k - 1]
            slots[rows, jj] = parent + 1
            slots[rows, jj + 1] = link[parent]
        roots.append(frontier)
        slots_all.append(slots)
        kids = slots[slots >= 0]
        frontier = kids[count[kids] == 0]
    roots_a, slots_a = np.concatenate(roots), np.concatenate(slots_all)
    order = np.argsort(roots_a, kind="stable")  # binary ids are depth-first positions
    return roots_a[order], slots_a[order]


QUANT_LEVELS = 255  # a child's bounds are whole 8-bit steps of its wide node's box
FOLD_MARGIN = 8 * 2.0**-24  # child boxes widened by this share of their node's size
SCALE_ROUNDS = 300  # doubling steps from one ulp cover any shortfall of finite bounds
# Layout of a wide node's 16-float record (one 16-float packet gather, two 8-wide loads)
REC_ORIGIN, REC_SCALE, REC_Q_LO, REC_Q_HI, REC_REFS = 0, 3, 6, 9, 12
RECORD_FLOATS = 16
INTEGER_SLOTS = tuple(range(REC_Q_LO, RECORD_FLOATS))  # uint32 bits in float slots


def dequantized(origin, scale, q, dtype) -> np.ndarray:
    """origin + q·scale in `dtype`, rounded after the product and after the sum: a child's
    bound as a record gives it, in plain float arithmetic. (The traversal evaluates it folded
    into the slab test, wide_traversal.WideNodes.open, with a rounding of its own that
    _fold_margin covers.)"""
    return (origin.astype(dtype) + q.astype(dtype) * scale.astype(dtype)).astype(dtype)


def _fold_margin(lo: np.ndarray, hi: np.ndarray, valid: np.ndarray):
    """The child boxes (I, WIDTH, 3) widened on each side by FOLD_MARGIN of their node's
    extent and coordinate size per axis, rounded outward to float32.

    The traversal tests a child bound in a folded form, t = fma(q, scale·inv_d,
    (origin - o)·inv_d) (wide_traversal.WideNodes.open), which is off from the exact
    (origin + q·scale - o)·inv_d by at most 3.0001·2^-24·(q·scale·|inv_d| + |t|) (three
    roundings, |origin - o| <= |origin + q·scale - o| + q·scale). The |t| part is relative,
    which the slab test's BOX_SLACK covers, as it covers the unfolded form's; the q·scale part
    is up to 3.0001·2^-24 of the node's grid extent, the children's extent plus these margins
    plus a few ulps of its coordinates that rounding origin and scale can add: this margin,
    8·2^-24·(extent + 2^-20·coordinate size), is more than that."""
    lo64, hi64 = lo.astype(np.float64), hi.astype(np.float64)
    node_lo = np.where(valid[..., None], lo64, np.inf).min(axis=1, keepdims=True)
    node_hi = np.where(valid[..., None], hi64, -np.inf).max(axis=1, keepdims=True)
    size = np.maximum(np.abs(node_lo), np.abs(node_hi))
    with np.errstate(invalid="ignore", over="ignore"):  # nodes without children: NaN, unused
        margin = FOLD_MARGIN * ((node_hi - node_lo) + 2.0**-20 * size)
        wide_lo, wide_hi = lo64 - margin, hi64 + margin
        lo32, hi32 = wide_lo.astype(np.float32), wide_hi.astype(np.float32)
        lo32 = np.where(lo32 > wide_lo, np.nextafter(lo32, np.float32(-np.inf)), lo32)
        hi32 = np.where(hi32 < wide_hi, np.nextafter(hi32, np.float32(np.inf)), hi32)
    return np.where(valid[..., None], lo32, lo), np.where(valid[..., None], hi32, hi)


def _quantize(lo: np.ndarray, hi: np.ndarray, valid: np.ndarray):
    """8-bit child bounds of the wide nodes, children (I, WIDTH, 3) where `valid`: (origin
    (I,3), scale (I,3) float32, q_lo, q_hi (I, WIDTH, 3)). Every dequantized bound lies on or
    outside its (already padded) child box in float32 and in float64 arithmetic alike, so
    that the slab test on it is conservative whatever the render precision: a step outward
    wherever rounding would land inside, and the node's whole box (0, 255) where that is not
    enough, which origin + 255·scale >= every hi makes safe. The boxes are first widened by
    _fold_margin, for the traversal's folded form of the test. Bounds are clipped to
    ±FLT_MAX: the padding of a vertex within 1e-5 of float32's range overflows to ±inf, which
    no finite origin and scale reach, and every finite vertex is still inside."""
    big = np.float32(np.finfo(np.float32).max)
    lo, hi = _fold_margin(np.clip(lo, -big, big), np.clip(hi, -big, big), valid)
    lo, hi = np.clip(lo, -big, big), np.clip(hi, -big, big)
    origin = np.where(valid[..., None], lo, big).min(axis=1)
    top = np.where(valid[..., None], hi, -big).max(axis=1)
    scale = ((top.astype(np.float64) - origin) / QUANT_LEVELS).astype(np.float32)
    full = np.full(scale.shape, QUANT_LEVELS)

    def reaches(q, bound, outward: int) -> np.ndarray:
        ok = np.ones(bound.shape, bool)
        for dtype in (np.float32, np.float64):
            with np.errstate(over="ignore", invalid="ignore"):
                v = dequantized(origin[:, None], scale[:, None], q, dtype)
            ok &= (v <= bound) if outward < 0 else (v >= bound)
        return ok

    # origin + 255·scale must reach top: where rounding leaves it short (by a few ulps of top,
    # which can be many ulps of scale), scale grows by a step that doubles each round
    grow = np.zeros(scale.shape)
    for _ in range(SCALE_ROUNDS):
        short = ~reaches(full[:, None], top[:, None], +1)[:, 0]
        if not short.any():
            break
        grow = np.where(short, np.maximum(2.0 * grow, np.spacing(scale).astype(np.float64)), 0.0)
        scale = np.where(short, (scale + grow).astype(np.float32), scale)
    else:
        raise ValueError("BVH node bounds could not be quantized")  # finite bounds always are
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        rel_lo = (lo.astype(np.float64) - origin[:, None]) / scale[:, None]
        rel_hi = (hi.astype(np.float64) - origin[:, None]) / scale[:, None]
    q_lo = np.clip(np.nan_to_num(np.floor(rel_lo), nan=0.0), 0, QUANT_LEVELS)
    q_hi = np.clip(np.nan_to_num(np.ceil(rel_hi), nan=QUANT_LEVELS), 0, QUANT_LEVELS)
    for _ in range(2):
        q_lo = np.where(reaches(q_lo, lo, -1), q_lo, np.maximum(q_lo - 1, 0))
        q_hi = np.where(reaches(q_hi, hi, +1), q_hi, np.minimum(q_hi + 1, QUANT_LEVELS))
    q_lo = np.where(reaches(q_lo, lo, -1), q_lo, 0)
    q_hi = np.where(reaches(q_hi, hi, +1), q_hi, QUANT_LEVELS)
    return origin, scale, q_lo.astype(np.uint32), q_hi.astype(np.uint32)


@kept(4)  # of the BVHs the search's renders share (memo.py)
def wide_records(bvh: BVH) -> tuple[np.ndarray, int]:
    """The tree collapsed to WIDTH = 4 children per node (_wide_children), as 64-byte records
    for traversal with Dr.Jit packet gathers (one node visit tests 4 boxes, one 16-float
    load), child boxes quantized to 8 bits of their node's box (_quantize) as Embree's
    compressed wide nodes are: half the bytes of float boxes, and half the packet loads a
    visit costs (measured 4-7% less time on primary rays, the boxes a little larger).

    Returns (records (I, 16) float32, 64-byte aligned, root reference); wide nodes are
    numbered 0..I-1 in the binary depth-first order. Record i is [origin xyz, scale xyz,
    q_lo words xyz, q_hi words xyz, ref ×4]: child k's box along axis a is origin + q·scale
    with q byte k of that axis' word; a reference (uint32 bits in the float slot, like the
    words) is a wide node number, ``(count << LEAF_SHIFT) | first`` for a leaf, or NO_CHILD
    for an empty slot (q_lo 255 and q_hi 0; the traversal skips it by its reference, since
    the slab test orders each axis' two bounds). A tree whose root is a leaf has no records
    (one zero record is returned) and a leaf root reference.
    """
    if len(bvh.order) >= 1 << LEAF_SHIFT or (bvh.count >> (32 - LEAF_SHIFT)).any():
        raise ValueError("too many triangles (or too large a leaf) for child references")
    count = bvh.count.astype(np.uint32)
    link = bvh.right_or_first.astype(np.int64)
    leaf = count > 0
    ref = np.full(bvh.node_count, NO_CHILD, np.uint32)
    ref[leaf] = (count[leaf] << np.uint32(LEAF_SHIFT)) | link[leaf].astype(np.uint32)
    if leaf[0]:
        return aligned_zeros((1, RECORD_FLOATS), np.float32), int(ref[0])
    wide, slots = _wide_children(bvh)
    ref[wide] = np.arange(len(wide), dtype=np.uint32)
    valid = slots >= 0
    node = np.where(valid, slots, 0)
    origin, scale, q_lo, q_hi = _quantize(bvh.lo[node], bvh.hi[node], valid)
    q_lo = np.where(valid[..., None], q_lo, np.uint32(QUANT_LEVELS))
    q_hi = np.where(valid[..., None], q_hi, np.uint32(0))
    shift = (np.arange(WIDTH, dtype=np.uint32) * 8)[None, :, None]
    rec = aligned_zeros((len(wide), RECORD_FLOATS), np.float32)
    rec[:, REC_ORIGIN:REC_ORIGIN + 3], rec[:, REC_SCALE:REC_SCALE + 3] = origin, scale
    rec[:, REC_Q_LO:REC_Q_LO + 3] = np.bitwise_or.reduce(q_lo << shift, axis=1).view(np.float32)
    rec[:, REC_Q_HI:REC_Q_HI + 3] = np.bitwise_or.reduce(q_hi << shift, axis=1).view(np.float32)
    rec[:, REC_REFS:REC_REFS + WIDTH] = np.where(valid, ref[node],
                                                 np.uint32(NO_CHILD)).view(np.float32)
    return rec, int(ref[0])
