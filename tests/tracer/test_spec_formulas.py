"""Hand-worked values of the course formulas (docs/course-format.md) against the tracer.

Each expected value is computed here step by step in float32 from the spec's formulas, for scenes
small enough to reason about by hand. Array layout: row 0 = top of the image (spec y = h-1-row).
"""
from __future__ import annotations

import ctypes
import ctypes.util
import math
from pathlib import Path

import numpy as np
import pytest
from spec_reference import Camera as RefCamera
from spec_reference import render_reference

from raycheck.tracer.image import quantize
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer, box_filter_3x3
from raycheck.tracer.scene import parse_scene_text

F = np.float32
FLT_MAX = np.finfo(np.float32).max

_libm = ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6")
_libm.tanf.restype = ctypes.c_float
_libm.tanf.argtypes = [ctypes.c_float]


def course_dist(angle_deg: float) -> np.float32:
    """dist = 1 / tanf(A/2), A = float32(pi * deg / 180) computed in double."""
    a = F(math.pi * float(F(angle_deg)) / 180.0)
    return F(1.0) / F(_libm.tanf(float(a / F(2.0))))


def f3(*v) -> np.ndarray:
    return np.array(v, dtype=np.float32)


def dot(a, b) -> np.float32:
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]


def normalize(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float32)
    n = F(np.sqrt(dot(v, v)))
    return np.array([v[0] / n, v[1] / n, v[2] / n], dtype=np.float32)


def render(text: str, w: int, h: int, **kw):
    scene = parse_scene_text(text, Path("/tmp/spec_formulas_scene.txt"))
    opts = RenderOptions(width=w, height=h, kinds=("color", "normals", "depth"), **kw)
    return Renderer(scene, opts).render()


def ulp_close(got, want, ulps: int = 4):
    got = np.asarray(got, dtype=np.float32)
    want = np.asarray(want, dtype=np.float32)
    tol = ulps * np.spacing(np.maximum(np.abs(want), np.float32(1e-30)))
    assert np.all(np.abs(got - want) <= tol), f"got {got!r}, want {want!r} (within {ulps} ulp)"


# ----------------------------------------------------------------------------- §4 camera
FLAT_Z = """
PerspectiveCamera { center 0 0 0 direction 0 0 -1 up 0 1 0 angle %s }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 1 offset -1 } }
"""


def test_ndc_edges_are_exactly_plus_minus_one():
    assert [RefCamera.ndc(x, 5) for x in range(5)] == [-1.0, -0.5, 0.0, 0.5, 1.0]
    assert [RefCamera.ndc(y, 3) for y in range(3)] == [-1.0, 0.0, 1.0]
    assert RefCamera.ndc(0, 13) == F(-1.0) and RefCamera.ndc(12, 13) == F(1.0)


def test_camera_rays_5x3_through_plane_depth():
    """Plane z = -1 seen from the origin: t = -1 / dir_z, dir = normalize((ndcx, ndcy, -dist)).

    No aspect correction: (ndcx, ndcy) = (-1, 0) and (0, -1) give the same t although the
    image is 5x3; the centre pixel direction is normalize(dist*w) = (0,0,-1) exactly -> t = 1."""
    res = render(FLAT_Z % 90, 5, 3, depth_min=0.0, depth_max=1.0)
    depth = res.depth  # value = (t - 0) / 1 = t
    dist = course_dist(90)
    for x in range(5):
        for y in range(3):
            ndcx, ndcy = F(2) * (F(x) / F(4.0)) - F(1), F(2) * (F(y) / F(2.0)) - F(1)
            d = normalize(f3(ndcx, ndcy, -dist))
            t = F(-1.0) / d[2]
            ulp_close(depth[2 - y, x], t, ulps=2)
    assert depth[1, 2] == F(1.0)  # centre pixel (2, 1)
    assert depth[1, 0] == depth[2, 2] == depth[0, 2] == depth[1, 4]  # |ndc| = 1 on one axis
    # Corner: t = sqrt(1 + 1 + dist²) / dist, about sqrt(3) for a 90° view.
    assert abs(float(depth[0, 0]) - math.sqrt(3.0)) < 1e-6


