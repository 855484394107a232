"""The mistakes operators generate at the sites of the course's formulas (tracer/operators.py),
found by the cause search (harness/diagnosis/causes.py): the tracer with one of them switched
on is the candidate, and the top finding of its first failing image names it, in its function,
with its parameter, and its evidence is the candidate's image; or where another mistake of
that function gives the very same images, that one with this one named beside it. The search
does not know the switch: it reaches the generated mistakes only where the catalogue
reproduces nothing. 64x64 images; the quick run tries five sites, the full run
(CI) every operator."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from raycheck.harness.judge.findings import as_bytes
from raycheck.tracer.mistake_model import Needs
from raycheck.tracer.mistakes import Switch, parse_switch
from raycheck.tracer.operators import GENERATED
from raycheck.tracer.pixel_index import OUTPUT_FORMS, TAP_FORMS, Form

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "harness"))

from test_causes import checked, first_failing, mistaken  # noqa: E402


def form(forms: tuple[Form, ...], text: str) -> str:
    """An INDEX site's value that reads as `text`."""
    return str(next(k for k, f in enumerate(forms) if f.text == text))


COURSE, FEATURES = REPO / "scenes" / "course", REPO / "scenes" / "features"
ARCH = COURSE / "arch.txt"
SPHERES = COURSE / "spheres_mirror.txt"
MESH = COURSE / "cubemap_mesh.txt"
WIDE_DEPTH = FEATURES / "inside_sphere.txt"
TRIANGLES = FEATURES / "triangle.txt"
ELLIPSOID = COURSE / "ellipsoid.txt"
ANGLE_1 = REPO / "scenes" / "extreme" / "angle_1.txt"  # a telephoto view of sunk spheres
PHONG = FEATURES / "phong_bump.txt"  # highlights of shininess 0 to 200
# a scene and feature where each site shows at 64x64, and the value a program might have there
# (a mutation tool's: a constant plus or minus one, zero, negated)
CASES: dict[str, tuple[Path, str, str]] = {
    "ndc_x_scale.constant": (ARCH, "plain", "3"),
    "ndc_x_denominator.constant": (ARCH, "plain", "0"),
    "ndc_x_shift.constant": (ARCH, "plain", "0"),
    "ndc_y_scale.constant": (ARCH, "plain", "1"),
    "ndc_y_denominator.constant": (ARCH, "plain", "2"),
    "ndc_y_shift.constant": (ARCH, "plain", "-1"),
    **{f"ndc_{axis}_{part}.{op}": (ARCH, "plain", "") for axis in "xy"
       for part, ops in (("product", ("plus", "minus", "divided")),
                         ("quotient", ("plus", "minus", "times"))) for op in ops},
    "normals_offset_x.constant": (ARCH, "plain", "0"),
    "normals_offset_y.constant": (ARCH, "plain", "2"),
    "normals_offset_z.constant": (ARCH, "plain", "0"),
    "normals_divisor.constant": (ARCH, "plain", "1"),
    # t * 6 and t + 6 are both past depth_max for all of the arch: a range from 2 to 30
    "depth_offset.plus": (WIDE_DEPTH, "plain", ""),
    "depth_offset.times": (WIDE_DEPTH, "plain", ""),
    "depth_offset.divided": (WIDE_DEPTH, "plain", ""),
    "depth_range.plus": (WIDE_DEPTH, "plain", ""),
    "depth_range.times": (WIDE_DEPTH, "plain", ""),
    "depth_range.divided": (WIDE_DEPTH, "plain", ""),
    "sample_loop.deleted": (ARCH, "plain", ""),
    # each pixel's one ray added up twice: every image twice as bright
    "sample_loop_start.constant": (ARCH, "plain", "-1"),
    # a loop that ends after 4 of the 16 samples: a quarter as bright, and noisier
    "sample_loop_bound.constant": (ARCH, "jitter", "4"),
    "jitter_width.constant": (ARCH, "jitter", "2"),
    "color_sum.assigned": (ARCH, "jitter", ""),
    "normals_sum.assigned": (ARCH, "jitter", ""),
    "depth_sum.assigned": (ARCH, "jitter", ""),
    "color_add.deleted": (ARCH, "plain", ""),
    "normals_add.deleted": (ARCH, "plain", ""),
    "depth_add.deleted": (ARCH, "plain", ""),
    # a pixel's 16 samples added up and not divided (or multiplied) by their number
    **{f"{kind}_mean.{op}": (ARCH, "jitter", "") for kind in ("color", "normals", "depth")
       for op in ("deleted", "times")},
    "columns_start.constant": (ARCH, "plain", "1"),
    "columns_end.constant": (ARCH, "plain", "2"),
    "rows_start.constant": (ARCH, "plain", "1"),
    "rows_end.constant": (ARCH, "plain", "1"),
    "output_columns_start.constant": (ARCH, "filter", "1"),
    "output_columns_end.constant": (ARCH, "filter", "1"),
    "output_rows_start.constant": (ARCH, "filter", "2"),
    "output_rows_end.constant": (ARCH, "filter", "1"),
    "color_start_r.constant": (ARCH, "plain", "1"),
    "color_start_g.constant": (ARCH, "plain", "-1"),
    "color_start_b.constant": (ARCH, "plain", "1"),
    "normals_start_x.constant": (ARCH, "plain", "-1"),
    "normals_start_y.constant": (ARCH, "plain", "1"),
    "normals_start_z.constant": (ARCH, "plain", "1"),
    "depth_start.constant": (ARCH, "plain", "1"),
    **{f"filter_weight_{j}{i}.constant": (ARCH, "filter", "0") for j in range(3)
       for i in range(3)},
    "filter_divisor.constant": (ARCH, "filter", "15"),
    # each tap three sub-pixels to the right; x and y swapped (every row the bottom row,
    # y / w + x, is ndc y's 2 as 0 too: that site, tried first, is named)
    "filter_tap_index.index": (ARCH, "filter", form(TAP_FORMS, "(3 * y + j) * w + (3 + x) + i")),
    "output_index.index": (ARCH, "plain", form(OUTPUT_FORMS, "x * w + y")),
    "sphere_offset.plus": (SPHERES, "plain", ""),
    "sphere_b.sign": (SPHERES, "plain", ""),
    "sphere_radius.unsquared": (SPHERES, "plain", ""),
    "sphere_disc_factor.constant": (SPHERES, "plain", "3"),
    # below 0 it changes nothing: the square root of a negative discriminant is NaN, a miss
    "sphere_disc_threshold.constant": (SPHERES, "plain", "1"),
    # a comparison's value numbers it: 0 <, 1 <=, 2 >, 3 >=, 4 ==, 5 !=
    "sphere_disc_threshold.comparison": (SPHERES, "plain", "3"),
    "sphere_near_root.comparison": (FEATURES / "inside_sphere.txt", "plain", "0"),
    "sphere_near_root.deleted": (WIDE_DEPTH, "plain", ""),
    "sphere_b_factor.constant": (SPHERES, "plain", "4"),
    # + r² misses every sphere: from outside, as a flipped b does; from inside, only it
    "sphere_c_term.plus": (WIDE_DEPTH, "plain", ""),
    "sphere_c_term.times": (SPHERES, "plain", ""),
    "sphere_c_term.divided": (SPHERES, "plain", ""),
    # r - r + r and 4 + a (a = d·d = 1) miss or shrink every sphere seen from outside, as many
    # mistakes do; from inside, only they
    "sphere_radius_product.plus": (WIDE_DEPTH, "plain", ""),
    "sphere_radius_product.minus": (SPHERES, "plain", ""),
    "sphere_radius_product.divided": (SPHERES, "plain", ""),
    "sphere_disc.plus": (SPHERES, "plain", ""),
    "sphere_disc.times": (SPHERES, "plain", ""),
    "sphere_disc.divided": (SPHERES, "plain", ""),
    "sphere_disc_product.plus": (WIDE_DEPTH, "plain", ""),
    "sphere_disc_product.minus": (SPHERES, "plain", ""),
    # 4 / a is 4 * a where a = d·d = 1: only a scaled sphere's a differs
    "sphere_disc_product.divided": (ELLIPSOID, "plain", ""),
    "sphere_sqrt.deleted": (SPHERES, "plain", ""),
    "sphere_near_term.times": (SPHERES, "plain", ""),
    "sphere_near_term.divided": (SPHERES, "plain", ""),
    "sphere_near_divisor.constant": (SPHERES, "plain", "1"),
    # the farther root is the one taken from inside a sphere
    "sphere_far_term.times": (WIDE_DEPTH, "plain", ""),
    "sphere_far_term.divided": (WIDE_DEPTH, "plain", ""),
    "sphere_far_divisor.constant": (WIDE_DEPTH, "plain", "1"),
    # shadow rays from inside the sphere toward a light: the wall behind them is hit at 10000
    "sphere_behind.deleted": (WIDE_DEPTH, "shadows", ""),
    "sphere_normal_center.plus": (SPHERES, "plain", ""),
    "sphere_normal_center.times": (SPHERES, "plain", ""),
    "sphere_normal.sign": (SPHERES, "plain", ""),
    "sphere_normal_unit.deleted": (SPHERES, "plain", ""),
    "plane_behind.comparison": (ARCH, "plain", "2"),
    # spheres_mirror.txt lists its floor first: tested against no hit, `t > h.t` never holds
    # (the floor is gone); inside_sphere.txt lists its floor last, which wins wherever it is
    # hit; angle_1.txt's red sphere, sunk in the floor and listed after it, shows through it
    "plane_closer.comparison": (SPHERES, "plain", "2"),
    "plane_closer.deleted": (WIDE_DEPTH, "plain", ""),
    "sphere_closer.comparison": (ANGLE_1, "plain", "5"),
    "sphere_closer.deleted": (ANGLE_1, "plain", ""),
    "shade_diffuse_clamp.comparison": (SPHERES, "plain", "2"),
    "shade_specular_clamp.comparison": (SPHERES, "plain", "4"),
    "plane_origin_term.sign": (ARCH, "plain", ""),
    "plane_numerator.times": (ARCH, "plain", ""),
    "plane_numerator.divided": (ARCH, "plain", ""),
    # t > 0: shadow rays find the triangles behind the surface, no camera ray any
    "triangle_behind.comparison": (FEATURES / "shadows.txt", "shadows", "2"),
    "triangle_origin.index": (TRIANGLES, "plain", "1"),
    "triangle_u_index.index": (TRIANGLES, "plain", "1"),
    "triangle_v_index.index": (TRIANGLES, "plain", "2"),
    "triangle_u_low.constant": (TRIANGLES, "plain", "-1"),
    "triangle_u_low.comparison": (TRIANGLES, "plain", "2"),
    "triangle_v_low.constant": (TRIANGLES, "plain", "-1"),
    "triangle_v_low.comparison": (TRIANGLES, "plain", "2"),
    "triangle_uv_sum.constant": (TRIANGLES, "plain", "2"),
    "triangle_uv_sum.comparison": (TRIANGLES, "plain", "0"),
    "triangle_u_low.deleted": (TRIANGLES, "plain", ""),
    "triangle_v_low.deleted": (TRIANGLES, "plain", ""),
    "triangle_uv_sum.deleted": (TRIANGLES, "plain", ""),
    "triangle_inside.deleted": (TRIANGLES, "plain", ""),
    # a scene whose background is not one colour: a camera that looks away shows it
    "triangle_accept.deleted": (MESH, "plain", ""),
    "triangle_weight0_one.constant": (MESH, "plain", "0"),
    "triangle_weight0_u.plus": (MESH, "plain", ""),
    "triangle_weight0_u.times": (MESH, "plain", ""),
    "triangle_weight0_u.divided": (MESH, "plain", ""),
    "triangle_weight0_v.plus": (MESH, "plain", ""),
    "triangle_weight0_v.times": (MESH, "plain", ""),
    "triangle_weight0_v.divided": (MESH, "plain", ""),
    "triangle_weight_0.weight": (MESH, "plain", "1"),
    "triangle_weight_1.weight": (MESH, "plain", "3"),
    "triangle_weight_2.weight": (MESH, "plain", "1"),
    "triangle_vertex_0.index": (MESH, "plain", "1"),
    "triangle_vertex_1.index": (MESH, "plain", "2"),
    "triangle_vertex_2.index": (MESH, "plain", "0"),
    "triangle_term_0.plus": (MESH, "plain", ""),
    "triangle_term_0.minus": (MESH, "plain", ""),
    "triangle_term_1.plus": (MESH, "plain", ""),
    "triangle_term_1.minus": (MESH, "plain", ""),
    "triangle_term_2.plus": (MESH, "plain", ""),
    "triangle_term_2.minus": (MESH, "plain", ""),
    "triangle_sum_1.minus": (MESH, "plain", ""),
    "triangle_sum_1.times": (MESH, "plain", ""),
    "triangle_sum_1.divided": (MESH, "plain", ""),
    "triangle_sum_2.minus": (MESH, "plain", ""),
    "triangle_sum_2.times": (MESH, "plain", ""),
    "triangle_sum_2.divided": (MESH, "plain", ""),
    "transform_origin_divide.plus": (ELLIPSOID, "plain", ""),
    "transform_origin_divide.minus": (ELLIPSOID, "plain", ""),
    # the transformed triangle among untransformed ones: every triangle tested (no BVH)
    "transform_direction_w.constant": (TRIANGLES, "plain", "1"),
    "transform_origin_w.constant": (ELLIPSOID, "plain", "1"),
    "transform_ray.swapped": (ELLIPSOID, "plain", ""),
    "transform_normal_matrix.index": (ELLIPSOID, "plain", "1"),
    "falloff_division.plus": (ARCH, "plain", ""),
    "falloff_division.minus": (ARCH, "plain", ""),
    "falloff_division.times": (ARCH, "plain", ""),
    # with 1 the highlight is the course's raised to about 8x the shininess: the catalogue's
    # shininess_scale=8 reproduces it, and is named
    "shade_mirror_factor.constant": (SPHERES, "plain", "3"),
    "shade_diffuse_clamp.constant": (SPHERES, "plain", "1"),
    # an odd shininess: (-1)^15 = -1 is told from 1^15
    "shade_specular_clamp.constant": (FEATURES / "smooth_vs_flat.txt", "plain", "1"),
    "trace_mirror_factor.constant": (SPHERES, "bounces", "1"),
    "trace_light_sum.minus": (ARCH, "plain", ""),
    # the first of two point lights alone: no other mistake leaves out the second one
    "trace_light_loop.constant": (SPHERES, "shadows", "1"),
    # two point lights: no light function's mistake leaves out the first alone
    "trace_light_start.constant": (SPHERES, "plain", "1"),
    "trace_blocked_light.constant": (SPHERES, "shadows", "1"),
    "trace_ambient.sign": (ARCH, "plain", ""),
    # arch has a point and a directional light: one light's term left out is told from the
    # light loop's
    "light_direction_set.deleted": (ARCH, "plain", ""),
    "light_intensity_set.deleted": (ARCH, "plain", ""),
    "directional_direction.sign": (ARCH, "plain", ""),
    "directional_direction_set.deleted": (ARCH, "plain", ""),
    "directional_intensity_set.deleted": (ARCH, "plain", ""),
    "light_vector.plus": (ARCH, "plain", ""),
    "light_vector.times": (ARCH, "plain", ""),
    "light_normalise.plus": (ARCH, "plain", ""),
    "light_normalise.minus": (ARCH, "plain", ""),
    "light_normalise.times": (ARCH, "plain", ""),
    "falloff_product.plus": (ARCH, "plain", ""),
    "falloff_product.minus": (ARCH, "plain", ""),
    "falloff_product.divided": (ARCH, "plain", ""),
    "falloff_outer.plus": (ARCH, "plain", ""),
    "falloff_outer.minus": (ARCH, "plain", ""),
    # below 1 every N·L but an exact 1 is clamped; below -1, none is (the catalogue's
    # diffuse_unclamped, which is named)
    "shade_diffuse_threshold.constant": (SPHERES, "plain", "1"),
    "shade_specular_threshold.constant": (PHONG, "plain", "1"),
    "shade_mirror_product.plus": (PHONG, "plain", ""),
    "shade_mirror_product.minus": (SPHERES, "plain", ""),
    "shade_mirror_product.divided": (SPHERES, "plain", ""),
    "shade_mirror_normal.plus": (SPHERES, "plain", ""),
    "shade_mirror_normal.minus": (SPHERES, "plain", ""),
    "shade_mirror_difference.times": (SPHERES, "plain", ""),
    "shade_diffuse_light.plus": (SPHERES, "plain", ""),
    "shade_diffuse_light.minus": (SPHERES, "plain", ""),
    "shade_specular_light.plus": (SPHERES, "plain", ""),
    "shade_specular_light.minus": (SPHERES, "plain", ""),
    "shade_power.swapped": (SPHERES, "plain", ""),
    "shade_diffuse_product.plus": (SPHERES, "plain", ""),
    "shade_diffuse_product.minus": (SPHERES, "plain", ""),
    "shade_specular_product.plus": (SPHERES, "plain", ""),
    "shade_specular_product.minus": (SPHERES, "plain", ""),
    "shade_sum.minus": (SPHERES, "plain", ""),
    "shade_sum.times": (SPHERES, "plain", ""),
    "trace_mirror_product.plus": (SPHERES, "bounces", ""),
    "trace_mirror_product.minus": (SPHERES, "bounces", ""),
    "trace_mirror_product.divided": (SPHERES, "bounces", ""),
    "trace_mirror_normal.plus": (SPHERES, "bounces", ""),
    "trace_mirror_normal.minus": (SPHERES, "bounces", ""),
    "trace_mirror_difference.times": (SPHERES, "bounces", ""),
    "trace_mirror_origin.minus": (SPHERES, "bounces", ""),
    "trace_mirror_origin.times": (SPHERES, "bounces", ""),
    "trace_mirror_origin.divided": (SPHERES, "bounces", ""),
    "trace_mirror_offset.plus": (SPHERES, "bounces", ""),
    "trace_mirror_offset.minus": (SPHERES, "bounces", ""),
    "trace_mirror_step.constant": (SPHERES, "bounces", "-1"),
    "trace_mirror_sum.minus": (SPHERES, "bounces", ""),
    "trace_mirror_weight.plus": (SPHERES, "bounces", ""),
    "trace_mirror_weight.minus": (SPHERES, "bounces", ""),
    "trace_ambient_product.plus": (ARCH, "plain", ""),
    "trace_ambient_product.minus": (ARCH, "plain", ""),
    # blocked only by a closest blocker beyond the light: no blocker of arch's is
    "trace_shadow_test.comparison": (ARCH, "shadows", "0"),
    "trace_shadow_origin.times": (ARCH, "shadows", ""),
    "trace_shadow_origin.divided": (ARCH, "shadows", ""),
    "trace_shadow_ray.swapped": (ARCH, "shadows", ""),
    "trace_mirror_ray.swapped": (SPHERES, "bounces", ""),
    "trace_start_r.constant": (ARCH, "plain", "1"),
    "trace_start_g.constant": (ARCH, "plain", "-1"),
    "trace_start_b.constant": (SPHERES, "bounces", "1"),
}
# one of each way a site is computed: in the kernel's camera, on the host, a comparison, a
# weight, an arithmetic operator in the shading
QUICK = {"ndc_x_scale.constant", "filter_weight_11.constant", "sphere_near_root.comparison",
         "triangle_weight_1.weight", "falloff_division.times"}


