"""The translator (mitsuba_ref.translate): what each course construct becomes in Mitsuba.

Scenes are written inline and parsed with the course parser; the checks are on the plain plan
(mi.load_dict layout) that both the dict loader and the XML export consume.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from raycheck.mitsuba_ref import translate
from raycheck.mitsuba_ref.translate import PLANE_SCALE, Settings, plan
from raycheck.tracer.scene import parse_scene_text

CAM = "PerspectiveCamera { center 0 1 10 direction 0 -0.1 -1 up 0 1 0 angle 30 }\n"
LIGHT = "Lights { numLights 1 DirectionalLight { direction 0 -1 -1 color 1 1 1 } }\n"
MATS = """Materials { numMaterials 3
  Material { diffuseColor 0.9 0.2 0.1 specularColor 0.5 0.5 0.5 shininess 20 }
  Material { diffuseColor 0.1 0.4 0.9 }
  Material { diffuseColor 0.3 0.3 0.3 specularColor 0.05 0 0 shininess 3 }
}
"""


def scene_of(group: str, lights: str = LIGHT, extra: str = "", tmp: Path | None = None):
    text = CAM + lights + extra + MATS + group
    return parse_scene_text(text, (tmp or Path("/nonexistent")) / "scene.txt")


def kinds(p: dict, kind: str) -> dict[str, dict]:
    return {k: v for k, v in p.items() if isinstance(v, dict) and v.get("type") == kind}


def test_bare_sphere_is_a_native_sphere_with_its_material():
    s = scene_of("Group { numObjects 1 MaterialIndex 1 Sphere { center 1 2 3 radius 0.5 } }")
    p = plan(s, Settings())
    (sphere,) = kinds(p, "sphere").values()
    assert sphere["center"] == [1.0, 2.0, 3.0]
    assert sphere["radius"] == 0.5
    assert sphere["bsdf"] == {"type": "ref", "id": "mat_001"}
    # only the material the scene uses goes in
    assert list(kinds(p, "course_phong")) == ["mat_001"]
    assert p["mat_001"]["kd"] == {"type": "rgb", "value": [pytest.approx(0.1),
                                                          pytest.approx(0.4),
                                                          pytest.approx(0.9)]}


def test_sphere_under_similarity_stays_a_sphere():
    s = scene_of("""Group { numObjects 1 MaterialIndex 0
        Transform { Translate 1 0 0 ZRotate 30 UniformScale 2
            Sphere { center 1 0 0 radius 0.5 } } }""")
    p = plan(s, Settings())
    (sphere,) = kinds(p, "sphere").values()
    c = math.radians(30)
    assert sphere["center"] == pytest.approx([1 + 2 * math.cos(c), 2 * math.sin(c), 0], abs=1e-6)
    assert sphere["radius"] == pytest.approx(1.0, rel=1e-6)
    assert not kinds(p, "instance")


def test_sphere_under_non_uniform_scale_becomes_an_instance():
    s = scene_of("""Group { numObjects 1 MaterialIndex 0
        Transform { Translate 0 1 0 Scale 2 0.5 1 Sphere { center 0 0 0 radius 1 } } }""")
    p = plan(s, Settings())
    (group,) = kinds(p, "shapegroup").items()
    assert group[1]["sphere"] == {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0,
                                  "bsdf": {"type": "ref", "id": "mat_000"}}
    (inst,) = kinds(p, "instance").values()
    assert inst["shapegroup"] == {"type": "ref", "id": group[0]}
    expected = np.diag([2.0, 0.5, 1.0, 1.0])
    expected[1, 3] = 1.0
    np.testing.assert_allclose(inst["to_world"], expected)
    assert not kinds(p, "sphere")


def test_nested_transforms_compose_parent_times_child():
    s = scene_of("""Group { numObjects 1 MaterialIndex 0
        Transform { Translate 5 0 0
            Transform { Scale 1 3 1 Sphere { center 0 1 0 radius 1 } } } }""")
    (inst,) = kinds(plan(s, Settings()), "instance").values()
    np.testing.assert_allclose(inst["to_world"][:3, :3], np.diag([1, 3, 1]))
    np.testing.assert_allclose(inst["to_world"][:3, 3], [5, 0, 0])


def test_bare_plane_is_a_large_disk_with_the_raw_normal_length_on_its_material():
    s = scene_of("""Group { numObjects 2 MaterialIndex 1 Plane { normal 0 2 0 offset -2 }
        MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }""")
    p = plan(s, Settings())
    (disk,) = kinds(p, "disk").values()
    m = disk["to_world"]
    n = m[:3, 2] / np.linalg.norm(m[:3, 2])
    np.testing.assert_allclose(n, [0, 1, 0], atol=1e-12)
    assert m[1, 3] == pytest.approx(-1.0)  # the plane 2y = -2
    # radius: PLANE_SCALE times the scene's extent (camera and sphere here)
    radius = np.linalg.norm(m[:3, 0])
    assert radius > PLANE_SCALE * 10
    assert np.linalg.norm(m[:3, 0]) == pytest.approx(np.linalg.norm(m[:3, 2]))  # similarity
    # the raw normal (0,2,0) is twice the disk's unit normal: a material copy carries it
    bsdf = disk["bsdf"]["id"]
    assert p[bsdf]["normal_scale"] == 2.0 and bsdf != "mat_001"
    assert p[bsdf]["kd"]["value"] == pytest.approx([0.1, 0.4, 0.9])
    # the camera reaches past the disk's rim
    assert p["camera"]["far_clip"] > radius


def test_unit_and_transformed_planes_share_the_material_and_use_the_transformed_plane():
    s = scene_of("""Group { numObjects 2 MaterialIndex 1 Plane { normal 0 1 0 offset -1 }
        Transform { Scale 1 2 1 Plane { normal 1 1 0 offset 3 } } }""")
    p = plan(s, Settings())
    disks = list(kinds(p, "disk").values())
    assert [d["bsdf"]["id"] for d in disks] == ["mat_001", "mat_001"]
    m = disks[1]["to_world"]
    n = m[:3, 2] / np.linalg.norm(m[:3, 2])
    # x + y = 3 in child space, y scaled by 2: x + y/2 = 3, unit normal along (1, 0.5, 0)
    np.testing.assert_allclose(n, np.array([1, 0.5, 0]) / math.sqrt(1.25), atol=1e-12)
    foot = m[:3, 3]
    assert foot[0] + foot[1] / 2 == pytest.approx(3.0)


def test_zero_normal_plane_is_left_out():
    s = scene_of("Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 0 offset 1 } }")
    p = plan(s, Settings())
    assert not kinds(p, "disk") and not kinds(p, "course_phong")
    assert "far_clip" not in p["camera"]


def test_triangles_become_one_mesh_per_material_with_face_normals(tmp_path: Path):
    s = scene_of("""Group { numObjects 3 MaterialIndex 0
        Triangle { vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 0 }
        Triangle { vertex0 0 0 0 vertex1 0 1 0 vertex2 1 0 0 }
        MaterialIndex 1
        Transform { Translate 0 0 2 Scale 2 1 1
            Triangle { vertex0 0 0 0 vertex1 1 0 0 vertex2 0 0 1 } } }""")
    p = plan(s, Settings())
    meshes = kinds(p, "mesh")
    assert len(meshes) == 2
    first, second = (m["data"] for m in meshes.values())
    v, n = first.world()
    assert v.shape == (6, 3) and first.faces.tolist() == [[0, 1, 2], [3, 4, 5]]
    np.testing.assert_array_equal(n[:3], [[0, 0, 1]] * 3)   # cross(v1-v0, v2-v0)
    np.testing.assert_array_equal(n[3:], [[0, 0, -1]] * 3)  # wound the other way: not flipped
    v, n = second.world()
    np.testing.assert_allclose(v, [[0, 0, 2], [2, 0, 2], [0, 0, 3]])
    np.testing.assert_allclose(n / np.linalg.norm(n, axis=1)[:, None], [[0, -1, 0]] * 3)


def test_mesh_keeps_course_normals_and_transforms_them_unnormalized(tmp_path: Path):
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                    "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    s = scene_of("Group { numObjects 1 MaterialIndex 2 Transform { Scale 3 1 1 "
                 "TriangleMesh { obj_file m.obj } } }", tmp=tmp_path)
    (mesh,) = kinds(plan(s, Settings()), "mesh").values()
    data = mesh["data"]
    parsed = s.root.objects[0].child
    np.testing.assert_array_equal(data.normals, parsed.normals)  # the parser's course normals
    v, n = data.world()
    np.testing.assert_allclose(v, parsed.vertices * [3, 1, 1])
    # M^-T n, left unnormalized so that Mitsuba's normalize(interpolation) is the course's
    np.testing.assert_allclose(n, parsed.normals * [1 / 3, 1, 1], rtol=1e-6)
    assert not data.flat  # 4 shared vertices: smooth


def test_lights_in_file_order_point_intensity_is_color_over_falloff():
    lights = """Lights { numLights 4
        PointLight { position 1 2 3 color 1 0.5 0.25 falloff 0.5 }
        DirectionalLight { direction 0 -1 0 color 0.3 0.3 0.3 }
        PointLight { falloff 0.5 }
        PointLight { position 0 5 0 color 1 1 0 } }
