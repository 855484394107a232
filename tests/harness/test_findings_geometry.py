"""Geometry-level findings (harness/judge/geometry.py) and depth_mapping's unclamped variant,
each from a renderer with exactly that bug (tests/wrappers/geometry_bugs.py, corrupt.py), with
the exact code and the numbers by hand; the tracer itself gets none on these cases. 12x12
images, the plain feature."""
from __future__ import annotations

import numpy as np
import pytest
from test_findings import REPO, SHADOWS, SIZE, checked, codes, reference, top

from raycheck.harness.catalog import scene_headers
from raycheck.harness.judge.parts import reference_parts
from raycheck.harness.pipeline.matrix import Matrix

ELLIPSOID = REPO / "scenes" / "course" / "ellipsoid.txt"  # one transformed (scaled) sphere
ROTATE = REPO / "scenes" / "features" / "rotate.txt"  # transformed meshes only


def changed(result, kind: str) -> np.ndarray:
    """Pixels where a channel differs by more than one level (by hand)."""
    a, b = reference(result, kind), reference(result, kind, "candidate")
    return np.abs(a - b).max(axis=2) > 1


def object_image(scene, size: int = SIZE) -> np.ndarray:
    """The reference's object image of the scene's plain case."""
    (case,), _ = Matrix(scene_headers([scene]), None, None, size=(size, size),
                        features=frozenset({"plain"})).cases()
    return reference_parts(case).images["object"]


@pytest.mark.parametrize("defect, scene, index, what", [
    ("one_material", SHADOWS, 0, "plane, line 39, material 0"),
    ("unnormalised_normals", ELLIPSOID, 1, "sphere, line 49, transformed, material 0"),
])
def test_differences_confined_to_one_object(defect, scene, index, what):
    """A material swapped on the first object, or a transformed sphere's normal not
    renormalised: every differing color pixel lies on that object (shares by hand)."""
    result = checked(defect, scene, "plain", causes=False)
    diff = changed(result, "color")
    on = object_image(scene) == index
    count, total = int((diff & on).sum()), int(diff.sum())
    assert codes(result)["color"][1][0] == f"object:{index}"
    assert top(result).message == (
        f"the differences are confined to object {index} ({what}): {count / total:.0%} of the "
        f"{total} differing pixels, {count / on.sum():.0%} of its pixels: is its material or "
        "normal the reference's?")
    assert count == total


def decoded_length(image: np.ndarray) -> np.ndarray:
    n = 2.0 * (image + 0.5) / 255.0 - 1.0
    return np.linalg.norm(n, axis=2)


def test_unnormalised_normals_have_another_length():
    """rotate.txt's meshes are scaled: their normals image decodes to lengths far from 1."""
    result = checked("unnormalised_normals", ROTATE, "plain", causes=False)
    obj = object_image(ROTATE)
    got = decoded_length(reference(result, "normals", "candidate"))
    ref = decoded_length(reference(result, "normals"))
    off = {i: (np.median(ref[obj == i]), np.median(got[obj == i])) for i in np.unique(obj)
           if i >= 0}
    off = {i: v for i, v in off.items() if abs(v[1] - v[0]) > 0.05}
    worst = max(off, key=lambda i: abs(off[i][1] - off[i][0]))
    r, g = off[worst]
    assert codes(result)["normals"][1][0] == "normal_length"
    assert top(result, "normals").message.endswith(
        f"have median length {g:.2f}, the reference's {r:.2f} (and {len(off) - 1} more "
        "objects): is the normal renormalised after the transform?")
    assert f"on object {worst} (mesh cube_flat.obj" in top(result, "normals").message


def test_half_pixel_shift_is_found_by_cross_correlation():
    """Primary rays through x+0.5, y+0.5 (y up): the candidate is the reference moved half a
    pixel right and half a pixel up."""
    result = checked("half_shift", SHADOWS, "plain", causes=False)
    assert codes(result)["color"][1][0] == "shifted"
    assert top(result).message.startswith(
        "your image is the reference shifted by (+0.50, -0.50) pixels (x right, y down; by "
        "cross-correlation)")


def test_pixel_centre_convention_is_edges_only():
    """ndc = 2*(x+0.5)/w - 1: a rescaling by (w-1)/w about the centre, hard edges left."""
    result = checked("pixel_centre", SHADOWS, "plain", causes=False)
    assert {k: v[1][:1] for k, v in codes(result).items()} == \
        {k: ["edges_only"] for k in ("color", "normals", "depth")}
    assert top(result, "normals").message.startswith(
        "your image differs from the reference at silhouettes (100% of the ")


def test_unclamped_depth_wraps_bytes():
    """Depth values outside the -depth range written as (unsigned char)(int)(255*v): the share
    of the reference's floats outside [0, 1] (misses, t = FLT_MAX, give 0 either way)."""
    result = checked("depth_unclamped", SHADOWS, "plain")
    depth = result.images["reference"]["depth"]
    v = depth.astype(np.float64) * 255.0
    finite = np.isfinite(v) & (np.abs(v) < 2.0**31)
    outside = finite & ((np.trunc(v) < 0) | (np.trunc(v) > 255))
    assert codes(result)["depth"] == ("fail", ["depth_mapping"])
    assert top(result, "depth").message == (
        "your depth image is not clamped to [0, 1]: it matches the reference's (t-min)/(max-min)"
        " written as (unsigned char)(int)(255*v), which wraps on the "
        f"{outside.mean():.1%} of the pixels outside the -depth range")


@pytest.mark.parametrize("scene", [SHADOWS, ELLIPSOID, ROTATE])
def test_the_tracer_gets_no_geometry_finding(scene):
    result = checked("none", scene, "plain")
    assert all(k.verdict == "pass" and k.findings == [] for k in result.kinds)


def test_bilinear_resampling_is_exact_on_a_linear_image_and_clamps_at_its_border():
    """An image whose value is 4 * row + column is linear, so bilinear interpolation gives the
    formula's value at every position inside; outside, the position is clamped to the border
    (a column of -1 reads column 0, a row of 9 reads the last row, 2)."""
    from raycheck.harness.judge.geometry import bilinear, shifted_by

    image = np.arange(12, dtype=np.float64).reshape(3, 4, 1)
    columns, rows = np.array([-1.0, 0.5, 2.25, 5.0]), np.array([0.0, 1.5, 9.0])
    expected = 4 * np.array([0.0, 1.5, 2.0])[:, None] + np.array([0.0, 0.5, 2.25, 3.0])
    assert np.array_equal(bilinear(image, columns, rows)[:, :, 0], expected)
    # the image as rays 0.5 right and 0.25 down of the course's see it
    assert np.array_equal(shifted_by(image, 0.5, 0.25)[:, :, 0],
                          4 * np.array([0.25, 1.25, 2.0])[:, None]
                          + np.array([0.5, 1.5, 2.5, 3.0]))
