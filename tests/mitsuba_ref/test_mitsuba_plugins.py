"""The Mitsuba-side plugins on small scenes, against values worked out from the spec.

course_camera (spec §4, §9), course_phong (§6 shade), course_whitted (§6-8), the cube-map lookup
(§7), and the render module's quantisation and -filter kernel (§8, §9).
"""
from __future__ import annotations

import math
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import raycheck.mitsuba_ref  # noqa: F401  (registers the plugins)
from raycheck.mitsuba_ref.bsdf import powf
from raycheck.mitsuba_ref.cubemap import CubeMapLookup
from raycheck.mitsuba_ref.image import to_bytes
from raycheck.mitsuba_ref.render import ReferenceOptions, ReferenceRenderer, filter_121
from raycheck.tracer.scene import parse_scene_text
from raycheck.tracer.scene.model import CubeMap


# ----------------------------------------------------------------------------- camera
def camera(width: int, height: int, jitter: bool = False, up=(0.0, 1.0, 0.0),
           center=(0.0, 0.0, 10.0), direction=(0.0, 0.0, -1.0), angle=90.0):
    return mi.load_dict({
        "type": "course_camera", "center": list(center), "direction": list(direction),
        "up": list(up), "angle": angle, "jitter": jitter, "far_clip": 123.0,
        "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
                 "pixel_format": "rgb"},
    })


def spec_direction(x: float, y: float, w: int, h: int, up, center_dir=(0, 0, -1), angle=90.0):
    """Spec §4 in float64: pixel (x, y), y = 0 the bottom row."""
    d = np.array(center_dir, float)
    u_ = np.cross(d, np.array(up, float))
    wv, uv, vv = d / np.linalg.norm(d), u_ / np.linalg.norm(u_), np.array(up, float)
    dist = 1 / math.tan(math.radians(angle) / 2)
    ndcx, ndcy = 2 * x / (w - 1) - 1, 2 * y / (h - 1) - 1
    r = dist * wv + ndcx * uv + ndcy * vv
    return r / np.linalg.norm(r)


def sample_rays(sensor, film_xy: list[tuple[float, float]]):
    w, h = sensor.film().size()
    pos = mi.Point2f([p[0] / w for p in film_xy], [p[1] / h for p in film_xy])
    ray, weight = sensor.sample_ray(0.0, 0.0, pos, mi.Point2f(0.5))
    return np.array(ray.o).T, np.array(ray.d).T, np.array(ray.maxt), np.array(weight)


def test_camera_edge_pixels_look_along_ndc_plus_minus_one_without_aspect_correction():
    w, h = 5, 3
    sensor = camera(w, h)
    # film row r is course row y = h - 1 - r; Mitsuba passes the pixel centre (x + 0.5)
    film = [(0.5, 2.5), (4.5, 0.5), (2.5, 1.5), (0.5, 0.5)]
    course = [(0, 0), (4, 2), (2, 1), (0, 2)]
    o, d, maxt, weight = sample_rays(sensor, film)
    for k, (x, y) in enumerate(course):
        np.testing.assert_allclose(d[k], spec_direction(x, y, w, h, (0, 1, 0)), atol=1e-6)
    # corner rays at 45 degrees in both axes for a 90-degree angle, whatever the aspect
    np.testing.assert_allclose(d[0], np.array([-1, -1, -1]) / math.sqrt(3), atol=1e-6)
    np.testing.assert_allclose(np.broadcast_to(o, (4, 3)), [[0, 0, 10]] * 4)  # from the eye
    np.testing.assert_allclose(maxt, 123.0)
    np.testing.assert_allclose(weight, 1.0)


def test_camera_uses_up_raw():
    up = (0.4, 1.0, 0.5)
    sensor = camera(4, 4, up=up, angle=30)
    o, d, _, _ = sample_rays(sensor, [(3.5, 0.5), (0.5, 3.5)])
    np.testing.assert_allclose(d[0], spec_direction(3, 3, 4, 4, up, angle=30), atol=1e-6)
    np.testing.assert_allclose(d[1], spec_direction(0, 0, 4, 4, up, angle=30), atol=1e-6)