# spec intro: normalize(v) = v / sqrt(v·v), three true divisions (angle 30, 5x3, pixel (1,0)).
def test_camera_ray_uses_true_division_in_normalize():
    res = render(FLAT_Z % 30, 5, 3, depth_min=0.0, depth_max=1.0)
    dist = course_dist(30)
    d = normalize(f3(F(-0.5), F(-1.0), -dist))
    t = F(-1.0) / d[2]
    assert t == F(1.043909)
    assert res.depth[2, 1] == t, f"tracer t = {res.depth[2, 1]!r}, spec t = {t!r}"


def test_rows_are_top_first_and_columns_left_first():
    text = """
PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
Materials { numMaterials 1 Material { diffuseColor 1 0 0 } }
Group { numObjects 2 MaterialIndex 0
  Sphere { center 0 1.5 0 radius 0.8 }
  Sphere { center 1.6 -1.6 0 radius 0.5 } }
"""
    res = render(text, 7, 7)
    hit = (res.normals != F(0.5)).any(axis=-1)
    # The upper sphere (world y > 0) covers ndcy 1/3 and 2/3: spec rows y = 4, 5 -> array rows 2, 1.
    assert hit[1, 3] and hit[2, 3]
    assert not hit[0, 3] and not hit[3, 3] and not hit[4, 3]
    # The lower-right sphere is in the bottom-right corner region of the array.
    assert hit[6, 6] or hit[5, 6] or hit[6, 5] or hit[5, 5]
    assert not hit[6, 0] and not hit[0, 6]


# ----------------------------------------------------------------------------- §5 + §8
ONE_SPHERE = """
PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
Materials { numMaterials 1 Material { diffuseColor 0.5 0.5 0.5 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }
"""


def test_sphere_hit_distance_depth_and_normal():
    # a = 1, b = -20, c = 99, disc = 4 -> t- = (20 - 2) / 2 = 9 exactly.
    res = render(ONE_SPHERE, 5, 5, depth_min=8.0, depth_max=10.0)
    assert res.depth[2, 2] == F(0.5)  # (9 - 8) / (10 - 8)
    assert quantize(res.depth)[2, 2] == 127
    np.testing.assert_array_equal(res.normals[2, 2], f3(0.5, 0.5, 1.0))  # n = (0,0,1)
    np.testing.assert_array_equal(quantize(res.normals)[2, 2], [127, 127, 255])
    res = render(ONE_SPHERE, 5, 5, depth_min=0.0, depth_max=1.0)
    assert res.depth[2, 2] == F(9.0)


def test_miss_normals_127_and_miss_depth_black():
    res = render(ONE_SPHERE, 5, 5, depth_min=8.0, depth_max=10.0)
    # Corner rays pass the unit sphere at about 2.7 units: misses.
    np.testing.assert_array_equal(res.normals[0, 0], f3(0.5, 0.5, 0.5))
    np.testing.assert_array_equal(quantize(res.normals)[0, 0], [127, 127, 127])
    assert res.depth[0, 0] > 1e37  # (FLT_MAX - 8) / 2
    assert quantize(res.depth)[0, 0] == 0
    np.testing.assert_array_equal(res.color[0, 0], f3(0.5, 0.5, 0.5))  # default background


def test_depth_with_min_equal_max_is_black():
    res = render(ONE_SPHERE, 5, 5, depth_min=9.0, depth_max=9.0)
    assert (quantize(res.depth) == 0).all()


def test_plane_raw_normal_in_normals_image():
    text = """
PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 2 0 offset -2 } }
"""
    res = render(text, 5, 5, depth_min=0.0, depth_max=100.0)
    # Bottom row looks down and hits 2y = -2: n = (0,2,0) raw -> (n+1)/2 = (0.5, 1.5, 0.5).
    np.testing.assert_array_equal(res.normals[4, 2], f3(0.5, 1.5, 0.5))
    np.testing.assert_array_equal(quantize(res.normals)[4, 2], [127, 255, 127])
    # Its t = (d - o·n) / (dir·n) = -2 / (2 dir_y).
    dist = course_dist(30)
    d = normalize(f3(0.0, -1.0, -dist))
    t = (F(-2.0) - F(0.0)) / dot(d, f3(0, 2, 0))
    ulp_close(res.depth[4, 2] * F(100.0), t, ulps=4)
    # The centre row looks parallel to the plane (dir·n = 0): rejected, so a miss.
    np.testing.assert_array_equal(res.normals[2, 2], f3(0.5, 0.5, 0.5))
    np.testing.assert_array_equal(res.normals[0, 2], f3(0.5, 0.5, 0.5))


