"""Structural invariants of the vectorised BVH build on random and degenerate inputs, and the
BVH's hits against brute force on a mid-sized mesh."""
from __future__ import annotations

import numpy as np
import pytest
from test_bvh import soup

from raycheck.tracer.accel.bvh import MAX_LEAF, MEDIAN_DEPTH, STACK_SIZE, build_bvh
from raycheck.tracer.accel.intersect import FLT_MAX, Intersector
from raycheck.tracer.accel.wide_bvh import (
    FOLD_MARGIN,
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
    _wide_children,
    dequantized,
    wide_records,
)
from raycheck.tracer.kernel.vecmath import make_types


def check_tree(v: np.ndarray, bvh) -> None:
    """Every invariant the traversal relies on."""
    t = len(v)
    n = bvh.node_count
    lo, hi, link, count = bvh.lo, bvh.hi, bvh.right_or_first.astype(np.int64), bvh.count
    assert lo.shape == hi.shape == (n, 3) and lo.dtype == hi.dtype == np.float32
    assert link.shape == count.shape == (n,)
    assert bvh.right_or_first.dtype == bvh.count.dtype == np.uint32
    assert np.isfinite(lo).all() and np.isfinite(hi).all() and (lo <= hi).all()
    # the order is a permutation, and the leaves tile it left to right in depth-first order
    assert np.array_equal(np.sort(bvh.order), np.arange(t))
    leaves = np.flatnonzero(count > 0)
    assert count[leaves].sum() == t
    assert np.array_equal(link[leaves], np.concatenate([[0], np.cumsum(count[leaves])[:-1]]))
    assert (count <= max(MAX_LEAF, 1)).all() or t <= 1
    # walk the tree from the root: depth-first layout, every node reached once, depth bound
    seen = np.zeros(n, int)
    stack = [(0, 0)]
    depth = 0
    while stack:
        node, d = stack.pop()
        seen[node] += 1
        depth = max(depth, d)
        if count[node] == 0:
            left, right = node + 1, int(link[node])
            assert left < right < n
            for child in (left, right):
                # children's boxes lie inside the parent's (after padding)
                assert (lo[child] >= lo[node]).all() and (hi[child] <= hi[node]).all()
                stack.append((child, d + 1))
    assert (seen == 1).all()
    assert depth == bvh.depth < STACK_SIZE
    # every finite triangle lies inside its leaf's box
    leaf_of = np.repeat(leaves, count[leaves])
    tri = v[bvh.order].astype(np.float64)
    finite = np.isfinite(tri).all(axis=(1, 2))
    tl, th = lo[leaf_of][finite, None, :], hi[leaf_of][finite, None, :]
    assert (tri[finite] >= tl).all() and (tri[finite] <= th).all()


def test_random_soups_of_many_sizes():
    rng = np.random.default_rng(10)
    for n in (1, 2, 3, 7, 8, 9, 16, 17, 33, 100, 1000, 20000):
        c = rng.uniform(-5, 5, (n, 1, 3))
        v = (c + rng.normal(0, 0.3, (n, 3, 3))).astype(np.float32)
        check_tree(v, build_bvh(v))


def test_clustered_and_skewed_input():
    rng = np.random.default_rng(11)
    # a dense cluster plus far outliers and sliver triangles along one axis
    v = np.concatenate([rng.normal(0, 1e-3, (3000, 3, 3)), rng.uniform(-1e3, 1e3, (50, 3, 3)),
                        np.repeat(rng.uniform(0, 100, (500, 1, 1)), 9, axis=2).reshape(500, 3, 3)
                        * np.array([1.0, 0.0, 0.0]) + rng.normal(0, 1e-2, (500, 3, 3))])
    v = v.astype(np.float32)
    check_tree(v, build_bvh(v))


def test_all_triangles_identical():
    v = np.tile(np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32), (5000, 1, 1))
    bvh = build_bvh(v)
    check_tree(v, bvh)
    assert bvh.depth <= 14  # median splits: about log2(5000 / MAX_LEAF) + 1


def test_all_in_one_plane():
    rng = np.random.default_rng(12)
    v = rng.uniform(-1, 1, (4000, 3, 3)).astype(np.float32)
    v[:, :, 2] = 0.5
    check_tree(v, build_bvh(v))


def test_collinear_triangles():
    rng = np.random.default_rng(13)
    x = rng.uniform(-10, 10, (3000, 3, 1))
    v = (x * np.array([1.0, 2.0, -1.0])).astype(np.float32)  # all vertices on one line
    check_tree(v, build_bvh(v))