def test_camera_jitter_samples_x_plus_xi():
    w, h = 4, 4
    sensor = camera(w, h, jitter=True)
    # film position (1 + 0.25, 2 + 0.75): course x + ξx = 1.25, y + ξy = 4 - 2.75 = 1.25
    _, d, _, _ = sample_rays(sensor, [(1.25, 2.75), (0.0, 4.0)])
    np.testing.assert_allclose(d[0], spec_direction(1.25, 1.25, w, h, (0, 1, 0)), atol=1e-6)
    np.testing.assert_allclose(d[1], spec_direction(0.0, 0.0, w, h, (0, 1, 0)), atol=1e-6)
    # without -jitter the offset is ignored: pixel x samples exactly x
    _, d2, _, _ = sample_rays(camera(w, h), [(1.9, 2.1)])
    np.testing.assert_allclose(d2[0], spec_direction(1, 1, w, h, (0, 1, 0)), atol=1e-6)


# ----------------------------------------------------------------------------- BSDF
def test_phong_bsdf_carries_the_course_material():
    bsdf = mi.load_dict({"type": "course_phong", "kd": {"type": "rgb", "value": [0.1, 0.2, 0.3]},
                         "ks": {"type": "rgb", "value": [0.5, 0.0, 0.0]}, "shininess": 8.0,
                         "normal_scale": 2.0})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    assert np.allclose(np.array(bsdf.eval_attribute_3("kd", si)).ravel(), [0.1, 0.2, 0.3])
    assert np.allclose(np.array(bsdf.eval_attribute_3("ks", si)).ravel(), [0.5, 0, 0])
    assert bsdf.eval_attribute_1("shininess", si)[0] == 8.0
    assert bsdf.eval_attribute_1("normal_scale", si)[0] == 2.0
    # eval: the course's response to a unit light along the normal seen from straight above:
    # diffuse max(N·L,0) kd = kd, specular max(R·L,0)^s ks = ks
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))
    np.testing.assert_allclose(np.array(value).ravel(), [0.6, 0.2, 0.3], atol=1e-6)
    # |ks| = 0.5 > 0.1: a mirror; sample() returns the mirror direction weighted by ks
    bs, weight = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.5))
    np.testing.assert_allclose(np.array(bs.wo).ravel(), [0, 0, 1])
    np.testing.assert_allclose(np.array(weight).ravel(), [0.5, 0, 0])


def test_powf_follows_c_semantics():
    base = mi.Float([0.0, 0.0, 0.0, 0.5, 0.9, 0.0, 0.028786868, 1.0])
    expo = mi.Float([0.0, 2.0, -1.0, 2.0, 200.0, 0.5, 200.0, math.inf])
    got = np.array(powf(base, expo))
    np.testing.assert_allclose(got[:4], [1.0, 0.0, math.inf, 0.25])
    assert got[4] == pytest.approx(0.9 ** 200, rel=1e-6)
    assert got[5] == 0.0
    # ~1e-308, double's subnormal range, where Dr.Jit's exp2 gives -inf: powf gives 0
    assert got[6] == 0.0
    assert got[7] == 1.0


# ----------------------------------------------------------------------------- integrator
CAM3 = "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"


def render(text: str, size=(3, 3), tmp: Path | None = None, **kw):
    scene = parse_scene_text(text, (tmp or Path("/nonexistent")) / "s.txt")
    opts = ReferenceOptions(width=size[0], height=size[1], kinds=("color", "normals", "depth"),
                            depth_min=8.0, depth_max=10.0, **kw)
    r = ReferenceRenderer(scene, opts)
    try:
        return r.render()
    finally:
        r.close()