# ----------------------------------------------------------------------------- §6 shading
def test_directional_light_centre_pixel_by_hand():
    text = """
PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
Lights { numLights 1 DirectionalLight { direction 0 -0.6 -0.8 color 0.9 0.8 0.7 } }
Background { ambientLight 0.1 0.2 0.3 }
Materials { numMaterials 1
  Material { diffuseColor 0.5 0.25 1 specularColor 0.3 0.3 0.3 shininess 10 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }
"""
    res = render(text, 5, 5)
    # Centre pixel: d = (0,0,-1), t = 9, p = (0,0,1), N = (0,0,1).
    light_dir = normalize(f3(0.0, -0.6, -0.8))  # normalized at parse time
    L = -light_dir
    N = f3(0, 0, 1)
    d = f3(0, 0, -1)
    I, kd, ks, amb = f3(0.9, 0.8, 0.7), f3(0.5, 0.25, 1.0), f3(0.3, 0.3, 0.3), f3(0.1, 0.2, 0.3)
    ndotl = max(dot(N, L), F(0))
    R = d - (F(2) * dot(N, d)) * N  # (0,0,1)
    spec = F(math.pow(float(max(dot(R, L), F(0))), 10.0))
    diffuse = (ndotl * I) * kd
    specular = (spec * I) * ks
    want = (f3(0, 0, 0) + (diffuse + specular)) + amb * kd
    assert float(ndotl) == pytest.approx(0.8, abs=1e-7)
    np.testing.assert_array_equal(res.color[2, 2], want)
    # 0.8*0.9*0.5 + 0.8^10*0.9*0.3 + 0.05 = 0.439 -> about 111.
    assert quantize(res.color)[2, 2, 0] == int(F(want[0]) * F(255.0))


def test_point_light_falloff_formula():
    text = """
PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 1 0 angle 30 }
Lights { numLights 1 PointLight { position 0 0 2 color 1 1 1 falloff 0.5 } }
Materials { numMaterials 1 Material { diffuseColor 0.8 0.6 0.4 } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 1 offset 0 } }
"""
    res = render(text, 5, 5)
    # p = (0,0,0), L = (0,0,1), dist = 2, I = 1 / ((2*0.5)*2) = 0.5.
    np.testing.assert_array_equal(res.color[2, 2], f3(0.4, 0.3, 0.2))

    text2 = text.replace("position 0 0 2 color 1 1 1 falloff 0.5",
                         "position 1 0.5 3 color 2 3 4 falloff 0.25")
    res = render(text2, 5, 5)
    to_light = f3(1.0, 0.5, 3.0)
    dist = F(np.sqrt(dot(to_light, to_light)))
    L = to_light / dist
    I = f3(2, 3, 4) / ((dist * F(0.25)) * dist)
    want = (max(dot(f3(0, 0, 1), L), F(0)) * I) * f3(0.8, 0.6, 0.4)
    ulp_close(res.color[2, 2], want, ulps=4)


def test_point_light_falloff_zero_is_infinite():
    text = """
PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 1 0 angle 30 }
Lights { numLights 1 PointLight { position 0 0 2 color 1 1 1 } }
Materials { numMaterials 1 Material { diffuseColor 0.8 0.6 0 %s } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 1 offset 0 } }
"""
    # I = color / ((dist*0)*dist) = inf. diffuse = (1*inf) ⊙ kd; specular = (powf(1, s)*inf) ⊙ ks.
    res = render(text % "specularColor 0.1 0.1 0 shininess 1", 5, 5)
    c = res.color[2, 2]
    assert np.isposinf(c[0]) and np.isposinf(c[1]) and np.isnan(c[2])  # kd = ks = 0: inf*0
    np.testing.assert_array_equal(quantize(res.color)[2, 2], [0, 0, 0])
    # Default ks = 0, shininess 0: specular = (powf(1,0)*inf)*0 = NaN in every channel.
    res = render(text % "", 5, 5)
    assert np.isnan(res.color[2, 2]).all()
    np.testing.assert_array_equal(quantize(res.color)[2, 2], [0, 0, 0])