def test_zero_area_points():
    v = np.zeros((2000, 3, 3), np.float32)
    v[:, :, 0] = np.arange(2000)[:, None] % 7
    check_tree(v, build_bvh(v))


@pytest.mark.parametrize("scale", [1e7, 1e-7, 1e30])
def test_extreme_coordinates(scale: float):
    rng = np.random.default_rng(14)
    v = (rng.uniform(-1, 1, (3000, 3, 3)) * scale).astype(np.float32)
    v[:1000] += np.float32(scale)  # offset clusters: large magnitude, small relative extent
    check_tree(v, build_bvh(v))


def test_non_finite_vertices():
    rng = np.random.default_rng(15)
    v = rng.uniform(-1, 1, (3000, 3, 3)).astype(np.float32)
    v[::7, 1, 0] = np.nan
    v[::11, 2, 2] = np.inf
    v[::13, 0, 1] = -np.inf
    bvh = build_bvh(v)
    check_tree(v, bvh)
    # all NaN
    v = np.full((100, 3, 3), np.nan, np.float32)
    check_tree(v, build_bvh(v))


def test_deep_degenerate_chain_stays_below_the_stack():
    # slivers at exponentially spaced x (each about 110 times): SAH peels one value per level
    # and reaches the median-split depth
    x = 1.6 ** (np.arange(20000.0) % 180)
    v = np.zeros((20000, 3, 3), np.float32)
    v[:, :, 0] = x[:, None] + np.array([0, 1e-3, 0])
    v[:, 2, 1] = 1e-3
    bvh = build_bvh(v)
    check_tree(v, bvh)
    assert bvh.depth > MEDIAN_DEPTH


def test_input_dtype_and_layout():
    rng = np.random.default_rng(16)
    v = rng.uniform(-1, 1, (500, 3, 3))
    a = build_bvh(v)  # float64 input: the same tree as its float32 rounding
    b = build_bvh(v.astype(np.float32))
    assert np.array_equal(a.order, b.order) and np.array_equal(a.lo, b.lo)
    c = build_bvh(np.asfortranarray(v.astype(np.float32)))
    assert np.array_equal(b.order, c.order) and np.array_equal(b.count, c.count)


def test_bvh_equals_brute_force_on_a_5k_mesh():
    # a bumpy closed surface (shared vertices) plus random rays from inside and outside
    k = 50
    th = np.linspace(0, np.pi, k + 1)
    ph = np.linspace(0, 2 * np.pi, k, endpoint=False)
    t, p = np.meshgrid(th, ph, indexing="ij")
    r = 1 + 0.1 * np.sin(5 * t) * np.cos(4 * p)
    pos = np.stack([r * np.sin(t) * np.cos(p), r * np.sin(t) * np.sin(p), r * np.cos(t)], -1)
    pos = pos.reshape(-1, 3)
    i, j = np.arange(k)[:, None], np.arange(k)[None, :]
    a, b = i * k + j, i * k + (j + 1) % k
    faces = np.concatenate([np.stack([a, a + k, b + k], -1).reshape(-1, 3),
                            np.stack([a, b + k, b], -1).reshape(-1, 3)])
    v = pos[faces].astype(np.float32)
    assert len(v) == 5000
    rng = np.random.default_rng(17)
    o = np.concatenate([rng.uniform(-3, 3, (3000, 3)), rng.normal(0, 0.3, (1000, 3))])
    d = np.concatenate([rng.uniform(-0.6, 0.6, (3000, 3)) - o[:3000],
                        rng.normal(0, 1, (1000, 3))])
    o, d = o.astype(np.float32), d.astype(np.float32)
    check_tree(v, build_bvh(v))
    T = make_types()
    results = []
    for accel in ("bvh", "brute"):
        isect = Intersector(soup(v), T, accel)
        hit = isect.closest(T.Array3f(o.T), T.Array3f(d.T))
        dist = T.Float(np.full(4000, 1.5, np.float32))
        blocked = isect.occluded(T.Array3f(o.T), T.Array3f(d.T), dist)
        isect.dr.eval(hit.t, hit.order, hit.normal, blocked)
        results.append((hit.t.numpy(), hit.order.numpy(), np.asarray(hit.normal.numpy()),
                        blocked.numpy()))
    (tb, ob, nb, sb), (tf, of, nf, sf) = results
    assert np.mean(tb < FLT_MAX) > 0.5
    assert np.array_equal(tb, tf)
    assert np.array_equal(ob, of)
    assert np.array_equal(nb, nf, equal_nan=True)
    assert np.array_equal(sb, sf)