"""
    s = scene_of("Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }",
                 lights=lights)
    p = plan(s, Settings())
    emitters = {k: v for k, v in p.items() if k.startswith("light_")}
    # the zero-colour light adds exactly 0 everywhere and is left out
    assert list(emitters) == ["light_000", "light_001", "light_003"]
    assert emitters["light_000"] == {"type": "point", "position": [1.0, 2.0, 3.0],
                                     "intensity": {"type": "rgb", "value": [2.0, 1.0, 0.5]}}
    assert emitters["light_001"]["type"] == "directional"
    assert emitters["light_001"]["direction"] == [0.0, -1.0, 0.0]
    assert emitters["light_001"]["irradiance"]["value"] == pytest.approx([0.3] * 3)
    # falloff 0: color/0 is inf (and 0/0 NaN), as in the course
    inf = emitters["light_003"]["intensity"]["value"]
    assert inf[:2] == [math.inf, math.inf] and math.isnan(inf[2])


def test_integrator_and_sensor_carry_the_command_line():
    s = scene_of("Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }",
                 extra="Background { color 0.1 0.2 0.3 ambientLight 0.4 0.5 0.6 }\n")
    p = plan(s, Settings(width=30, height=20, bounces=3, shadows=True, filter=True,
                         kinds=("color", "normals", "depth"), depth_min=2, depth_max=5))
    integ = p["integrator"]
    assert integ["type"] == "course_whitted" and integ["bounces"] == 3 and integ["shadows"]
    assert integ["background"]["value"] == pytest.approx([0.1, 0.2, 0.3])
    assert integ["ambient"]["value"] == pytest.approx([0.4, 0.5, 0.6])
    assert (integ["normals"], integ["depth"], integ["depth_min"], integ["depth_max"]) == \
        (True, True, 2.0, 5.0)
    cam = p["camera"]
    assert cam["type"] == "course_camera" and cam["angle"] == 30.0
    assert cam["up"] == [0.0, 1.0, 0.0]  # raw, as written
    # -filter renders the 3w x 3h sub-pixel grid
    assert (cam["film"]["width"], cam["film"]["height"]) == (90, 60)
    assert cam["film"]["rfilter"] == {"type": "box"}
    assert cam["sampler"] == {"type": "stratified", "sample_count": 1, "jitter": False}
    assert "jitter" not in cam

    j = plan(s, Settings(jitter=True, seed=7))["camera"]
    assert j["jitter"] is True
    assert j["sampler"] == {"type": "independent", "sample_count": 16, "seed": 7}
    # Mitsuba's seed is below 2^32: a 64-bit seed wraps, 5e9 - 2^32 = 705_032_704
    big = plan(s, Settings(jitter=True, seed=5_000_000_000))["camera"]["sampler"]["seed"]
    assert big == 705_032_704


def test_only_what_the_scene_needs():
    # no lights: no emitters, no shadow rays even with -shadows; no cube map; AOVs only if asked
    s = scene_of("Group { numObjects 1 MaterialIndex 2 Sphere { center 0 0 0 radius 1 } }",
                 lights="")
    p = plan(s, Settings(shadows=True))
    assert not [k for k in p if k.startswith("light_")]
    assert "shadows" not in p["integrator"] and "cube_map" not in p["integrator"]
    assert not {"normals", "depth", "bounces"} & set(p["integrator"])
    assert list(kinds(p, "course_phong")) == ["mat_002"]
    # ambient forced to 1 by the parser when there is no light
    assert p["integrator"]["ambient"]["value"] == [1.0, 1.0, 1.0]


def test_cube_map_goes_to_the_integrator_as_a_folder(tmp_path: Path):
    from PIL import Image

    (tmp_path / "sky").mkdir()
    for name in ("left", "right", "up", "down", "front", "back"):
        Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / "sky" / f"{name}.png")
    s = scene_of("Group { numObjects 0 }", extra="Background { cubeMap sky }\n", tmp=tmp_path)
    integ = plan(s, Settings())["integrator"]
    assert Path(integ["cube_map"]) == (tmp_path / "sky").resolve()
    assert "background" not in integ


def test_load_dict_form_builds_mitsuba_objects():
    import mitsuba as mi

    s = scene_of("""Group { numObjects 3 MaterialIndex 0 Sphere { center 0 0 0 radius 1 }
        Triangle { vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 0 }
        Transform { Scale 2 1 1 Sphere { center 0 0 0 radius 1 } } }""")
    d = translate.load_dict_form(plan(s, Settings()))
    (mesh,) = [v for v in d.values() if isinstance(v, mi.Mesh)]
    assert mesh.face_count() == 1 and mesh.has_vertex_normals()
    assert d["shape_0001"]["type"] == "instance"
    assert isinstance(d["shape_0001"]["to_world"], mi.ScalarTransform4f)
    # every material reference is the one shared BSDF object
    assert d["shape_0000"]["bsdf"] is mesh.bsdf()
    scene = mi.load_dict(d)
    assert len(scene.shapes()) == 3
    del scene


def test_objects_under_a_singular_transform_are_never_hit():
    # M^-1 is inf/NaN in the course's arithmetic, so rays never reach the child
    s = scene_of("""Group { numObjects 3 MaterialIndex 0
        Transform { Scale 0 1 1 Sphere { center 0 0 0 radius 1 } }
        Transform { Rotate { 0 0 0 30 } Plane { normal 0 1 0 offset -1 } }
        Transform { Translate 1 0 0 Transform { Scale 1 1 0
            Triangle { vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 0 } } } }""")
    p = plan(s, Settings())
    assert not [k for k in p if k.startswith("shape_") or k.startswith("group_")]
    assert not kinds(p, "course_phong")