HEAD_ON_PLANE = """
PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 1 0 angle 30 }
Lights { numLights 1 DirectionalLight { direction 0 0 1 color 1 1 1 } }
Background { ambientLight 0 0 0 }
Materials { numMaterials 1
  Material { diffuseColor 0.9 0.9 0.9 specularColor 0.25 0.5 0.75 shininess %s } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 1 offset 0 } }
"""


def test_shininess_zero_gives_powf_0_0_equal_1():
    # Light travels +z, so L = (0,0,-1) is behind the surface: N·L = -1 (no diffuse) and
    # R·L = -1 -> max(.,0) = 0 -> powf(0, 0) = 1: specular = I ⊙ ks.
    res = render(HEAD_ON_PLANE % 0, 5, 5)
    np.testing.assert_array_equal(res.color[2, 2], f3(0.25, 0.5, 0.75))
    res = render(HEAD_ON_PLANE % 2, 5, 5)  # powf(0, 2) = 0
    np.testing.assert_array_equal(res.color[2, 2], f3(0, 0, 0))


def test_specular_is_not_gated_by_n_dot_l():
    text = """
PerspectiveCamera { center 0 3 3 direction 0 -1 -1 up 0 1 0 angle 30 }
Lights { numLights 1 DirectionalLight { direction 0 0.2 0.98 color 1 1 1 } }
Background { ambientLight 0 0 0 }
Materials { numMaterials 1
  Material { diffuseColor 1 1 1 specularColor 0.5 0.6 0.7 shininess 2 } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 1 0 offset 0 } }
"""
    res = render(text, 3, 3)
    dist = course_dist(30)
    w = normalize(f3(0, -1, -1))
    d = normalize(dist * w)  # centre pixel: ndc = (0, 0)
    N = f3(0, 1, 0)
    L = -normalize(f3(0.0, 0.2, 0.98))
    assert dot(N, L) < 0  # light below the plane: no diffuse ...
    R = d - (F(2) * dot(N, d)) * N
    rl = dot(R, L)
    assert rl > 0  # ... but the mirrored eye ray still sees it
    want = (F(math.pow(float(rl), 2.0)) * f3(1, 1, 1)) * f3(0.5, 0.6, 0.7)
    assert float(want[0]) > 0.05
    ulp_close(res.color[1, 1], want, ulps=16)


def test_no_lights_forces_ambient_one():
    text = """
PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
Background { color 0.1 0.2 0.3 ambientLight 0.2 0.2 0.2 }
Materials { numMaterials 1
  Material { diffuseColor 0.3 0.6 0.9 specularColor 0.05 0.05 0.05 shininess 3 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }
"""
    res = render(text, 5, 5)
    np.testing.assert_array_equal(res.color[2, 2], f3(0.3, 0.6, 0.9))  # 1 ⊙ kd
    np.testing.assert_array_equal(res.color[0, 0], f3(0.1, 0.2, 0.3))  # background


SHADOW_SCENE = """
PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 1 0 angle 30 }
Lights { numLights 1 %s }
Background { ambientLight 0.1 0.1 0.1 }
Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
Group { numObjects 2 MaterialIndex 0
  Plane { normal 0 0 1 offset 0 }
  Sphere { center %s radius 0.3 } }
"""
POINT_22 = "PointLight { position 2 0 2 color 1 1 1 falloff 0.1 }"
POINT_11 = "PointLight { position 1 0 1 color 1 1 1 falloff 0.1 }"
DIRECTIONAL_DIAG = "DirectionalLight { direction -1 0 -1 color 0.5 0.5 0.5 }"