def spelled(code: str) -> Switch:
    value = CASES[code][2]
    return parse_switch(f"{code}={value}" if value else code)


def test_every_generated_mistake_has_a_case():
    assert set(CASES) == {m.code for m in GENERATED}


@pytest.mark.parametrize("code", [pytest.param(m.code, marks=() if m.code in QUICK
                                               else pytest.mark.full) for m in GENERATED])
def test_the_top_finding_names_the_generated_mistake(code):
    on = spelled(code)
    scene, feature, _ = CASES[code]
    result = checked(mistaken(on), scene, feature)
    failing = first_failing(result)
    top = failing.findings[0]
    if top.functions and len(top.functions) > 1:
        # a mistake in another function whose images equal these: neither function leads and
        # both are named (arch's lights are a point light and a directional one, neither
        # blocked without -shadows: the directional light's term missing is the light loop
        # ending after the first light's)
        assert top.code.startswith("cause:") and on.mistake.function in top.functions, top
        assert f"--mistake {on}" in top.message, top
        return
    if top.code != f"cause:{code}":
        # another mistake of the same function whose images equal these (a normal image's
        # sums starting at -1, or its offset of -1: the same image), with this one named
        assert top.code.startswith("cause:") and top.message.startswith(
            f"{on.mistake.function}: your program "), top
        assert f"These images cannot tell it from: your program {on.describe()} " \
               f"(--mistake {on})" in top.message, top
        return
    assert top.message.startswith(f"{on.mistake.function}: your program {on.describe()}"), top
    if Needs.JITTER in on.mistake.needs:  # a distribution: its mean is shown
        assert "a likely draw of the reference's distribution" in top.message, top
        return
    assert top.message.endswith(f"--mistake {on}"), top
    assert np.array_equal(result.evidence[failing.kind],
                          as_bytes(result.images["candidate"][failing.kind]).astype(np.uint8))
