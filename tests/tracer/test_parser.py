"""The course scene parser: every rule of spec §1-3 and its error messages."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from raycheck.tracer.scene import (
    DirectionalLight,
    Mesh,
    Plane,
    PointLight,
    SceneError,
    Sphere,
    Transform,
    Triangle,
    load_scene,
    parse_scene_text,
)
from raycheck.tracer.scene.lexer import tokenize

CAM = "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
P = Path("/scenes/x.txt")


def parse(text: str):
    return parse_scene_text(text, P)


def parse_error(text: str) -> str:
    with pytest.raises(SceneError) as e:
        parse(text)
    return str(e.value)


# --- lexing ---------------------------------------------------------------------------------
def test_one_closing_brace_glued_to_a_number_is_split():
    toks = [t.text for t in tokenize("shininess 20} } x 1e-3} -.16} 20}}")]
    assert toks == ["shininess", "20", "}", "}", "x", "1e-3", "}", "-.16", "}", "20}}"]


def test_two_closing_braces_glued_to_a_number_are_an_error():
    # the course reads the number, then the token '}}', and aborts
    msg = parse_error(CAM + "Lights { numLights 1 PointLight { falloff 0.1}}\n")
    assert msg == ("/scenes/x.txt:2: expected a number for falloff, found '0.1}}': only one '}' "
                   "may follow a number (separate the others with spaces)")


def test_opening_brace_glued_to_keyword_is_an_error():
    msg = parse_error(CAM + "Materials { numMaterials 1 Material {diffuseColor 1 0 0 } }")
    assert msg == "/scenes/x.txt:2: expected '{', found '{diffuseColor'"


def test_c_float_syntax():
    s = parse(CAM + "Background { color -.5 1e-1 5 }")
    assert s.background.color == (-0.5, float(np.float32(0.1)), 5.0)


def test_comments_are_an_extension_and_lines_are_counted():
    s = parse("# a comment\n" + CAM + "Lights { numLights 1 PointLight { } }\n"
              "Background { color 1 1 1 # trailing\n ambientLight 1 0 0 }\n")
    assert s.background.ambient == (1.0, 0.0, 0.0)
    assert parse_error("# a comment\n" + CAM + "2.5").startswith("/scenes/x.txt:3: expected one")


def test_keywords_are_case_sensitive():
    assert "found 'background'" in parse_error(CAM + "background { }")


# --- top level ------------------------------------------------------------------------------
def test_defaults_when_blocks_are_missing():
    s = parse(CAM)
    assert s.background.color == (0.5, 0.5, 0.5)
    assert s.materials == () and s.lights == () and s.root.objects == ()


def test_missing_camera_is_an_error():
    assert parse_error("Background { }") == "/scenes/x.txt: no PerspectiveCamera block"


def test_later_block_replaces_earlier():
    s = parse(CAM + "Background { color 1 0 0 }\nBackground { ambientLight 0.5 0.5 0.5 }\n"
              "Lights { numLights 1 PointLight { } }")
    assert s.background.color == (0.5, 0.5, 0.5)  # the second block's default, not red
    assert s.background.ambient == (0.5, 0.5, 0.5)


def test_camera_fields_fixed_order():
    msg = parse_error("PerspectiveCamera { direction 0 0 -1 center 0 0 0 up 0 1 0 angle 30 }")
    assert msg == "/scenes/x.txt:1: expected 'center', found 'direction'"


def test_camera_values():
    s = parse("PerspectiveCamera {\n center 1 2 3\n direction 0 0 -1\n up 0 1 0.5\n angle 45\n}")
    c = s.camera
    assert (c.center, c.direction, c.up, c.angle_deg) == ((1, 2, 3), (0, 0, -1), (0, 1, 0.5), 45)


# --- lights ---------------------------------------------------------------------------------
def test_directional_light_is_normalized_and_fixed_order():
    s = parse(CAM + "Lights { numLights 1 DirectionalLight { direction 0 0 -2 color 1 1 1 } }")
    (li,) = s.lights
    assert isinstance(li, DirectionalLight) and li.direction == (0.0, 0.0, -1.0)
    assert "expected 'direction'" in parse_error(
        CAM + "Lights { numLights 1 DirectionalLight { color 1 1 1 direction 0 0 -1 } }")


def test_point_light_any_order_and_defaults():
    s = parse(CAM + "Lights { numLights 2 PointLight { falloff 0.5 position 1 2 3 }"
              " PointLight { } }")
    a, b = s.lights
    assert isinstance(a, PointLight) and a.position == (1, 2, 3) and a.falloff == 0.5
    assert a.color == (0, 0, 0)
    assert (b.position, b.color, b.falloff) == ((0, 0, 0), (0, 0, 0), 0.0)


def test_light_count_mismatch():
    msg = parse_error(CAM + "Lights { numLights 2\n PointLight { } }")
    assert msg == "/scenes/x.txt:3: expected DirectionalLight or PointLight, found '}'"
    msg = parse_error(CAM + "Lights { numLights 1\n PointLight { }\n PointLight { } }")
    assert msg == "/scenes/x.txt:4: expected '}' after 1 lights, found 'PointLight'"


def test_no_lights_forces_white_ambient():
    for lights in ("", "Lights { numLights 0 }\n"):
        s = parse(CAM + lights + "Background { ambientLight 0.2 0.3 0.4 }")
        assert s.background.ambient == (1.0, 1.0, 1.0)
    s = parse(CAM + "Lights { numLights 1 PointLight { } } Background { ambientLight 0.25 0 0 }")
    assert s.background.ambient == (0.25, 0, 0)


# --- materials ------------------------------------------------------------------------------
def test_materials_any_order_defaults_bump_and_phong_alias():
    s = parse(CAM + "Materials { numMaterials 3\n"
              " Material { shininess 20} \n"
              " PhongMaterial { specularColor 1 1 1 bump whatever.png diffuseColor 0 1 0 }\n"
              " Material { } }")
    a, b, c = s.materials
    assert (a.diffuse, a.specular, a.shininess) == ((1, 1, 1), (0, 0, 0), 20)
    assert (b.diffuse, b.specular) == ((0, 1, 0), (1, 1, 1))
    assert (c.diffuse, c.specular, c.shininess) == ((1, 1, 1), (0, 0, 0), 0)


def test_unknown_material_field():
    msg = parse_error(CAM + "Materials { numMaterials 1\n Material { transparency 1 } }")
    assert msg.startswith("/scenes/x.txt:3: expected diffuseColor, specularColor, shininess, bump")
    assert msg.endswith("found 'transparency'")


# --- groups and objects ---------------------------------------------------------------------
MATS = "Materials { numMaterials 3 Material { } Material { } Material { } }\n"


def test_material_index_is_global_state_not_scoped():
    s = parse(CAM + MATS + """Group { numObjects 3
      MaterialIndex 0
      Group { numObjects 1 MaterialIndex 2 Sphere { center 0 0 0 radius 1 } }
      Sphere { center 1 0 0 radius 1 }
      MaterialIndex 1
      Plane { normal 0 1 0 offset -2 }
    }""")
    inner, after, plane = s.root.objects
    assert inner.objects[0].material == 2
    assert after.material == 2  # the nested group's MaterialIndex outlives the group
    assert plane.material == 1


def test_object_before_material_index():
    msg = parse_error(CAM + MATS + "Group { numObjects 1\n Sphere { center 0 0 0 radius 1 } }")
    assert msg == "/scenes/x.txt:4: Sphere before any MaterialIndex"


def test_material_index_out_of_range():
    msg = parse_error(CAM + MATS + "Group { numObjects 1\n MaterialIndex 3 "
                      "Sphere { center 0 0 0 radius 1 } }")
    assert msg == "/scenes/x.txt:4: MaterialIndex 3 out of range: the scene has 3 materials"


def test_materials_block_may_follow_group():
    s = parse(CAM + "Group { numObjects 1 MaterialIndex 1 Sphere { center 0 0 0 radius 1 } }\n"
              + MATS)
    assert s.root.objects[0].material == 1


def test_object_count_must_match():
    msg = parse_error(CAM + MATS + "Group { numObjects 2 MaterialIndex 0\n"
                      "Sphere { center 0 0 0 radius 1 }\n}")
    assert msg == "/scenes/x.txt:5: expected an object (1 of 2 read): one of Group, Transform, " \
                  "Sphere, Plane, Triangle, TriangleMesh, found '}'"
    msg = parse_error(CAM + MATS + "Group { numObjects 0 MaterialIndex 0\n"
                      "Sphere { center 0 0 0 radius 1 }\n}")
    assert msg == "/scenes/x.txt:4: expected '}' after 0 objects, found 'Sphere'"


def test_primitives_fields():
    s = parse(CAM + MATS + """Group { numObjects 3 MaterialIndex 0
      Sphere { center 1 2 3 radius 0.5 }
      Plane { normal 0 2 0 offset -2 }
      Triangle { vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 0 } }""")
    sp, pl, tr = s.root.objects
    assert isinstance(sp, Sphere) and (sp.center, sp.radius) == ((1, 2, 3), 0.5)
    assert isinstance(pl, Plane) and (pl.normal, pl.offset) == ((0, 2, 0), -2)  # not normalized
    assert isinstance(tr, Triangle) and tr.v1 == (1, 0, 0)


def test_end_of_file_inside_block():
    msg = parse_error(CAM + MATS + "Group { numObjects 1 MaterialIndex 0\nSphere { center 0 0")
    assert msg == "/scenes/x.txt:4: expected a number for center, found end of file"


def test_count_not_an_integer():
    assert parse_error(CAM + "Lights { numLights 1.5 }") == \
        "/scenes/x.txt:2: expected an integer for numLights, found '1.5'"
    assert parse_error(CAM + "Lights { numLights -1 }") == \
        "/scenes/x.txt:2: numLights must be in 0..10000000, found -1"


def test_nesting_limit():
    deep = ("Group { numObjects 1 " * 70 + "MaterialIndex 0 Sphere { center 0 0 0 radius 1 }"
            + " }" * 70)
    assert "nested deeper than 64 levels" in parse_error(CAM + MATS + deep)


# --- transforms -----------------------------------------------------------------------------
def _matrix(ops: str) -> np.ndarray:
    s = parse(CAM + MATS + "Group { numObjects 1 MaterialIndex 0 Transform { " + ops
              + " Sphere { center 0 0 0 radius 1 } } }")
    (t,) = s.root.objects
    assert isinstance(t, Transform)
    return t.matrix


def test_translate_then_scale_applies_scale_first():
    m = _matrix("Translate 1 2 3 Scale 2 3 4")
    p = m @ np.array([1, 1, 1, 1], np.float32)
    assert p.tolist() == [3, 5, 7, 1]  # T(t)·S(s)·p


def test_uniform_scale_and_axis_rotations():
    assert np.array_equal(_matrix("UniformScale 2"), np.diag([2, 2, 2, 1]).astype(np.float32))
    x = _matrix("ZRotate 90") @ np.array([1, 0, 0, 1], np.float32)
    assert np.allclose(x, [0, 1, 0, 1], atol=1e-7)  # right-handed: x goes to y
    y = _matrix("XRotate 90") @ np.array([0, 1, 0, 1], np.float32)
    assert np.allclose(y, [0, 0, 1, 1], atol=1e-7)
    z = _matrix("YRotate 90") @ np.array([0, 0, 1, 1], np.float32)
    assert np.allclose(z, [1, 0, 0, 1], atol=1e-7)


def test_a_rotation_by_an_overflowing_angle_is_nan_as_in_c():
    # 1e39 is inf in float32 (strtof); C's cos and sin of inf are NaN, and so is the matrix's
    # rotation block and, through 0 * NaN in the product with the identity, the row below it
    m = _matrix("ZRotate 1e39")
    assert np.isnan(m[:3, :2]).all() and m[:3, 2:].tolist() == [[0, 0], [0, 0], [1, 0]]


def test_rotate_normalizes_its_axis():
    assert np.allclose(_matrix("Rotate { 0 0 5 90 }"), _matrix("ZRotate 90"), atol=1e-7)
    m = _matrix("Rotate { 1 1 1 120 }")  # cycles the axes x -> y -> z
    assert np.allclose(m @ np.array([1, 0, 0, 1], np.float32), [0, 1, 0, 1], atol=1e-6)


def test_composed_ops_round_each_step_of_their_product_to_float32():
    """XRotate 30 YRotate 45 ZRotate 60 (features/xyz_rotate): every entry of each product is
    its four float32 products summed left to right, each sum rounded, as the course's matrix
    class computes it (a product with fused multiply-adds moved 3 pixels of that scene at
    128x128 by one level)."""
    f32 = np.float32

    def rotation(axis: int, deg: float) -> np.ndarray:
        a = float(f32(np.pi * deg / 180.0))
        c, s = f32(np.cos(a)), f32(np.sin(a))
        i, j = [k for k in range(3) if k != axis]
        r = np.eye(4, dtype=f32)
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
        if axis == 1:  # about y the sines swap places (z x x = y)
            r[i, j], r[j, i] = s, -s
        return r

    def stepwise(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        out = np.zeros((4, 4), f32)
        for i in range(4):
            for j in range(4):
                acc = f32(a[i, 0] * b[0, j])
                for k in range(1, 4):
                    acc = f32(acc + f32(a[i, k] * b[k, j]))
                out[i, j] = acc
        return out

    want = stepwise(stepwise(stepwise(np.eye(4, dtype=f32), rotation(0, 30)), rotation(1, 45)),
                    rotation(2, 60))
    assert _matrix("XRotate 30 YRotate 45 ZRotate 60").tobytes() == want.tobytes()


def test_matrix4f_is_column_major_and_left_multiplies():
    cols = "1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1"  # column 3 holds the translation
    m = _matrix(f"Matrix4f {{ {cols} }}")
    assert m[:3, 3].tolist() == [5, 6, 7]
    # Scale first (right-multiplied onto I), then Matrix4f left-multiplies: M = File · S
    m = _matrix(f"Scale 2 2 2 Matrix4f {{ {cols} }}")
    assert (m @ np.array([1, 1, 1, 1], np.float32)).tolist() == [7, 8, 9, 1]
    # and a later op still right-multiplies: M = File · S · T
    m = _matrix(f"Scale 2 2 2 Matrix4f {{ {cols} }} Translate 1 0 0")
    assert (m @ np.array([0, 0, 0, 1], np.float32)).tolist() == [7, 6, 7, 1]


def test_transform_needs_exactly_one_object():
    assert "expected a transform op or one object, found '}'" in parse_error(
        CAM + MATS + "Group { numObjects 1 MaterialIndex 0 Transform { Translate 1 0 0 } }")
    assert "expected '}', found 'Sphere'" in parse_error(
        CAM + MATS + "Group { numObjects 1 MaterialIndex 0 Transform { "
        "Sphere { center 0 0 0 radius 1 } Sphere { center 0 0 0 radius 1 } } }")


def test_nested_transforms_keep_their_matrices():
    s = parse(CAM + MATS + """Group { numObjects 1 MaterialIndex 0
      Transform { Translate 1 0 0 Group { numObjects 1
        Transform { UniformScale 3 Sphere { center 0 0 0 radius 1 } } } } }""")
    outer = s.root.objects[0]
    inner = outer.child.objects[0]
    assert outer.matrix[0, 3] == 1 and inner.matrix[0, 0] == 3


# --- OBJ meshes and relative paths ----------------------------------------------------------
OBJ = """# a quad made of two triangles sharing an edge
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 1
vt 0 0
vn 0 0 1
f 1/1 2/1 3/1
f 1 3 4 99
"""


def test_obj_mesh_relative_path_and_normal_averaging(tmp_path: Path):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "quad.obj").write_text(OBJ)
    scene_file = tmp_path / "s.txt"
    scene_file.write_text(CAM + MATS + "Group { numObjects 1 MaterialIndex 2 "
                          "TriangleMesh { obj_file meshes/quad.obj } }")
    s = load_scene(scene_file)
    (mesh,) = s.root.objects
    assert isinstance(mesh, Mesh) and mesh.material == 2
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3]]  # only the first three indices
    n1 = np.array([0, 0, 1], np.float32)  # face (v1, v2, v3)
    n2 = np.cross([1, 1, 0], [0, 1, 1]).astype(np.float32)
    n2 = n2 / np.sqrt(np.dot(n2, n2))
    shared = (n1 + n2) / np.linalg.norm(n1 + n2)
    assert np.allclose(mesh.normals[0], shared, atol=1e-7)  # vertex 1 is in both faces
    assert np.allclose(mesh.normals[1], n1, atol=0)  # vertex 2 only in face 1: flat
    assert np.allclose(mesh.normals[3], n2, atol=1e-7)


def test_obj_errors(tmp_path: Path):
    scene_file = tmp_path / "s.txt"
    scene_file.write_text(CAM + MATS + "Group { numObjects 1 MaterialIndex 0\n"
                          "TriangleMesh { obj_file missing.obj } }")
    with pytest.raises(SceneError) as e:
        load_scene(scene_file)
    assert str(e.value) == f"{scene_file}:4: OBJ file not found: {tmp_path / 'missing.obj'}"
    (tmp_path / "missing.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
    with pytest.raises(SceneError) as e:
        load_scene(scene_file)
    assert str(e.value) == f"{tmp_path / 'missing.obj'}:4: face index out of range 1..3: 1 2 4"


def test_scene_file_rules(tmp_path: Path):
    with pytest.raises(SceneError, match="must end in .txt"):
        load_scene(tmp_path / "scene.scn")
    with pytest.raises(SceneError, match="scene file not found"):
        load_scene(tmp_path / "none.txt")
    bad = tmp_path / "bin.txt"
    bad.write_bytes(CAM.encode() + b"\xff\xfe")
    with pytest.raises(SceneError, match=r"bin.txt:2: scene file is not text"):
        load_scene(bad)


def test_cube_map_loading(tmp_path: Path):
    from PIL import Image

    sky = tmp_path / "sky"
    sky.mkdir()
    for i, name in enumerate(("left", "right", "up", "down", "front", "back")):
        Image.fromarray(np.full((2, 3, 3), 40 * i, np.uint8)).save(sky / f"{name}.png")
    f = tmp_path / "s.txt"
    f.write_text(CAM + "Background { cubeMap sky }")
    cube = load_scene(f).background.cube_map
    assert cube.faces["up"].shape == (2, 3, 3)
    assert cube.faces["up"][0, 0, 0] == np.float32(80) / np.float32(255)
    (sky / "down.png").unlink()
    with pytest.raises(SceneError) as e:
        load_scene(f)
    assert str(e.value) == f"{f}:2: cube-map face not found: {sky / 'down.png'}"


def test_large_cube_map_faces_are_decoded_once_per_content(tmp_path: Path, monkeypatch):
    """Faces of CACHED_FACE_TEXELS or more are kept decoded in the per-machine cache, keyed by
    their bytes: a second load decodes nothing and gives the same texels; an edited face or a
    damaged entry is decoded again; smaller faces are not kept."""
    from PIL import Image

    from raycheck.tracer.scene import CubeMap, cubemap

    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "cache"))
    decoded = []
    real = cubemap._decode
    monkeypatch.setattr(cubemap, "_decode", lambda data, path, *a: decoded.append(path.name)
                        or real(data, path, *a))
    rng = np.random.default_rng(5)
    sky = tmp_path / "sky"
    sky.mkdir()
    sizes = {"left": (256, 256), "right": (255, 256)}  # 65536 texels, and one row fewer
    for name in CubeMap.FACE_NAMES:
        Image.fromarray(rng.integers(0, 256, (*sizes.get(name, (256, 257)), 3), np.uint8)) \
            .save(sky / f"{name}.png")
    f = tmp_path / "s.txt"
    f.write_text(CAM + "Background { cubeMap sky }")
    first = load_scene(f).background.cube_map
    assert sorted(decoded) == sorted(f"{n}.png" for n in CubeMap.FACE_NAMES)
    entries = sorted((tmp_path / "cache" / "faces").iterdir())
    assert len(entries) == 5  # all but the 255x256 face
    decoded.clear()
    again = load_scene(f).background.cube_map
    assert decoded == ["right.png"]
    for name in CubeMap.FACE_NAMES:
        assert again.rgb8[name].dtype == np.uint8
        np.testing.assert_array_equal(again.rgb8[name], first.rgb8[name])
        np.testing.assert_array_equal(again.rgb8[name],
                                      np.asarray(Image.open(sky / f"{name}.png")))
    decoded.clear()
    Image.fromarray(np.full((256, 256, 3), 9, np.uint8)).save(sky / "left.png")
    up = tmp_path / "cache" / "faces" / f"{cubemap._cache_key((sky / 'up.png').read_bytes())}.npz"
    up.write_bytes(up.read_bytes()[:100])  # an entry cut short
    edited = load_scene(f).background.cube_map
    assert sorted(decoded) == ["left.png", "right.png", "up.png"]
    assert edited.rgb8["left"].tolist() == np.full((256, 256, 3), 9).tolist()
    assert edited.faces["left"][0, 0, 0] == np.float32(9) / np.float32(255)
    np.testing.assert_array_equal(edited.rgb8["up"], first.rgb8["up"])
    assert up.stat().st_size > 3 * 256 * 257  # written whole again


def test_the_cache_folder_without_a_home(tmp_path: Path, monkeypatch):
    """No HOME and no passwd entry (some containers): Path.home() raises, and the cache is a
    folder of the user's in the temporary directory instead of a traceback."""
    import os
    import pwd
    import tempfile

    from raycheck.tracer.cache import cache_folder

    def no_entry(uid):
        raise KeyError(uid)

    monkeypatch.delenv("RAYCHECK_CACHE", raising=False)
    monkeypatch.delenv("HOME", raising=False)
    monkeypatch.setattr(pwd, "getpwuid", no_entry)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    assert cache_folder() == tmp_path / f"raycheck-cache-{os.getuid()}"
    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "c"))
    assert cache_folder() == tmp_path / "c"


def test_obj_short_lines_are_skipped_and_only_v_and_f_count():
    from raycheck.tracer.scene.obj import parse_obj

    text = "v\nf\nv 0 0 0\nv 1 0 0\nvn 0 0 1\nvt 0.5 0.5\ng group\ns off\nv 0 1 0\nf 3 1 2\n"
    v, f = parse_obj(text, Path("/m.obj"))
    assert v.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    assert f.tolist() == [[2, 0, 1]]