def _lit_value(light_pos, falloff):
    p = f3(0, 0, 0)
    to_light = f3(*light_pos) - p
    dist = F(np.sqrt(dot(to_light, to_light)))
    L = to_light / dist
    I = F(1.0) / ((dist * F(falloff)) * dist)
    return (max(dot(f3(0, 0, 1), L), F(0)) * I) * F(1.0) + F(0.1)


def test_shadow_blocked_by_object_between_point_and_light():
    text = SHADOW_SCENE % (POINT_22, "1 0 1")
    lit = render(text, 5, 5)
    shadowed = render(text, 5, 5, shadows=True)
    ulp_close(lit.color[2, 2], np.full(3, _lit_value((2, 0, 2), 0.1)), ulps=4)
    np.testing.assert_array_equal(shadowed.color[2, 2], f3(0.1, 0.1, 0.1))  # ambient only


def test_shadow_ray_not_blocked_beyond_point_light():
    text = SHADOW_SCENE % (POINT_11, "2 0 2")  # sphere behind the light, seen from p
    lit = render(text, 5, 5)
    shadowed = render(text, 5, 5, shadows=True)
    np.testing.assert_array_equal(shadowed.color[2, 2], lit.color[2, 2])
    ulp_close(shadowed.color[2, 2], np.full(3, _lit_value((1, 0, 1), 0.1)), ulps=4)


def test_directional_light_blocked_by_any_hit():
    text = SHADOW_SCENE % (DIRECTIONAL_DIAG, "2 0 2")  # distToLight = FLT_MAX
    lit = render(text, 5, 5)
    shadowed = render(text, 5, 5, shadows=True)
    assert lit.color[2, 2, 0] > 0.4
    np.testing.assert_array_equal(shadowed.color[2, 2], f3(0.1, 0.1, 0.1))


MIRROR = """
PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 1 0 angle 30 }
Background { color 0.1 0.3 0.9 }
Materials { numMaterials 1
  Material { diffuseColor 0.2 0.4 0.6 specularColor %s } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 1 offset 0 } }
"""


def test_mirror_reflection_by_hand():
    # No lights -> ambient (1,1,1). Centre ray reflects to R = (0,0,1) from (0,0,0.01) and
    # misses (the plane is behind it): color = (0 + ks ⊙ background) + 1 ⊙ kd.
    res = render(MIRROR % "0.5 0.5 0.5", 5, 5, bounces=1)
    ks, bg, kd = f3(0.5, 0.5, 0.5), f3(0.1, 0.3, 0.9), f3(0.2, 0.4, 0.6)
    want = (f3(0, 0, 0) + ks * bg) + f3(1, 1, 1) * kd
    np.testing.assert_array_equal(res.color[2, 2], want)
    np.testing.assert_array_equal(quantize(res.color)[2, 2],
                                  [int(F(x) * F(255)) for x in want[:2]] + [255])
    res0 = render(MIRROR % "0.5 0.5 0.5", 5, 5, bounces=0)
    np.testing.assert_array_equal(res0.color[2, 2], kd)


def test_weak_specular_does_not_reflect():
    # |ks| = sqrt(3 * 0.05²) = 0.0866 <= 0.1: no reflection even with bounces.
    res = render(MIRROR % "0.05 0.05 0.05", 5, 5, bounces=3)
    np.testing.assert_array_equal(res.color[2, 2], f3(0.2, 0.4, 0.6))


def test_reference_agrees_with_hand_values():
    """The test-only reference reproduces the hand-worked mirror and sphere values."""
    scene = parse_scene_text(MIRROR % "0.5 0.5 0.5", Path("/tmp/x.txt"))
    color, _, _ = render_reference(scene, 5, 5, bounces=1)
    np.testing.assert_array_equal(color[2, 2], (f3(0, 0, 0) + f3(0.05, 0.15, 0.45))
                                  + f3(0.2, 0.4, 0.6))
    scene = parse_scene_text(ONE_SPHERE, Path("/tmp/x.txt"))
    _, normals, depth = render_reference(scene, 5, 5, depth_min=8, depth_max=10)
    assert depth[2, 2] == F(0.5)
    np.testing.assert_array_equal(normals[2, 2], f3(0.5, 0.5, 1.0))


