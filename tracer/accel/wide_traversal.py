"""The wide BVH's nodes on the device (wide_bvh.wide_records) and the box tests a traversal
makes with them: the root's slab test, opening a node (its four children's folded,
dequantized slab tests, near to far), and decoding child references; and the traversal loop,
which interleaves these with a TriangleSet's triangle tests (traverse)."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..kernel.backend import import_drjit, syntax_on_first_call
from ..kernel.lane_stack import LaneStack
from ..kernel.vecmath import Types, float_bits, gather_packet
from .flat_scene import NO_INSTANCE
from .wide_bvh import (
    LEAF_SHIFT,
    NO_CHILD,
    REC_ORIGIN,
    REC_Q_HI,
    REC_Q_LO,
    REC_REFS,
    REC_SCALE,
    RECORD_FLOATS,
    WIDE_STACK_SIZE,
    WIDTH,
)

NO_NODE = NO_CHILD  # no node to open (an empty child slot, a missed child, an empty stack)
BOX_SLACK = 1.0 + 1e-6  # relative widening of box intervals against rounding in the slab test
FOLD_LIMIT = 1e37  # bound on |t| terms of the folded box test (fold_inverse); float32 max 3.4e38


if TYPE_CHECKING:
    from .triangle_search import TriangleSearch
    from .triangles import TriangleSet

class WideNodes:
    def __init__(self, types: Types, records, root_ref: int, root_lo: list[float],
                 root_hi: list[float]) -> None:
        self.T = types
        self.dr = import_drjit()
        self.records = records  # the nodes' 64-byte records, aligned, in the render precision
        self.root_ref = root_ref
        self.root_lo, self.root_hi = root_lo, root_hi
        # One fixed size for every scene: with per-scene sizes (depth + 1), rays in one
        # process missed hits after scenes with shallower trees had been traced (a reused
        # kernel with a smaller stack is suspected; not reproduced in isolation).
        self.stack_size = WIDE_STACK_SIZE

    def slab(self, lo, hi, o, inv_d, limit):
        """Slab test of a padded box. The slack keeps it conservative under rounding.

        A ray lying in a slab plane gets t = 0·inf = NaN there; such an axis must not make the
        box missed. The minima and maxima are selects, `a < b ? a : b`, which compile to one
        x86 min/max instruction each (fmin/fmax's NaN rules took three) and give the second
        operand when either is NaN: each axis' near and far, and the running t_near and t_far
        with their axes as first operands, so that a NaN near or far value drops out (an
        axis without a bound: as permissive as fmin/fmax or more, never less)."""
        return self.slab_t((lo - o) * inv_d, (hi - o) * inv_d, limit)

    def slab_t(self, t0, t1, limit):
        """slab on the boxes' plane distances t0 (lo) and t1 (hi) per axis."""
        dr = self.dr
        near = dr.select(t0 < t1, t0, t1)
        far = dr.select(t0 > t1, t0, t1)

        def max_drop_nan(a, b):
            return dr.select(a > b, a, b)

        def min_drop_nan(a, b):
            return dr.select(a < b, a, b)

        t_near = max_drop_nan(near.x, max_drop_nan(near.y, max_drop_nan(near.z, 0.0)))
        t_far = min_drop_nan(far.x, min_drop_nan(far.y, min_drop_nan(far.z, dr.inf)))
        return (t_near <= t_far * BOX_SLACK) & (t_near <= limit * BOX_SLACK), t_near

    def open(self, node, o, inv_fold, limit, memory, stack: LaneStack, nearest_first: bool):
        """Opens wide node `node` (in a symbolic branch, which masks the pushes): slab tests
        of its WIDTH child boxes (one 16-float packet load of the record, the 8-bit bounds
        dequantized: wide_bvh.wide_records); one child hit goes on, the other hits are pushed.
        nearest_first (closest hit): the hits are sorted near to far, the
        nearest goes on and the others are pushed far first; without it (any hit, where the
        order does not change the answer and sorting measured ~10% slower) the last hit in
        slot order goes on. No distance is pushed: a popped inner node the closest hit has
        since moved past is opened, and its children, inside its box, fail the slab test
        against the new limit in the iteration a distance check would have spent; a popped
        leaf's triangles are tested, one an iteration, and fail the closer test. That costs
        less than a second per-lane stack did (5-15% of primary-ray time, measured).
        A bound's t is fma(q, scale·inv_d, (origin - o)·inv_d), 2 operations a bound where
        (origin + q·scale - o)·inv_d takes 5 (primary rays ~15% faster), whose rounding
        wide_bvh._fold_margin covers; inv_fold is inv_d where that cannot overflow
        (fold_inverse), else NaN, which drops the axis from the test.
        Returns that child's reference or NO_NODE."""
        dr, T = self.dr, self.T
        A3 = T.Array3f
        rec = gather_packet(T, self.records, RECORD_FLOATS, node)
        origin = [rec[REC_ORIGIN + a] for a in range(3)]
        scale = [rec[REC_SCALE + a] for a in range(3)]
        q_lo = [float_bits(T, rec[REC_Q_LO + a]) for a in range(3)]
        q_hi = [float_bits(T, rec[REC_Q_HI + a]) for a in range(3)]

        refs = [float_bits(T, rec[REC_REFS + k]) for k in range(WIDTH)]

        def byte(word, k):
            return T.Float(word >> (8 * k) if k == WIDTH - 1 else (word >> (8 * k)) & 0xFF)

        step = A3(*(scale[a] * inv_fold[a] for a in range(3)))
        base = A3(*((origin[a] - o[a]) * inv_fold[a] for a in range(3)))

        def t(word, k):
            return dr.fma(A3(*(byte(word[a], k) for a in range(3))), step, base)

        kids = []
        tests = [self.slab_t(t(q_lo, k), t(q_hi, k), limit) for k in range(WIDTH)]
        for (hit, near), ref in zip(tests, refs):
            hit &= ref != NO_NODE
            kids.append((dr.select(hit, near, dr.inf), dr.select(hit, ref, NO_NODE)))
        if not nearest_first:
            nxt = kids[0][1]
            for _, ref in kids[1:]:
                stack.push(dr, memory, nxt, (ref != NO_NODE) & (nxt != NO_NODE))
                nxt = dr.select(ref != NO_NODE, ref, nxt)
            return nxt
        # a sorting network on near t; misses (t = inf) go last
        for a, b in ((0, 1), (2, 3), (0, 2), (1, 3), (1, 2)):
            swap = kids[b][0] < kids[a][0]
            (ta, ra), (tb, rb) = kids[a], kids[b]
            kids[a] = (dr.select(swap, tb, ta), dr.select(swap, rb, ra))
            kids[b] = (dr.select(swap, ta, tb), dr.select(swap, ra, rb))
        for _, ref in reversed(kids[1:]):
            stack.push(dr, memory, ref, ref != NO_NODE)
        return kids[0][1]

    def fold_inverse(self, o, inv_d):
        """inv_d for the folded box tests (open), NaN on the axes where they could overflow.
        There every |q·scale·inv_d| and |(origin - o)·inv_d| is below 2.01·R·|inv_d| and
        1.01·(R + |o|)·|inv_d|, R the largest root-box coordinate, and (4R + 2|o|)·|inv_d|
        under FOLD_LIMIT leaves room for their sum. NaN drops the axis from the slab test
        (slab): permissive, so a ray with a huge finite 1/d (a direction nearly in a
        coordinate plane, or triangles beyond ~1e36) tests the boxes on its other axes only.
        An infinite inv_d (a zero component) is kept: where the ray lies in a child's slab,
        origin - o <= 0 <= q·scale makes every folded bound of that axis NaN (inf - inf or
        0·inf), so the axis drops out as it must; outside it, any answer is safe."""
        dr = self.dr
        size = float(max(np.abs(self.root_lo).max(), np.abs(self.root_hi).max()))
        out = []
        for c, oc in zip(inv_d, o):
            safe = dr.isinf(c) | (dr.abs(c) * (4.0 * size + 2.0 * dr.abs(oc)) < FOLD_LIMIT)
            out.append(dr.select(safe, c, dr.nan))
        return self.T.Array3f(*out)

    def decode(self, ref):
        """A child reference as (inner node or NO_NODE, first triangle, triangle end)."""
        dr, UInt32 = self.dr, self.T.UInt32
        count = ref >> LEAF_SHIFT
        leaf = (count != 0) & (ref != NO_NODE)
        first = dr.select(leaf, ref & ((1 << LEAF_SHIFT) - 1), 0)
        node = dr.select(leaf, NO_NODE, ref)
        return node, first, first + dr.select(leaf, count, UInt32(0))


@syntax_on_first_call
def traverse(tris: TriangleSet, o, d, state: TriangleSearch, any_hit_limit, active_lanes=None,
             skip_mesh=None) -> TriangleSearch:
    """Closest hit among `tris` through their BVH: one loop that tests leaf triangles one per
    iteration and between them pops the per-lane stack and opens wide inner nodes, whose
    records hold their children's boxes (WideNodes.open: one child goes on, the others are
    pushed; a leaf child's triangles become the pending ones). With any_hit_limit, stops at
    the first accepted hit with t <= limit.
    With one instance, the whole search is in its space (one_instance); with more, the
    ray in the instance of the last triangle tested is kept, and moved into another only
    when the next triangle is in another (leaves are mostly one instance's)."""
    # No dataclass locals here (such as tris.T): @dr.syntax would treat them as loop state.
    dr = tris.dr
    UInt32, Bool, A3 = tris.T.UInt32, tris.T.Bool, tris.T.Array3f
    width = dr.width(o)
    per_triangle_instance = tris.levels > 0 and tris.one_instance == NO_INSTANCE
    o, d = tris._in_one_instance(o, d)  # with one instance, the BVH is in its space
    nodes = tris.nodes
    memory = dr.alloc_local(UInt32, nodes.stack_size)
    inv_d = 1.0 / d
    inv_fold = nodes.fold_inverse(o, inv_d)
    stack = LaneStack.empty(dr, UInt32, width)
    limit = state.t if any_hit_limit is None else dr.minimum(state.t, any_hit_limit)
    root_hit, _ = nodes.slab(A3(*nodes.root_lo), A3(*nodes.root_hi), o, inv_d, limit)
    if active_lanes is not None:
        root_hit &= active_lanes
    node, tri, tri_end = nodes.decode(dr.select(root_hit, UInt32(nodes.root_ref), NO_NODE))
    done = dr.full(Bool, False, width)
    active = root_hit
    cur_inst = dr.full(UInt32, NO_INSTANCE, width)  # the instance (oi, di) is in
    oi, di = A3(o), A3(d)
    # Each iteration has three steps, each for the lanes that need it (Dr.Jit skips a
    # step no lane of a packet needs): test one pending leaf triangle; with none pending
    # and no node, pop the stack; open the current inner node.
    while active:
        if tri < tri_end:
            if per_triangle_instance:
                inst = dr.gather(UInt32, tris.tinstance, tri)
                if inst != cur_inst:
                    oi, di = tris.into_instance(inst, o, d)
                    cur_inst = UInt32(inst)
            t, u, v, ok = tris._triangle(tri, oi, di, skip_mesh, moved=True)
            if any_hit_limit is not None:
                ok &= t <= any_hit_limit
            state.offer(dr, ok, t, tri, u, v, tris.torder)
            tri += 1
            if any_hit_limit is not None:
                done |= ok
        if (tri >= tri_end) & (node == NO_NODE) & stack.nonempty() & ~done:
            ref = stack.pop(dr, memory)
            node, tri, tri_end = nodes.decode(ref)
        if (node != NO_NODE) & ~done:
            limit = state.t if any_hit_limit is None else dr.minimum(state.t, any_hit_limit)
            nxt = nodes.open(node, o, inv_fold, limit, memory, stack,
                             nearest_first=any_hit_limit is None)
            node, tri, tri_end = nodes.decode(nxt)
        active = ~done & ((tri < tri_end) | (node != NO_NODE) | stack.nonempty())
    return state
