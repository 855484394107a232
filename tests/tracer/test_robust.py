"""Robust mode (--mode robust): course mode unchanged, and hand-made numeric cases where the
course's arithmetic fails and robust mode is right."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from raycheck.harness.catalog import SCENES
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.parser import parse_scene_text

EXTREME = SCENES / "extreme"


def _render(scene, **kw):
    kw.setdefault("width", 16)
    kw.setdefault("height", 16)
    return Renderer(scene, RenderOptions(**kw)).render()


def test_course_is_the_default_and_bit_identical():
    from spec_reference import render_reference

    from raycheck.tracer.image import quantize

    assert RenderOptions().mode == "course"
    scene = load_scene(SCENES / "course" / "spheres_mirror.txt")
    a = _render(scene, shadows=True, bounces=2)
    b = _render(scene, shadows=True, bounces=2, mode="course")
    assert np.array_equal(a.color, b.color, equal_nan=True)
    ref = render_reference(scene, 16, 16, shadows=True, bounces=2)[0]
    assert np.mean(quantize(a.color) == quantize(ref)) >= 0.999


def test_unknown_mode_is_rejected():
    with pytest.raises(ValueError):
        Renderer(load_scene(EXTREME / "size_1x1.txt"), RenderOptions(mode="fast"))


PLANE_1E6 = """
PerspectiveCamera { center 1000000 1000003 1000000 direction 0 -1 -0.2 up 0 0.2 -1 angle 40 }
Lights { numLights 1 DirectionalLight { direction 0.3 -1 -0.2 color 0.8 0.8 0.8 } }
Background { color 0 0 0 ambientLight 0.1 0.1 0.1 }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 1 0 offset 1000000 } }
"""


def test_shadow_acne_far_from_the_origin():
    """A plane at y = 1e6 (float32 spacing 0.0625, above the course offset 0.01)."""
    scene = parse_scene_text(PLANE_1E6, Path("plane_1e6.txt"))
    ambient_only = np.float32(0.1)
    course = _render(scene, shadows=True).color[..., 0]
    robust = _render(scene, shadows=True, mode="robust").color[..., 0]
    # every pixel sees the lit plane: a pixel with only the ambient term is self-shadowed
    assert np.sum(np.isclose(course, ambient_only)) > 20  # the course offset is below 1 ulp
    assert np.sum(np.isclose(robust, ambient_only)) == 0


def test_far_tiny_sphere_is_hit_exactly():
    scene = load_scene(EXTREME / "far_tiny_sphere_1e5.txt")
    kw = dict(kinds=("depth",), depth_min=999, depth_max=1001)
    course = _render(scene, **kw).depth
    robust = _render(scene, mode="robust", **kw).depth
    exact = _render(scene, mode="robust", precision="double", **kw).depth
    hits = lambda d: np.isfinite(d) & (d < 10)  # noqa: E731  (a miss is (FLT_MAX-min)/range)
    assert hits(course).all()  # the course's discriminant is noise: every ray "hits"
    assert 0 < hits(exact).sum() < exact.size
    assert np.array_equal(hits(robust), hits(exact))


@pytest.mark.parametrize("name", ["mesh_vertex_hits", "mesh_watertight_edges"])
def test_watertight_mesh_has_no_holes(name):
    scene = load_scene(EXTREME / f"{name}.txt")
    r = _render(scene, width=21, height=21, mode="robust", kinds=("color", "normals"))
    ref = _render(scene, width=21, height=21, mode="robust", precision="double",
                  kinds=("color", "normals"))
    hole = np.all(r.color == np.float32([1, 0, 1]), axis=-1)
    covered = ~np.all(ref.color == np.float64([1, 0, 1]), axis=-1)
    assert not (hole & covered).any()
    assert not hole[10, 10]  # the center ray hits the shared vertex / the shared corner


@pytest.mark.parametrize("size", [(1, 1), (1, 5), (5, 1)])
@pytest.mark.parametrize("jitter", [False, True])
def test_single_row_or_column_images_are_finite(size, jitter):
    scene = load_scene(EXTREME / "size_1x9.txt")
    kw = dict(width=size[0], height=size[1], jitter=jitter, samples=2, kinds=("color", "normals"))
    course = _render(scene, **kw)
    robust = _render(scene, mode="robust", **kw)
    assert np.isfinite(robust.color).all() and np.isfinite(robust.normals).all()
    if size == (1, 1) and not jitter:
        # course: the NaN ray misses (background); robust: the center ray hits the sphere ahead
        assert not np.array_equal(course.color, robust.color)


@pytest.mark.parametrize("name", ["falloff_zero_shadows", "falloff_tiny", "light_on_surface",
                                  "overflow_inf", "shininess_extremes", "angle_0",
                                  "degenerate_triangles"])
def test_robust_mode_is_nan_free(name):
    scene = load_scene(EXTREME / f"{name}.txt")
    r = _render(scene, shadows=True, mode="robust", kinds=("color", "normals"))
    assert np.isfinite(r.color).all() and np.isfinite(r.normals).all()


def test_falloff_zero_is_finite_and_quantises_like_the_course():
    from raycheck.tracer.image import quantize

    scene = load_scene(EXTREME / "falloff_zero_shadows.txt")
    course = _render(scene, shadows=True)
    robust = _render(scene, shadows=True, mode="robust")
    assert not np.isfinite(course.color).all()
    assert np.isfinite(robust.color).all()
    # the red channel (color 1 / 0 = inf: black) stays black; the green channel (0/0 = NaN in
    # the course, black) is 0 / 1e-30 = 0 in robust mode, so the other light shows there
    assert np.array_equal(quantize(course.color)[..., 0], quantize(robust.color)[..., 0])


@pytest.mark.parametrize("name", ["offset_1e5", "offset_1e7", "far_tiny_sphere_1e7",
                                  "concentric_spheres"])
def test_robust_single_precision_matches_float64_far_from_the_origin(name):
    # camera-relative coordinates (offsets), float64 sphere roots (a radius of a few float32
    # ulps of its distance) and sphere hits ordered by their float64 t (shells 4e-5 apart at a
    # distance where float32 t steps by 0.001): the float32 robust render equals the float64 one
    # on >= 99% of bytes
    from raycheck.harness.catalog import bundled
    from raycheck.tracer.image import quantize

    sc = next(s for s in bundled("extreme") if s.name == name)
    scene = load_scene(sc.path)
    flags = sc.flags
    kw = dict(shadows="-shadows" in flags, mode="robust",
              bounces=int(flags[flags.index("-bounces") + 1]) if "-bounces" in flags else 0)
    w, h = sc.size or (48, 48)
    single = Renderer(scene, RenderOptions(w, h, **kw)).render().color
    double = Renderer(scene, RenderOptions(w, h, precision="double", **kw)).render().color
    equal = np.mean(np.abs(quantize(single).astype(int) - quantize(double).astype(int)) <= 1)
    assert equal >= 0.99, f"{name}: {equal:.2%} of bytes within one level"


def test_robust_records_hold_each_triangles_unit_normal_in_a_scene_with_meshes():
    """The geometric normal that robust shadow and mirror rays are offset along: a cube mesh's
    12 triangles point along the six axes, each normal of length 1 (it once held the mesh's
    triangle count in every slot, for every scene with a mesh)."""
    from raycheck.tracer.accel.flat_scene import flatten
    from raycheck.tracer.arithmetic.robust import RobustIntersector
    from raycheck.tracer.kernel.vecmath import make_types

    text = ("PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
            "Lights { numLights 0 }\nBackground { color 0 0 0 }\n"
            "Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }\n"
            "Group { numObjects 1 MaterialIndex 0 TriangleMesh { obj_file "
            f"{SCENES / 'assets' / 'cube_flat.obj'} }} }}\n")
    scene = parse_scene_text(text, SCENES / "features" / "x.txt")
    isect = RobustIntersector(flatten(scene, course=False), make_types(), "bvh")
    records = np.asarray(isect.triangles.trecord).reshape(-1, 4, 4)
    normals = records[:, 3, :3]
    assert len(normals) == 12
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)
    axes = {tuple(np.rint(n).astype(int)) for n in normals}
    assert axes == {(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)}