def _leaves_below(bvh, node: int) -> list[tuple[int, int]]:
    """The (first, count) of every leaf under a binary node, left to right."""
    if bvh.count[node]:
        return [(int(bvh.right_or_first[node]), int(bvh.count[node]))]
    return _leaves_below(bvh, node + 1) + _leaves_below(bvh, int(bvh.right_or_first[node]))


def _record_boxes(rec: np.ndarray, dtype) -> tuple[np.ndarray, np.ndarray]:
    """The child boxes (I, WIDTH, 3) lo and hi a traversal in `dtype` computes from records."""
    words = rec[:, REC_Q_LO:REC_Q_HI + 3].view(np.uint32)
    q = (words[:, None, :] >> (np.arange(WIDTH, dtype=np.uint32) * 8)[None, :, None]) & 0xFF
    origin = rec[:, None, REC_ORIGIN:REC_ORIGIN + 3]
    scale = rec[:, None, REC_SCALE:REC_SCALE + 3]
    with np.errstate(over="ignore"):  # near ±FLT_MAX, q·scale may be ±inf, as in the kernel
        return (dequantized(origin, scale, q[..., :3], dtype),
                dequantized(origin, scale, q[..., 3:], dtype))


@pytest.mark.parametrize("n", [1, 2, 3, 700])
def test_wide_records_collapse_the_binary_tree_greedily_by_area(n: int):
    rng = np.random.default_rng(18)
    v = rng.uniform(-1, 1, (n, 3, 3)).astype(np.float32)
    bvh = build_bvh(v)
    rec, root = wide_records(bvh)
    assert rec.shape[1] == RECORD_FLOATS == 16 and rec.dtype == np.float32
    assert rec.ctypes.data % 64 == 0  # Dr.Jit packet gathers need 64-byte aligned memory
    refs = rec[:, REC_REFS:REC_REFS + WIDTH].view(np.uint32)

    def leaves(ref: int) -> list[tuple[int, int]]:
        """The leaves a reference covers, walking the wide records."""
        if ref >> LEAF_SHIFT:
            return [(ref & ((1 << LEAF_SHIFT) - 1), ref >> LEAF_SHIFT)]
        out = []
        for k in range(WIDTH):
            if refs[ref, k] != NO_CHILD:
                out += leaves(int(refs[ref, k]))
        return out

    # the wide tree reaches the same leaves in the same order as the binary tree
    assert leaves(root) == _leaves_below(bvh, 0)
    if bvh.count[0]:  # a leaf root: no records to read
        return
    inner = np.flatnonzero(bvh.count == 0)
    assert len(rec) < len(inner) or len(inner) == 1  # fewer nodes than the binary tree

    def area(node: int) -> float:
        e = np.maximum(bvh.hi[node].astype(np.float64) - bvh.lo[node], 0.0)
        return 2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])

    def greedy_slots(node: int) -> list[int]:
        """A wide node's children, one binary node at a time: start from the two children,
        open the inner one of the largest area while a slot is free."""
        slots = [node + 1, int(bvh.right_or_first[node])]
        while len(slots) < WIDTH:
            inner_slots = [k for k, c in enumerate(slots) if bvh.count[c] == 0]
            if not inner_slots:
                break
            k = max(inner_slots, key=lambda j: area(slots[j]))
            c = slots[k]
            slots[k:k + 1] = [c + 1, int(bvh.right_or_first[c])]
        return slots

    # the root's slots in the binary tree's order, each box holding its child's box and at
    # most a step of 1/255 of the root's box (plus rounding) larger on each side
    slots = greedy_slots(0)
    step = (bvh.hi[0].astype(np.float64) - bvh.lo[0]) / 255
    for dtype in (np.float32, np.float64):
        lo, hi = _record_boxes(rec, dtype)
        for k in range(WIDTH):
            if k >= len(slots):
                assert refs[0, k] == NO_CHILD  # an empty slot, skipped by its reference
                continue
            c = slots[k]
            assert bool(refs[0, k] >> LEAF_SHIFT) == bool(bvh.count[c])
            assert (lo[0, k] <= bvh.lo[c]).all() and (hi[0, k] >= bvh.hi[c]).all()
            assert (bvh.lo[c] - lo[0, k] <= 1.01 * step).all()
            assert (hi[0, k] - bvh.hi[c] <= 1.01 * step).all()
    assert (refs != NO_CHILD).sum(axis=1).min() >= 2  # a wide node has 2 to 4 children
    if n == 700:  # the area-greedy collapse fills most nodes
        assert (refs != NO_CHILD).sum(axis=1).mean() > 2.8
    assert WIDE_STACK_SIZE >= (WIDTH - 1) * (bvh.depth + 1)  # a wide level spans >= 1 binary level