def centre(result, image="color"):
    img = getattr(result, image)
    return img[img.shape[0] // 2, img.shape[1] // 2]


SPHERE = CAM3 + """Lights { numLights 1 DirectionalLight { direction 0 0 -1 color 1 0.5 0.25 } }
Background { color 0.1 0.2 0.3 ambientLight 0.2 0.2 0.2 }
Materials { numMaterials 1 Material { diffuseColor 0.5 0.6 0.7 specularColor 0.1 0.05 0.0
  shininess 7 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }
"""


def test_whitted_shading_of_a_sphere_facing_the_camera():
    res = render(SPHERE)
    # centre ray hits (0,0,1) at t = 9 with N = L = R = +z: diffuse I kd, specular I ks (1^7),
    # plus ambient kd
    i = np.array([1, 0.5, 0.25])
    kd, ks = np.array([0.5, 0.6, 0.7]), np.array([0.1, 0.05, 0.0])
    np.testing.assert_allclose(centre(res), i * kd + i * ks + 0.2 * kd, rtol=1e-6)
    np.testing.assert_allclose(centre(res, "normals"), [0.5, 0.5, 1.0], atol=1e-6)
    assert centre(res, "depth") == pytest.approx((9 - 8) / 2, abs=1e-6)
    # a corner ray misses: background colour, normal 0 -> 0.5, depth FLT_MAX -> black
    np.testing.assert_allclose(res.color[0, 0], [0.1, 0.2, 0.3], atol=1e-7)
    np.testing.assert_allclose(res.normals[0, 0], [0.5, 0.5, 0.5])
    assert to_bytes(res.depth[0, 0]) == 0 and res.depth[0, 0] > 1e30


def test_point_light_falloff_and_specular_without_n_dot_l_gate():
    text = CAM3 + """Lights { numLights 1 PointLight { position 0 0 5 color 2 2 2 falloff 0.5 } }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 specularColor 0.5 0.5 0.5 shininess 0 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }
"""
    res = render(text)
    # p = (0,0,1), dist 4: I = 2 / ((4*0.5)*4) = 0.25; diffuse 0.25, specular 1 * 0.25 * 0.5
    np.testing.assert_allclose(centre(res), [0.25 + 0.125] * 3, rtol=1e-6)
    # light behind the sphere: no diffuse, but powf(0, 0) = 1 keeps the specular term
    behind = text.replace("position 0 0 5", "position 0 0 -5")
    dist = 6.0  # from the hit (0, 0, 1) to the light
    i = 2 / ((dist * 0.5) * dist)
    np.testing.assert_allclose(centre(render(behind)), [i * 0.5] * 3, rtol=1e-6)


def test_falloff_zero_gives_inf_or_nan_which_quantise_to_black():
    text = CAM3 + """Lights { numLights 1 PointLight { position 0 0 5 color 1 0 0 } }
Background { color 0.3 0.3 0.3 }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }
"""
    res = render(text)
    c = centre(res)
    # diffuse 1 * inf = inf, but the specular term powf(x, 0) * inf * ks(0) is NaN: all NaN
    assert np.isnan(c).all()
    assert to_bytes(c).tolist() == [0, 0, 0]
    np.testing.assert_allclose(res.color[0, 0], [0.3] * 3)


# The camera looks down at p = (3, 0, 0) on the plane z = 0 from the side, so that blockers
# placed above p stay out of its view.
SHADOW = """PerspectiveCamera { center 3 -8 8 direction 0 1 -1 up 0 1 1 angle 30 }
Lights { numLights 2
  DirectionalLight { direction 0 0 -1 color 0.5 0.5 0.5 }
  PointLight { position 0 0 4 color 1 1 1 falloff 0.1 } }
Background { ambientLight 0.1 0.1 0.1 }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
Group { numObjects 2 MaterialIndex 0
  Plane { normal 0 0 1 offset 0 }
  Sphere { center BLOCKER radius 0.5 } }
"""
# at p: ambient 0.1; directional N·L = 1 -> 0.5; point light at distance 5 with
# N·L = 4/5 -> I = 1 / ((5 * 0.1) * 5) = 0.4 -> 0.32
AMBIENT, DIRECTIONAL, POINT = 0.1, 0.5, 0.32


@pytest.mark.parametrize("blocker, expected", [
    ("0 0 6", AMBIENT + DIRECTIONAL + POINT),     # off both shadow rays
    ("3 0 6", AMBIENT + POINT),                  # above p: blocks the directional light
    ("1.5 0 2", AMBIENT + DIRECTIONAL),          # between p and the point light
    ("-1.5 0 6", AMBIENT + DIRECTIONAL + POINT),  # on the line to the point light, beyond it
])
def test_shadow_rule_directional_any_hit_point_only_up_to_its_distance(blocker, expected):
    text = SHADOW.replace("BLOCKER", blocker)
    np.testing.assert_allclose(centre(render(text, shadows=True)), [expected] * 3, rtol=1e-5)
    unshadowed = AMBIENT + DIRECTIONAL + POINT
    np.testing.assert_allclose(centre(render(text)), [unshadowed] * 3, rtol=1e-5)


MIRROR = CAM3 + """Background { color 0.2 0.4 0.8 }
Materials { numMaterials 1 Material { diffuseColor 0 0 0 specularColor 0.5 1 1 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }
"""


def test_mirror_recursion_returns_ks_times_the_reflected_background():
    # no lights: ambient forced to 1, kd = 0; the centre ray reflects straight back to a miss
    np.testing.assert_allclose(centre(render(MIRROR)), [0, 0, 0])
    np.testing.assert_allclose(centre(render(MIRROR, bounces=1)), [0.1, 0.4, 0.8], rtol=1e-6)
    # |ks| = 0.1 is not > 0.1: no recursion
    dull = MIRROR.replace("specularColor 0.5 1 1", "specularColor 0.1 0 0")
    np.testing.assert_allclose(centre(render(dull, bounces=3)), [0, 0, 0])


def test_a_closed_renderer_leaves_no_plugin_alive_without_a_garbage_collection(monkeypatch):
    """close() only drops the scene: a reference cycle anywhere in it would keep its plugins in
    every later symbolic call until the next full collection (translate._converted was such a
    cycle). A film rendered in bands of rows (one scene for all bands) is dropped the same
    way."""
    import gc

    from raycheck.mitsuba_ref import render as render_module
    from raycheck.mitsuba_ref.bsdf import CoursePhong
    from raycheck.mitsuba_ref.camera import CourseCamera
    from raycheck.mitsuba_ref.integrator import CourseWhitted

    def alive() -> int:
        return sum(isinstance(o, (CoursePhong, CourseCamera, CourseWhitted))
                   for o in gc.get_objects())

    gc.collect()
    assert alive() == 0
    gc.disable()
    try:
        render(MIRROR, bounces=1)
        assert alive() == 0
        monkeypatch.setattr(render_module, "MAX_LAUNCH_LANES", 27)  # 3 bands of 3 rows
        render(MIRROR, size=(9, 9), bounces=1)
        assert alive() == 0
    finally:
        gc.enable()


def test_raw_plane_normal_is_used_as_written():
    text = """PerspectiveCamera { center 0 5 0 direction 0 -1 0 up 0 0 -1 angle 30 }
Lights { numLights 1 DirectionalLight { direction 0 -1 0 color 0.2 0.2 0.2 } }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 2 0 offset -2 } }
"""
    res = render(text)
    # plane y = -1 hit at t = 6; N = (0,2,0) raw: N·L = 2 doubles the diffuse term
    np.testing.assert_allclose(centre(res), [0.4] * 3, rtol=1e-6)
    np.testing.assert_allclose(centre(res, "normals"), [0.5, 1.5, 0.5])
    assert to_bytes(centre(res, "normals")).tolist() == [127, 255, 127]


def test_mitsuba_offsets_give_the_same_image_away_from_contact_points():
    text = SHADOW.replace("BLOCKER", "3 0 6")
    a = render(text, size=(9, 9), shadows=True)
    b = render(text, size=(9, 9), shadows=True, offsets="mitsuba")
    np.testing.assert_allclose(a.color, b.color, rtol=1e-5)


def test_cube_map_background_and_reflection(tmp_path: Path):
    from PIL import Image

    sky = tmp_path / "sky"
    sky.mkdir()
    colors = {"left": (255, 0, 0), "right": (0, 255, 0), "up": (0, 0, 255),
              "down": (255, 255, 0), "front": (0, 255, 255), "back": (255, 0, 255)}
    for name, c in colors.items():
        Image.fromarray(np.full((2, 2, 3), c, np.uint8)).save(sky / f"{name}.png")
    text = CAM3 + """Background { cubeMap sky }
Materials { numMaterials 1 Material { diffuseColor 0 0 0 specularColor 1 1 1 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 0.1 } }
"""
    res = render(text, tmp=tmp_path, bounces=1)
    np.testing.assert_allclose(res.color[0, 0], [1, 0, 1])      # camera looks at -z: back
    np.testing.assert_allclose(centre(res), [0, 1, 1])          # reflected to +z: front


# ----------------------------------------------------------------------------- cube map
def lookup(faces: dict[str, np.ndarray], dirs):
    cm = CubeMapLookup(CubeMap(Path("."), faces))
    d = np.array(dirs, dtype=np.float32)
    got = cm.lookup(mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))
    return np.array(got).T


