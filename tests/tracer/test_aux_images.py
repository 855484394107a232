"""The tracer's auxiliary images (tracer/shade/auxiliary.py): the parts of the color image.

Against the independent spec model (spec_reference.py: its per-hit terms, light by light) on
small inline scenes, and on the bundled scenes the identity that defines them: the color image
is ((Σ unblocked lights' diffuse + specular) + reflection) + ambient, bit for bit.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from spec_reference import ReferenceTracer

from raycheck.harness.catalog import bundled_path
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import render
from raycheck.tracer.scene import load_scene, parse_scene_text
from raycheck.tracer.shade.auxiliary import AUX_KINDS, compose, scene_objects

# a mirror sphere, a dull sphere (transformed), a plane; a point and a directional light
MIRRORS = """
PerspectiveCamera { center 0 1 9 direction 0 -0.1 -1 up 0 1 0 angle 35 }
Lights { numLights 2
  PointLight { position 3 4 5 color 0.9 0.8 0.7 falloff 0.02 }
  DirectionalLight { direction -0.3 -1 -0.4 color 0.4 0.4 0.5 } }
Background { color 0.1 0.2 0.3 ambientLight 0.2 0.2 0.2 }
Materials { numMaterials 3
  Material { diffuseColor 0.5 0.2 0.2 specularColor 0.6 0.6 0.6 shininess 20 }
  Material { diffuseColor 0.2 0.6 0.3 specularColor 0.05 0.05 0.05 shininess 4 }
  Material { diffuseColor 0.7 0.7 0.7 } }
Group { numObjects 3
  MaterialIndex 0
  Sphere { center -1 0 0 radius 1 }
  MaterialIndex 1
  Transform { Translate 1.5 0 0.5 Scale 0.8 1.2 0.8 Sphere { center 0 0 0 radius 1 } }
  MaterialIndex 2
  Plane { normal 0 1 0 offset -1 } }
"""


def spec_parts(scene, w: int, h: int, bounces: int, shadows: bool):
    """The spec model's parts of every pixel (row 0 at the top), None where the ray misses."""
    ref = ReferenceTracer(scene, shadows=shadows)
    with np.errstate(all="ignore"):
        return [[ref.parts(*ref.primary_ray(x, h - 1 - row, w, h), bounces) for x in range(w)]
                for row in range(h)]


@pytest.mark.parametrize("bounces,shadows", [(0, False), (0, True), (3, True)])
def test_parts_match_the_spec_model(bounces, shadows):
    scene = parse_scene_text(MIRRORS, Path("mirrors.txt"))
    w = h = 10
    aux = render(scene, RenderOptions(width=w, height=h, bounces=bounces, shadows=shadows,
                                      aux=AUX_KINDS)).aux
    hits = 0
    for row, line in enumerate(spec_parts(scene, w, h, bounces, shadows)):
        for x, parts in enumerate(line):
            if parts is None:
                assert aux["object"][row, x] == -1 and aux["material"][row, x] == -1
                continue
            hits += 1
            assert aux["material"][row, x] == parts["material"]
            np.testing.assert_allclose(aux["ambient"][row, x], parts["ambient"], rtol=1e-5)
            for i, (diffuse, specular, blocked) in enumerate(parts["lights"]):
                np.testing.assert_allclose(aux["diffuse"][row, x, i], diffuse, rtol=1e-5,
                                           atol=1e-7)
                np.testing.assert_allclose(aux["specular"][row, x, i], specular, rtol=1e-5,
                                           atol=1e-7)
                assert bool(aux["shadow"][row, x, i]) == blocked
            reflection = parts["reflection"]
            np.testing.assert_allclose(aux["reflection"][row, x],
                                       (0, 0, 0) if reflection is None else reflection,
                                       rtol=1e-5, atol=1e-7)
            assert (aux["mirror_depth"][row, x] > 0) == (reflection is not None)
    assert hits > 50


@pytest.mark.parametrize("name", ["course/spheres_mirror", "course/arch", "course/cubemap_mesh",
                                  "features/falloff", "features/specular_no_gate"])