@pytest.mark.parametrize("offset, size", [(0.0, 1.0), (1e7, 1.0), (-3e5, 1e-3), (1e30, 1e28),
                                          (3e38, 1e37), (0.0, 1e-40), (5.0, 0.0)])
def test_quantized_child_boxes_are_conservative_in_both_precisions(offset: float,
                                                                     size: float):
    """Every child box the traversal computes from the 8-bit records holds the child's own
    (padded) box, in float32 and in float64 arithmetic, far from the origin, near float32's
    largest values, for subnormal and for zero extents alike."""
    rng = np.random.default_rng(7)
    v = (offset + size * rng.uniform(-1, 1, (300, 3, 3))).astype(np.float32)
    bvh = build_bvh(v)
    rec, _ = wide_records(bvh)
    refs = rec[:, REC_REFS:REC_REFS + WIDTH].view(np.uint32)
    _, slots = _wide_children(bvh)  # each wide child slot's binary node
    valid = slots >= 0
    for dtype in (np.float32, np.float64):
        lo, hi = _record_boxes(rec, dtype)
        child = np.where(valid, slots, 0)
        assert np.all(~valid[..., None] | (lo <= bvh.lo[child]))
        assert np.all(~valid[..., None] | (hi >= bvh.hi[child]))
        assert np.isfinite(lo[valid]).all()
    assert (refs[~valid] == NO_CHILD).all()


@pytest.mark.parametrize("offset, size", [(0.0, 1.0), (1e7, 1.0), (-3e5, 1e-3), (1e30, 1e28),
                                          (0.0, 1e-40), (5.0, 0.0)])
def test_child_boxes_leave_the_folded_test_its_margin(offset: float, size: float):
    """The traversal's folded box test is off by up to 3.0001·2^-24 of its node's grid extent
    (wide_bvh._fold_margin): every child's grid box, origin + q·scale evaluated exactly (float64:
    q·scale is exact there, the sum within 2^-53), lies at least FOLD_MARGIN·(node extent +
    2^-20·its coordinate size) outside the child's padded box, more than that error."""
    rng = np.random.default_rng(9)
    v = (offset + size * rng.uniform(-1, 1, (300, 3, 3))).astype(np.float32)
    v[:40] = (offset + size * (0.5 + 1e-4 * rng.uniform(-1, 1, (40, 3, 3)))).astype(np.float32)
    bvh = build_bvh(v)
    rec, _ = wide_records(bvh)
    _, slots = _wide_children(bvh)
    valid = slots >= 0
    child = np.where(valid, slots, 0)
    lo, hi = _record_boxes(rec, np.float64)
    c_lo, c_hi = bvh.lo[child].astype(np.float64), bvh.hi[child].astype(np.float64)
    n_lo = np.where(valid[..., None], c_lo, np.inf).min(axis=1, keepdims=True)
    n_hi = np.where(valid[..., None], c_hi, -np.inf).max(axis=1, keepdims=True)
    margin = FOLD_MARGIN * ((n_hi - n_lo) + 2.0**-20 * np.maximum(abs(n_lo), abs(n_hi)))
    # the error bound against the margin, where scale is a normal float32 (the kernels flush
    # subnormals: there the boxes are only as exact as the triangle test, which flushes too)
    scale = rec[:, None, REC_SCALE:REC_SCALE + 3].astype(np.float64)
    normal = scale >= np.finfo(np.float32).tiny
    assert np.all(~normal | (3.0001 * 2.0**-24 * 255 * scale < margin))
    assert np.all(~valid[..., None] | (lo <= c_lo - margin))
    assert np.all(~valid[..., None] | (hi >= c_hi + margin))


@pytest.mark.parametrize("offset, size", [(0.0, 1.0), (1e7, 3.0), (-3e5, 1e-2), (1e30, 1e24),
                                          (3e38, 2e31), (1e-38, 1e-44)])