def test_cube_map_face_choice_ties_and_zero_direction():
    # face k's texels are the byte 51 k: value k / 5
    faces = {n: np.full((2, 2, 3), 51 * k, np.uint8)
             for k, n in enumerate(("left", "right", "up", "down", "front", "back"))}
    got = lookup(faces, [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1],
                         [1, 1, 0], [0, -1, -1], [1, 1, 1], [0, 0, 0]])
    expected = [0.2, 0.0, 0.4, 0.6, 0.8, 1.0,
                0.2,   # |x| = |y|: ties go to X
                0.6,   # |y| = |z|: ties go to Y
                0.2,   # all equal: X
                0.0]   # a zero major component gives black
    np.testing.assert_allclose(got[:, 0], expected, atol=1e-7)


def test_cube_map_uv_table_and_bilinear_fetch():
    # a 2x2 face (row 0 = top of the PNG) with distinct texels: values 0, 0.2, 0.4, 0.6
    face = np.array([[[0] * 3, [51] * 3], [[102] * 3, [153] * 3]], np.uint8)
    faces = {n: face for n in ("left", "right", "up", "down", "front", "back")}
    # +X, d = (1, 0, 0): u = v = 0.5 -> X = Y = 1 -> texel (i=1, j=1), weights a = b = 0
    # +X, d = (1, 0.5, 0): v = 0.75 -> Y = 0.5: half texel (1,0) and half texel (1,1)
    # -X, d = (-1, 0.5, 0): v = 1 - (y/x + 1)/2 = 0.75 as well
    # +Z, d = (-0.5, 0, 1): u = 1 - (x/z + 1)/2 = 0.75 -> X = 1.5: texel column 1 (clamped)
    got = lookup(faces, [[1, 0, 0], [1, 0.5, 0], [-1, 0.5, 0], [-0.5, 0, 1]])
    np.testing.assert_allclose(got[:, 0], [0.6, 0.4, 0.4, 0.6], atol=1e-6)