@pytest.mark.parametrize("bounces,shadows", [(0, False), (4, True)])
def test_the_parts_add_up_to_the_color_image_bit_for_bit(name, bounces, shadows):
    scene = load_scene(bundled_path(name))
    opts = RenderOptions(width=24, height=24, bounces=bounces, shadows=shadows)
    plain = render(scene, opts)
    result = render(scene, RenderOptions(**{**opts.__dict__, "aux": AUX_KINDS}))
    np.testing.assert_array_equal(result.color, plain.color)  # asking for parts changes nothing
    hit = result.aux["object"] >= 0
    assert hit.any()
    composed = compose(result.aux, result.color)
    assert np.array_equal(composed.view(np.uint32)[hit] & 0x7FFFFFFF,
                          result.color.view(np.uint32)[hit] & 0x7FFFFFFF)  # ±0 alike


def test_the_light_terms_are_made_of_the_recorded_cosines_and_intensities():
    scene = parse_scene_text(MIRRORS, Path("mirrors.txt"))
    aux = render(scene, RenderOptions(width=12, height=12, shadows=True, aux=AUX_KINDS)).aux
    hit = aux["object"] >= 0
    kd = np.array([m.diffuse for m in scene.materials], np.float32)[aux["material"][hit]]
    nl = np.maximum(aux["cos_nl"][hit], np.float32(0))
    expected = (nl[..., None] * aux["intensity"][hit]) * kd[:, None, :]
    np.testing.assert_array_equal(aux["diffuse"][hit], expected)
    assert (aux["cos_rl"][hit] >= 0).all()


def test_object_and_material_images_number_the_leaves_in_file_order():
    scene = parse_scene_text(MIRRORS, Path("mirrors.txt"))
    objects = scene_objects(scene)
    assert [(o.kind, o.material, o.transformed) for o in objects] == \
        [("sphere", 0, False), ("sphere", 1, True), ("plane", 2, False)]
    aux = render(scene, RenderOptions(width=20, height=20, aux=("object", "material"))).aux
    obj, mat = aux["object"], aux["material"]
    assert set(np.unique(obj)) == {-1, 0, 1, 2}
    # the camera looks down at the plane: the bottom row is floor, the top row sky
    assert (obj[-1] == 2).all() and (obj[0] == -1).all()
    assert obj[10, 5] == 0 and obj[10, 15] == 1  # the left sphere left, the right one right
    assert np.array_equal(mat, np.where(obj >= 0, np.array([0, 1, 2])[obj], -1))


def test_a_mesh_is_one_object_over_all_its_faces(tmp_path):
    (tmp_path / "quad.obj").write_text("v -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\nf 1 2 3\nf 1 3 4\n")
    text = MIRRORS.replace("Plane { normal 0 1 0 offset -1 }", 'TriangleMesh { obj_file quad.obj }')
    (tmp_path / "s.txt").write_text(text)
    scene = load_scene(tmp_path / "s.txt")
    objects = scene_objects(scene)
    assert objects[2].kind == "mesh" and objects[2].count == 2 and objects[2].first_order == 2
    obj = render(scene, RenderOptions(width=16, height=16, aux=("object",))).aux["object"]
    assert set(np.unique(obj)) <= {-1, 0, 1, 2} and (obj == 2).any()


@pytest.mark.parametrize("changes,message", [
    ({"aux": ("nonsense",)}, "unknown auxiliary images"),
    ({"aux": ("object",), "jitter": True}, "without -jitter and -filter"),
    ({"aux": ("object",), "filter": True}, "without -jitter and -filter"),
    ({"aux": ("object",), "mode": "robust"}, "course-mode"),
])
def test_auxiliary_images_need_one_course_mode_primary_ray_per_pixel(changes, message):
    with pytest.raises(ValueError, match=message):
        render(parse_scene_text(MIRRORS, Path("mirrors.txt")),
               RenderOptions(width=4, height=4, **changes))


def test_a_scene_without_lights_has_per_light_images_of_no_lights():
    scene = parse_scene_text(MIRRORS.replace(MIRRORS[MIRRORS.index("Lights"):
                                                     MIRRORS.index("Background")], ""),
                             Path("dark.txt"))
    result = render(scene, RenderOptions(width=8, height=8, aux=AUX_KINDS))
    assert result.aux["diffuse"].shape == (8, 8, 0, 3) and result.aux["shadow"].shape == (8, 8, 0)
    hit = result.aux["object"] >= 0
    assert np.array_equal(compose(result.aux, result.color)[hit], result.color[hit])