def test_quantize_rounds_outward_where_the_kernels_arithmetic_would_land_inside(
        offset: float, size: float):
    """_quantize on unpadded boxes, near and far from the origin: every dequantized bound,
    in float32 and float64, is on or outside its box (the kernel's rounded origin + q·scale
    with q = floor((lo - origin)/scale) lands inside now and then: two bounds in 480,000 at
    (0, 1))."""
    from raycheck.tracer.accel.wide_bvh import _quantize

    rng = np.random.default_rng(3)  # (0, 1) then has bounds that plain floor/ceil put inside
    a = (offset + size * rng.uniform(-1, 1, (20000, WIDTH, 3, 2))).astype(np.float32)
    lo, hi = a.min(axis=-1), a.max(axis=-1)
    valid = rng.uniform(size=(20000, WIDTH)) < 0.9
    valid[:, :2] = True
    origin, scale, q_lo, q_hi = _quantize(lo, hi, valid)
    assert np.isfinite(scale).all() and q_lo.max() <= 255 and q_hi.max() <= 255
    for dtype in (np.float32, np.float64):
        qlo = dequantized(origin[:, None], scale[:, None], q_lo, dtype)
        qhi = dequantized(origin[:, None], scale[:, None], q_hi, dtype)
        assert np.all(~valid[..., None] | (qlo <= lo))
        assert np.all(~valid[..., None] | (qhi >= hi))


@pytest.mark.parametrize("extreme", [-3.4028235e38, 3.4028235e38])
def test_a_vertex_at_the_edge_of_float32_quantizes_conservatively(extreme: float):
    """A vertex within the padding of ±FLT_MAX makes its padded box ±inf, which no finite
    origin and scale reach (the quantization once looped for ever on it): its node's bounds
    are clipped to ±FLT_MAX and still hold every vertex, and the BVH finds the brute-force
    hits."""
    rng = np.random.default_rng(5)
    v = rng.uniform(-1, 1, (40, 3, 3)).astype(np.float32)
    v[0, 1, 0] = np.float32(extreme)
    bvh = build_bvh(v)
    assert np.isinf(bvh.lo).any() or np.isinf(bvh.hi).any()  # the case described
    rec, _ = wide_records(bvh)
    _, slots = _wide_children(bvh)
    valid = slots >= 0
    child = np.where(valid, slots, 0)
    big = np.float32(np.finfo(np.float32).max)
    for dtype in (np.float32, np.float64):
        lo, hi = _record_boxes(rec, dtype)
        assert np.all(~valid[..., None] | (lo <= np.clip(bvh.lo[child], -big, big)))
        assert np.all(~valid[..., None] | (hi >= np.clip(bvh.hi[child], -big, big)))
        assert not np.isnan(lo[valid]).any() and not np.isnan(hi[valid]).any()
    o = rng.uniform(-3, 3, (2000, 3)).astype(np.float32)
    d = rng.normal(size=(2000, 3)).astype(np.float32)
    hits = []
    with np.errstate(over="ignore"):  # the face normal of the huge triangle is ±inf
        scene = soup(v)
    for accel in ("bvh", "brute"):
        isect = Intersector(scene, make_types(), accel)
        T = isect.T
        hit = isect.closest(T.Array3f(o.T), T.Array3f(d.T))
        isect.dr.eval(hit.t, hit.order)
        hits.append((hit.t.numpy(), hit.order.numpy()))
    assert np.array_equal(hits[0][0], hits[1][0]) and np.array_equal(hits[0][1], hits[1][1])
    assert np.mean(hits[0][0] < FLT_MAX) > 0.05


def test_throughput_bench_runs_on_a_tiny_mesh():
    """bench/throughput.py end to end at toy size (no timings checked; Mitsuba left out)."""
    from raycheck.harness.bench.throughput import bumpy_sphere, run_throughput
    from raycheck.harness.pages.throughput import format_throughput

    pos, faces, normals = bumpy_sphere(500)
    assert faces.min() >= 0 and faces.max() < len(pos)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)
    rows = run_throughput(sizes=(200, 500), rays=32 * 32, warm_runs=1, mitsuba=False)
    assert [r.triangles for r in rows] == [196, 484]  # 4 rings², the nearest to the ask
    for r in rows:
        assert r.brute_agrees and 0.2 < r.hit_fraction < 0.9
        assert r.nodes == r.leaves * 2 - 1 and r.depth < STACK_SIZE
        assert r.node_bytes > 0 and r.triangle_bytes > 0 and r.render_warm_s > 0
        assert r.ours_mrays > 0 and r.ours_full_mrays > 0
    text = format_throughput(rows)
    assert "ours" in text and "BVH build" in text and "Render" in text