# ----------------------------------------------------------------------------- images
def test_quantisation_rule():
    values = np.array([1.7, 0.5, -0.2, 1.0, 0.999, np.inf, -np.inf, np.nan, 1e30, 8e6, 1e7],
                      np.float32)
    # 1e7 * 255 = 2.55e9 >= 2^31: INT_MIN, clamped to 0 (black); 8e6 * 255 < 2^31: 255
    assert to_bytes(values).tolist() == [255, 127, 0, 255, 254, 0, 0, 0, 0, 255, 0]


def test_filter_kernel_121():
    big = np.zeros((6, 3), np.float32)
    big[1, 1] = 16.0   # centre of the first 3x3 block: weight 4
    big[3, 0] = 16.0   # corner of the second block: weight 1
    out = filter_121(big)
    assert out.shape == (2, 1)
    np.testing.assert_allclose(out[:, 0], [4.0, 1.0])


def test_quantisation_agrees_with_the_tracers_independent_one():
    from raycheck.tracer.image import quantize

    rng = np.random.default_rng(3)
    values = np.concatenate([
        rng.normal(0.5, 2.0, 5000), rng.uniform(-1, 2, 5000),
        np.array([0, 1, 1 / 255, 254.9999 / 255, 255 / 255, 256 / 255, -0.0, 1e-45, 8.42e6,
                  8.43e6, -8.43e6, 3.4e38, -3.4e38, np.inf, -np.inf, np.nan]),
        (np.arange(0, 256) / 255.0)]).astype(np.float32)
    np.testing.assert_array_equal(to_bytes(values), quantize(values))
