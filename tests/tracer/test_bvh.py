"""The BVH finds exactly the brute-force hit: same t and same triangle for every ray."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from raycheck.tracer.accel.bvh import STACK_SIZE, build_bvh
from raycheck.tracer.accel.flat_scene import FlatScene, TriangleSoup
from raycheck.tracer.accel.intersect import FLT_MAX, Intersector
from raycheck.tracer.kernel.vecmath import make_types

ASSETS = Path(__file__).resolve().parents[2] / "scenes" / "assets"


def soup(vertices: np.ndarray) -> FlatScene:
    n = len(vertices)
    unit = np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0])
    normals = np.repeat(unit[:, None, :], 3, axis=1).astype(np.float32)
    tris = TriangleSoup(vertices.astype(np.float32), normals, np.zeros(n, np.uint32),
                        np.arange(n, dtype=np.uint32))
    return FlatScene([], [], tris, n)


def grid_box(k: int) -> np.ndarray:
    """The surface of the cube [-1,1]^3 as a k x k grid of quads per face (axis-aligned)."""
    g = np.linspace(-1, 1, k + 1)
    tris = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            for i in range(k):
                for j in range(k):
                    quad = []
                    for a, b in ((g[i], g[j]), (g[i + 1], g[j]),
                                 (g[i + 1], g[j + 1]), (g[i], g[j + 1])):
                        p = [0.0, 0.0, 0.0]
                        p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3] = side, a, b
                        quad.append(p)
                    tris += [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]]
    return np.array(tris, np.float32)


def hits(flat: FlatScene, accel: str, o: np.ndarray, d: np.ndarray):
    T = make_types()
    isect = Intersector(flat, T, accel)
    hit = isect.closest(T.Array3f(o.T), T.Array3f(d.T))
    occl = isect.occluded(T.Array3f(o.T), T.Array3f(d.T), T.Float(np.full(len(o), 2.5, np.float32)))
    isect.dr.eval(hit.t, hit.order, hit.normal, occl)
    return hit.t.numpy(), hit.order.numpy(), np.asarray(hit.normal.numpy()), occl.numpy()


def assert_same(flat: FlatScene, o: np.ndarray, d: np.ndarray) -> float:
    tb, ob, nb, sb = hits(flat, "bvh", o, d)
    tf, of, nf, sf = hits(flat, "brute", o, d)
    assert np.array_equal(tb, tf), f"{np.sum(tb != tf)} rays differ in t"
    assert np.array_equal(ob, of), f"{np.sum(ob != of)} rays hit another triangle"
    assert np.array_equal(nb, nf, equal_nan=True)
    assert np.array_equal(sb, sf), f"{np.sum(sb != sf)} shadow rays differ"
    return float(np.mean(tb < FLT_MAX))


def test_random_triangles_random_rays():
    rng = np.random.default_rng(1)
    centers = rng.uniform(-3, 3, (400, 1, 3))
    v = (centers + rng.normal(0, 0.4, (400, 3, 3))).astype(np.float32)
    o = rng.uniform(-6, 6, (4000, 3)).astype(np.float32)
    d = rng.normal(0, 1, (4000, 3)).astype(np.float32)
    share = assert_same(soup(v), o, d)
    assert share > 0.1  # the test means something only if many rays hit


def test_rays_through_vertices_and_edges_of_a_closed_mesh():
    v = grid_box(4)
    rng = np.random.default_rng(2)
    targets = np.concatenate([v.reshape(-1, 3),  # every vertex
                              0.5 * (v[:, 0] + v[:, 1]), 0.5 * (v[:, 1] + v[:, 2])])  # edges
    o = rng.uniform(-5, 5, (len(targets), 3)).astype(np.float32) * 2
    d = (targets - o).astype(np.float32)
    share = assert_same(soup(v), o, d)
    assert share > 0.95


def test_axis_parallel_rays_lying_in_box_faces():
    v = grid_box(3)
    g = np.linspace(-1, 1, 7).astype(np.float32)  # includes the faces' own coordinates ±1
    o, d = [], []
    for a in g:
        for b in g:
            for axis in range(3):
                p = np.zeros(3, np.float32)
                p[axis] = -4
                p[(axis + 1) % 3], p[(axis + 2) % 3] = a, b
                dirv = np.zeros(3, np.float32)
                dirv[axis] = 1
                o.append(p)
                d.append(dirv)
    assert_same(soup(v), np.array(o), np.array(d))


def test_build_is_a_valid_tree():
    rng = np.random.default_rng(3)
    v = rng.uniform(-1, 1, (1000, 3, 3)).astype(np.float32)
    bvh = build_bvh(v)
    assert sorted(bvh.order.tolist()) == list(range(1000))  # every triangle in one leaf
    leaves = bvh.count > 0
    assert bvh.count[leaves].sum() == 1000
    # every triangle lies inside its leaf's box
    for node in np.nonzero(leaves)[0]:
        first, n = bvh.right_or_first[node], bvh.count[node]
        tri = v[bvh.order[first:first + n]]
        assert (tri >= bvh.lo[node]).all() and (tri <= bvh.hi[node]).all()
    # inner nodes: the left child follows its parent, the right child comes later
    inner = np.nonzero(~leaves)[0]
    assert (bvh.right_or_first[inner] > inner + 1).all()
    assert bvh.depth < STACK_SIZE


def test_depth_stays_below_the_stack_size_on_a_degenerate_input():
    # 3000 triangles along a line at exponentially growing spacing: SAH alone goes deep
    x = np.cumsum(1.1 ** np.arange(3000.0) % 7)
    v = np.zeros((3000, 3, 3), np.float32)
    v[:, :, 0] = x[:, None] + np.array([0, 1e-3, 0])
    v[:, 2, 1] = 1e-3
    bvh = build_bvh(v)
    assert bvh.depth < STACK_SIZE
    assert sorted(bvh.order.tolist()) == list(range(3000))


@pytest.mark.parametrize("n", [1, 2, 9])
def test_tiny_meshes(n: int):
    rng = np.random.default_rng(n)
    v = rng.uniform(-1, 1, (n, 3, 3)).astype(np.float32)
    o = rng.uniform(-3, 3, (500, 3)).astype(np.float32)
    d = (rng.uniform(-0.5, 0.5, (500, 3)) - o).astype(np.float32)
    assert_same(soup(v), o, d)


# one torus in nested transforms (rotations, a non-uniform scale, a shear-free translation),
# or two tori in different ones: the search runs in the one instance's space (its BVH over
# the object-space triangles), or moves the ray at each triangle test into that triangle's
TRANSFORMED = """PerspectiveCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }}
Lights {{ numLights 0 }}
Background {{ color 0 0 0 }}
Materials {{ numMaterials 1 Material {{ diffuseColor 1 1 1 }} }}
Group {{ numObjects {count}
  MaterialIndex 0
  Transform {{ Translate 0.3 -0.2 0.1 YRotate 20 Transform {{ XRotate 55 Scale 1.5 0.6 1
    TriangleMesh {{ obj_file torus.obj }} }} }}
{second}}}
"""
SECOND = "  Transform { ZRotate 30 Translate 0 1.2 -0.5 TriangleMesh { obj_file torus.obj } }\n"


@pytest.mark.parametrize("tori", [1, 2])
def test_transformed_meshes_rays_random_and_through_vertices(tori, tmp_path):
    from raycheck.tracer.accel.flat_scene import NO_INSTANCE, flatten
    from raycheck.tracer.scene import load_scene

    shutil.copy(ASSETS / "torus.obj", tmp_path)
    path = tmp_path / "scene.txt"
    path.write_text(TRANSFORMED.format(count=tori, second=SECOND if tori == 2 else ""))
    flat = flatten(load_scene(path), course=True)
    one = Intersector(flat, make_types(), "bvh").triangles.one_instance
    assert (one != NO_INSTANCE) == (tori == 1)
    rng = np.random.default_rng(4)
    world = flat.triangles.bounds.reshape(-1, 3)  # where the vertices lie in world space
    targets = np.concatenate([world[rng.choice(len(world), 1500, replace=False)],
                              rng.uniform(-2, 2, (1500, 3))]).astype(np.float32)
    o = rng.uniform(-6, 6, (len(targets), 3)).astype(np.float32)
    share = assert_same(flat, o, (targets - o).astype(np.float32))
    assert share > 0.5


def test_tiny_triangles_in_large_nodes_and_rays_nearly_in_coordinate_planes():
    """The folded box test (wide_traversal.WideNodes.open) on what strains it: tiny triangles beside
    triangles a million times larger, so that a node's rounding (~2^-24 of its size) is
    larger than its tiny children's padding (BOX_PAD of their size and place), rays through
    their vertices from near and farther away, and rays with a direction component that is
    zero, or so small that 1/d is huge and finite (the axis the fold cannot take). (Rays
    from much farther away would meet the limit of any box test: the triangle test's own
    rounding, ~2^-24 of the distance, can then accept points outside the padded box.)"""
    rng = np.random.default_rng(11)
    tiny = 10.0 + rng.uniform(-1e-3, 1e-3, (200, 1, 3)) + rng.normal(0, 1e-4, (200, 3, 3))
    huge = rng.uniform(-1e3, 1e3, (40, 1, 3)) + rng.normal(0, 50.0, (40, 3, 3))
    v = np.concatenate([tiny, huge]).astype(np.float32)
    targets = v[:200].reshape(-1, 3)
    near = (targets + rng.normal(0, 1e-2, targets.shape)).astype(np.float32)
    far = (targets + rng.normal(0, 30.0, targets.shape)).astype(np.float32)
    o = np.concatenate([near, far])
    d = (np.concatenate([targets, targets]) - o).astype(np.float32)
    # the same targets along directions with components 0, 2e-38 and 1e-30
    flat = d.copy()
    flat[0::3, 0] = 0.0
    flat[1::3, 1] = np.float32(2e-38) * np.sign(flat[1::3, 1])
    flat[2::3, 2] = np.float32(1e-30)
    o, d = np.concatenate([o, o]), np.concatenate([d, flat])
    share = assert_same(soup(v), o, d)
    assert share > 0.25  # the rays through vertices hit; most of the flattened ones miss