# ----------------------------------------------------------------------------- §9 filter
def test_filter_kernel_on_known_6x6():
    big = np.arange(36, dtype=np.float32).reshape(6, 6)
    # A linear ramp through a symmetric kernel gives the block centre.
    np.testing.assert_array_equal(box_filter_3x3(big), [[7, 10], [25, 28]])
    rgb = np.stack([big, 2 * big, big * big], axis=-1)
    out = box_filter_3x3(rgb)
    assert out.shape == (2, 2, 3)
    np.testing.assert_array_equal(out[..., 1], [[14, 20], [50, 56]])
    K = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]], np.float32)
    for r in range(2):
        for c in range(2):
            want = F((K * (big * big)[3 * r:3 * r + 3, 3 * c:3 * c + 3]).sum() / 16)
            assert out[r, c, 2] == want
    impulse = np.zeros((6, 6), np.float32)
    impulse[0, 0], impulse[1, 1], impulse[4, 3] = 1.0, 1.0, 1.0
    np.testing.assert_array_equal(box_filter_3x3(impulse), [[5 / 16, 0], [0, 2 / 16]])


def test_filter_render_matches_kernel_of_big_render():
    res = render(ONE_SPHERE, 4, 3, filter=True, depth_min=8.0, depth_max=12.0)
    big = render(ONE_SPHERE, 12, 9, depth_min=8.0, depth_max=12.0)
    np.testing.assert_array_equal(res.color, box_filter_3x3(big.color))
    np.testing.assert_array_equal(res.normals, box_filter_3x3(big.normals))
    with np.errstate(over="ignore", invalid="ignore"):
        want_depth = box_filter_3x3(big.depth)
    np.testing.assert_array_equal(quantize(res.depth), quantize(want_depth))
    # Every output pixel with a missed sub-sample has an overflowing (black) depth.
    assert (quantize(res.depth)[(big.normals == F(0.5)).all(-1).reshape(3, 3, 4, 3)
                                .any(axis=(1, 3))] == 0).all()


# ----------------------------------------------------------------------------- §8 quantize
@pytest.mark.parametrize("value, byte", [
    (0.5, 127), (1.7, 255), (-0.1, 0), (1e7, 0), (np.inf, 0), (-np.inf, 0), (np.nan, 0),
    (1.0, 255), (254.9 / 255, 254), (0.0, 0), (-0.0, 0), (8e6, 255), (1 / 255, 1),
    (0.999, 254), (100.0 / 255, 100), (FLT_MAX, 0),
])
def test_quantize(value, byte):
    c = F(value)
    out = quantize(np.array([c], dtype=np.float32))
    assert int(out[0]) == byte, f"quantize({c!r}) = {int(out[0])}, want {byte}"
    if np.isfinite(c) and abs(float(c) * 255.0) < 2.0 ** 31:
        assert byte == min(max(int(c * F(255.0)), 0), 255)  # the formula itself


def test_quantize_matches_the_reference_rule_on_edge_values():
    """quantize's shortcut (one comparison and a clamp) gives the bytes of the literal rule:
    NaN, ±inf, out-of-int32 products, rounding edges, and every float32 bit pattern drawn."""
    from spec_reference import quantize_reference

    edges = [np.nan, np.inf, -np.inf, 0.0, -0.0, 1.0, 1 / 255, 254.999 / 255, 2.0**31 / 255,
             -(2.0**31) / 255, 8421504.5, 8421505.0, 1e38, -1e38, 3e38, -0.001, 0.999, 1e-45]
    rng = np.random.default_rng(17)
    bits = rng.integers(0, 2**32, 200_000, dtype=np.uint64).astype(np.uint32).view(np.float32)
    for values in (np.array(edges, np.float64), rng.normal(0, 2, 200_000), bits):
        for dtype in (np.float32, np.float64):
            with np.errstate(all="ignore"):
                v = values.astype(dtype)
            np.testing.assert_array_equal(quantize(v), quantize_reference(v))
