"""Intersection routines, the cube-map lookup and jitter, each against hand-worked values."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from raycheck.tracer.accel.flat_scene import flatten
from raycheck.tracer.accel.intersect import FLT_MAX, Intersector
from raycheck.tracer.kernel.vecmath import make_types
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import parse_scene_text
from raycheck.tracer.scene.cubemap import load_cube_map
from raycheck.tracer.scene.model import Background as BackgroundSpec
from raycheck.tracer.shade.background import Background

T = make_types()
CAM = "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
MAT = "Materials { numMaterials 2 Material { } Material { } }\n"


def closest(obj: str, o, d):
    """t and normal of rays o + t·d against one object."""
    scene = parse_scene_text(CAM + MAT + f"Group {{ numObjects 1 MaterialIndex 0 {obj} }}",
                             Path("/x/s.txt"))
    isect = Intersector(flatten(scene), T)
    hit = isect.closest(T.Array3f(np.array(o, np.float32).reshape(-1, 3).T),
                        T.Array3f(np.array(d, np.float32).reshape(-1, 3).T))
    isect.dr.eval(hit.t, hit.normal, hit.material)
    return hit.t.numpy(), np.asarray(hit.normal.numpy()).T


def test_sphere_front_inside_behind_and_tangent():
    sphere = "Sphere { center 0 0 0 radius 2 }"
    t, n = closest(sphere, [[0, 0, 10], [0, 0, 0], [0, 0, 10], [2, 0, 10]],
                   [[0, 0, -1], [1, 0, 0], [0, 0, 1], [0, 0, -1]])
    assert t[0] == 8 and n[0].tolist() == [0, 0, 1]
    assert t[1] == 2 and n[1].tolist() == [1, 0, 0]  # from inside: t+ and the outward normal
    assert t[2] == FLT_MAX and n[2].tolist() == [0, 0, 0]  # sphere behind the ray
    assert t[3] == 10 and n[3].tolist() == [1, 0, 0]  # tangent: disc = 0 still hits


def test_sphere_uses_unnormalized_direction_as_parameter():
    t, _ = closest("Sphere { center 0 0 0 radius 2 }", [[0, 0, 10]], [[0, 0, -2]])
    assert t[0] == 4  # o + 4·(0,0,-2) = (0,0,2)


def test_plane_raw_normal_parallel_and_behind():
    plane = "Plane { normal 0 2 0 offset -2 }"  # the plane y = -1, stored normal (0,2,0)
    t, n = closest(plane, [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, -3, 0]],
                   [[0, -1, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0]])
    assert t[0] == 1 and n[0].tolist() == [0, 2, 0]
    assert t[1] == FLT_MAX  # parallel: (d - o·n)/0 = -inf, rejected
    assert t[2] == FLT_MAX  # plane behind: t = -1 < tmin
    assert t[3] == 2 and n[3].tolist() == [0, 2, 0]  # two-sided, normal never flipped


def test_triangle_edges_and_vertices_are_inclusive_and_no_culling():
    tri = "Triangle { vertex0 0 0 0 vertex1 4 0 0 vertex2 0 4 0 }"
    o = [[1, 1, 5], [2, 2, 5], [0, 0, 5], [4, 0, 5], [2.0001, 2, 5], [-0.0001, 1, 5], [1, 1, -5]]
    d = [[0, 0, -1]] * 6 + [[0, 0, 1]]
    t, n = closest(tri, o, d)
    assert t.tolist() == [5, 5, 5, 5, FLT_MAX, FLT_MAX, 5]
    assert n[0].tolist() == [0, 0, 1] and n[6].tolist() == [0, 0, 1]  # back side: same normal


def test_closest_of_several_and_ties_go_to_the_first_in_file_order():
    objs = ("Sphere { center 0 0 0 radius 1 } MaterialIndex 1 Sphere { center 0 0 -3 radius 1 }"
            " Plane { normal 0 0 1 offset 1 }")
    scene = parse_scene_text(CAM + MAT + "Group { numObjects 3 MaterialIndex 0 " + objs + " }",
                             Path("/x/s.txt"))
    isect = Intersector(flatten(scene), T)
    hit = isect.closest(T.Array3f([0, 0], [0, 0], [10, -10]), T.Array3f([0, 0], [0, 0], [-1, 1]))
    isect.dr.eval(hit.t, hit.material, hit.order)
    # From +z: the first sphere and the plane z=1 tie at t=9; the sphere comes first in the file.
    assert hit.t.numpy().tolist() == [9, 6] and hit.order.numpy().tolist() == [0, 1]
    assert hit.material.numpy().tolist() == [0, 1]


def test_transformed_sphere_is_an_ellipsoid_with_world_t():
    ell = "Transform { Scale 2 1 1 Sphere { center 0 0 0 radius 1 } }"
    t, n = closest(ell, [[5, 0, 0], [5, 0, 0], [0, 5, 0]], [[-1, 0, 0], [-2, 0, 0], [0, -1, 0]])
    assert t.tolist() == [3, 1.5, 4]  # the direction is not renormalized in object space
    assert n[0].tolist() == [1, 0, 0] and n[2].tolist() == [0, 1, 0]
    # off-axis: the normal is normalize(M^-T n_object), not the sphere's radial direction
    p = np.array([np.sqrt(2), np.sqrt(0.5), 0])  # on the ellipse x²/4 + y² = 1
    t, n = closest(ell, [p + [0, 0, 5]], [[0, 0, -1]])
    assert t[0] == pytest.approx(5, abs=1e-5)
    expected = np.array([p[0] / 4, p[1], 0])
    assert np.allclose(n[0], expected / np.linalg.norm(expected), atol=1e-6)


FACES = {"right": (255, 0, 0), "left": (0, 255, 0), "up": (0, 0, 255),
         "down": (255, 255, 0), "front": (0, 255, 255), "back": (255, 0, 255)}


def lookup(folder: Path, dirs) -> np.ndarray:
    bg = Background(BackgroundSpec(cube_map=load_cube_map(folder, folder / "s.txt", 1)), T)
    c = bg.lookup(T.Array3f(np.array(dirs, np.float32).reshape(-1, 3).T))
    bg.dr.eval(c)
    return np.asarray(c.numpy()).T


def test_cube_map_face_choice_and_ties(tmp_path: Path):
    for name, rgb in FACES.items():
        Image.fromarray(np.full((3, 3, 3), rgb, np.uint8)).save(tmp_path / f"{name}.png")
    got = lookup(tmp_path, [[2, 0, 0], [-1, 0.5, 0], [0, 3, 0], [0.2, -1, 0], [0, 0, 1],
                            [0, 0, -1], [1, 1, 0], [0, -1, 1], [1, 1, 1]])
    want = [FACES[f] for f in ("right", "left", "up", "down", "front", "back",
                               "right", "down", "right")]  # ties go to X, then Y
    assert (got * 255).round().astype(int).tolist() == [list(w) for w in want]


def test_cube_map_bilinear_fetch_on_the_front_face(tmp_path: Path):
    for name in FACES:
        Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / f"{name}.png")
    # front (+Z) face, PNG row 0 at the top: texel (i, j) = column i, row j
    face = np.array([[[10, 0, 0], [20, 0, 0]], [[30, 0, 0], [40, 0, 0]]], np.uint8)
    Image.fromarray(face).save(tmp_path / "front.png")
    # d = (0,0,1): u = 1 - (0+1)/2 = 0.5, v = 0.5 -> X = 1, Y = 1 -> texel (1,1) alone
    # d = (0.5,0,1): u = 1 - 1.5/2 = 0.25 -> X = 0.5, i = 0, a = 0.5; Y = 1, j = 1, b = 0
    # d = (0,-0.5,1): v = 0.25 -> Y = 1.5, j = 1 (j+1 clamped to 1), b = 0.5; X = 1, i = 1
    got = lookup(tmp_path, [[0, 0, 1], [0.5, 0, 1], [0, -0.5, 1]])[:, 0] * 255
    assert got == pytest.approx([40, 0.5 * 30 + 0.5 * 40, 40], abs=1e-4)


def test_jitter_averages_16_samples_before_quantisation():
    scene = parse_scene_text(CAM + "Background { color 0.5 0.25 0 }\n" + MAT
                             + "Group { numObjects 1 MaterialIndex 0 "
                             "Sphere { center 0 0 0 radius 1 } }", Path("/x/s.txt"))
    opts = RenderOptions(15, 15, jitter=True, kinds=("color", "depth"), depth_min=8, depth_max=10)
    r = Renderer(scene, opts).render()
    plain = Renderer(scene, RenderOptions(15, 15, kinds=("color", "depth"), depth_min=8,
                                          depth_max=10)).render()
    assert r.launches == 1  # the 16 samples loop inside one kernel
    # far from the sphere every sample sees the background: the mean is exact
    assert r.color[0, 0].tolist() == [0.5, 0.25, 0]
    # inside the silhouette every sample sees white (no lights: kd·ambient 1): mean exact
    assert r.color[7, 7].tolist() == [1, 1, 1]
    # silhouette pixels average both: strictly between background and sphere
    edge = (r.color[..., 2] > 0) & (r.color[..., 2] < 1)
    assert edge.sum() >= 8
    # a depth pixel with any missed sample is black (the FLT_MAX mean overflows)
    from raycheck.tracer.image import quantize
    assert (quantize(r.depth)[edge] == 0).all()
    assert quantize(r.depth)[7, 7] > 0 and (r.depth[~edge & (plain.depth < 2)] < 2).all()


def test_jitter_with_filter_samples_the_3x_grid_16_times():
    scene = parse_scene_text(CAM + "Background { color 0.5 0.25 0 }\n" + MAT
                             + "Group { numObjects 1 MaterialIndex 0 "
                             "Sphere { center 0 0 0 radius 2 } }", Path("/x/s.txt"))
    r = Renderer(scene, RenderOptions(5, 5, jitter=True, filter=True)).render()
    assert r.color.shape == (5, 5, 3)
    assert r.color[0, 0].tolist() == [0.5, 0.25, 0]  # 9 sub-pixels x 16 samples of background
    assert r.color[2, 2].tolist() == [1, 1, 1]


def test_powf_underflow_is_zero_not_minus_inf():
    # 0.028786868^200 is about 1e-308: double's subnormal range, where Dr.Jit 1.5's exp2
    # returns -inf; powf gives 0 in float32. Found as black dots on a shininess-200 sphere.
    scene = parse_scene_text(CAM + MAT, Path("/x/s.txt"))
    shader = Renderer(scene, RenderOptions(2, 2)).shader
    x = T.Float([0.028786868, 0.5, 0.0, 2.0, 1.0, 0.3])
    e = T.Float([200.0, 2.0, 0.0, 3.0, 1e4, 0.0])
    got = shader.powf(x, e).numpy().tolist()
    assert got == [0.0, 0.25, 1.0, 8.0, 1.0, 1.0]


def test_under_a_singular_transform_only_spheres_are_hit_at_10000():
    # spec §5: rays go into the child through M^-1, which a Scale 0 makes inf/NaN; NaN misses
    # triangles and planes, but the course's sphere test falls back to t = 10000 (as a2 does)
    for obj, want in (("Triangle { vertex0 -1 -1 0 vertex1 1 -1 0 vertex2 0 1 0 }", FLT_MAX),
                      ("Sphere { center 0 0 0 radius 1 }", 10000.0),
                      ("Plane { normal 0 0 1 offset 0 }", FLT_MAX)):
        t, _ = closest(f"Transform {{ Scale 1 1 0 {obj} }}", [[0, 0, 10], [0.1, 0.1, 10]],
                       [[0, 0, -1], [0, 0, -1]])
        assert t.tolist() == [want, want], obj


@pytest.mark.parametrize("size", [(16, 12), (15, 14)])  # 4x4 lane blocks / plain rows
@pytest.mark.parametrize("jitter", [False, True])
def test_lane_blocks_and_launch_splits_leave_every_value_in_place(monkeypatch, size, jitter):
    """Lanes trace 4x4 sub-pixel blocks when both sides are multiples of 4 and scatter their
    values into top-down row-major buffers; images larger than TILE_RAYS take several launches.
    Every value must land on its pixel whatever the split: rendered one launch per band of
    rows, the image is the one of a single launch, and a pixel's value is the one its own
    primary ray gives."""
    from raycheck.tracer import render as render_module

    scene = parse_scene_text(CAM + "Background { color 0.5 0.25 0 }\n" + MAT
                             + "Group { numObjects 2 MaterialIndex 0 "
                             "Sphere { center 0.6 0.3 0 radius 1 } MaterialIndex 1 "
                             "Sphere { center -1 -1 1 radius 0.5 } }", Path("/x/s.txt"))
    w, h = size
    opts = RenderOptions(w, h, jitter=jitter, kinds=("color", "normals", "depth"),
                         depth_min=8, depth_max=10)
    whole = Renderer(scene, opts).render()
    assert whole.launches == 1
    monkeypatch.setattr(render_module, "TILE_RAYS", 1)  # one band of rows per launch
    split = Renderer(scene, opts).render()
    assert split.launches == (h // 4 if w % 4 == 0 and h % 4 == 0 else h)
    for name in ("color", "normals", "depth"):
        np.testing.assert_array_equal(getattr(split, name), getattr(whole, name))
    if jitter:  # a launch of at most 16 x 5 ray casts: packets of 16 lanes, 5 samples each
        monkeypatch.setattr(render_module, "TILE_RAYS", 1 << 21)
        monkeypatch.setattr(render_module, "LAUNCH_WORK", 80)
        chunks = Renderer(scene, opts)
        lanes = {(first, count) for first, count, _ in chunks.launches()}
        assert {c for _, c in lanes} <= {16, w * h % 16} and {
            s for *_, s in chunks.launches()} == {(0, 5), (5, 10), (10, 15), (15, 16)}
        chunked = chunks.render()
        assert chunked.launches == len(lanes) * 4
        for name in ("color", "normals", "depth"):  # the sums added in the same order
            np.testing.assert_array_equal(getattr(chunked, name), getattr(whole, name))
    if not jitter:
        # row 0 is the top row: the pixel (x, y from the top) has the normal its own ray gives
        r = Renderer(scene, opts)
        for x, y in [(0, 0), (w - 1, 0), (w // 2, h // 3), (3, h - 1)]:
            px = T.Float([float(x)])
            py = T.Float([float(h - 1 - y)])
            want = r._sample(px, py)["normals"]
            got = whole.normals[y, x]
            assert got.tolist() == np.asarray(want.numpy()).ravel().tolist()


@pytest.mark.parametrize("size", [(16, 12), (15, 14), (8, 4)])
def test_lane_positions_on_the_host_are_the_kernel_s(size):
    """render.lane_positions (the throughput bench casts its rays in this order) gives the
    positions Renderer._lanes gives each lane."""
    from raycheck.tracer.render import lane_positions

    scene = parse_scene_text(CAM + "Background { color 0.5 0.25 0 }\n" + MAT
                             + "Group { numObjects 1 MaterialIndex 0 "
                             "Sphere { center 0 0 0 radius 1 } }", Path("/x/s.txt"))
    w, h = size
    _, _, pos = Renderer(scene, RenderOptions(w, h))._lanes(0, w * h)
    assert pos.numpy().tolist() == lane_positions(w, h).tolist()
    if size == (8, 4):  # two 4x4 blocks side by side, each row-major within
        assert lane_positions(8, 4)[:20].tolist() == [0, 1, 2, 3, 8, 9, 10, 11, 16, 17, 18, 19,
                                                      24, 25, 26, 27, 4, 5, 6, 7]
