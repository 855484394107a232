"""Named findings (harness/judge/findings.py): each from a renderer that has exactly that bug
(tests/wrappers/corrupt.py, in process), with the exact code and numbers; the tracer itself
gets none. Tiny images (12x12) and one feature per run."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from raycheck.harness.case_settings import CaseSettings
from raycheck.harness.catalog import scene_headers
from raycheck.harness.judge import findings
from raycheck.harness.judge.verdict import Tolerance
from raycheck.harness.pipeline.case import CaseResult, run_case
from raycheck.harness.pipeline.matrix import Matrix
from raycheck.harness.records import FindingRecord
from raycheck.harness.renderers import renderer_from_spec
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import render
from raycheck.tracer.scene import load_scene

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "wrappers"))
from corrupt import Corrupted, course_bytes  # noqa: E402

SHADOWS = REPO / "scenes" / "features" / "shadows.txt"  # lights, shadows, no mirrors
JITTER_FILTER = REPO / "scenes" / "features" / "jitter_filter.txt"
MIRROR = REPO / "scenes" / "course" / "spheres_mirror.txt"
NO_GATE = REPO / "scenes" / "features" / "specular_no_gate.txt"  # highlights behind surfaces
# the shading fits need objects of some pixels and highlights of a few
FIT_SIZE = 32
SIZE = 12
TRACER = renderer_from_spec("tracer")


def checked(defect: str, scene: Path, feature: str,
            tolerance: Tolerance = Tolerance(), size: int = SIZE,
            causes: bool = True) -> CaseResult:
    """The one case of the scene's feature, the defect's renderer against the tracer; causes:
    whether the cause search runs (off: the findings it would precede)."""
    matrix = Matrix(scene_headers([scene]), Corrupted(defect), TRACER,
                    CaseSettings(tolerance, causes=causes), size=(size, size),
                    features=frozenset({feature}))
    (case,), _ = matrix.cases()
    return run_case(case, matrix.candidate, matrix.reference, matrix.settings)


def codes(result: CaseResult) -> dict[str, tuple[str, list[str]]]:
    """kind -> (verdict, finding codes)."""
    return {k.kind: (k.verdict, [f.code for f in k.findings]) for k in result.kinds}


def top(result: CaseResult, kind: str = "color") -> FindingRecord:
    return next(k for k in result.kinds if k.kind == kind).findings[0]


def reference(result: CaseResult, kind: str, role: str = "reference") -> np.ndarray:
    """A role's image as the course's bytes (the tracer's floats quantised; a candidate's
    8-bit image as it is)."""
    image = result.images[role][kind]
    return image.astype(int) if image.dtype == np.uint8 else course_bytes(image)


def share_changed(a: np.ndarray, b: np.ndarray) -> float:
    """Share of pixels whose channels differ by more than one level (by hand)."""
    return float(np.mean(np.abs(a.astype(int) - b.astype(int)).max(axis=2) > 1))


# --- output level ---------------------------------------------------------------------------
@pytest.mark.parametrize("defect, code, message", [
    ("flip", "flipped_vertical", "Renderer::Render: your image is upside down: it matches "
     "the reference flipped vertically (is row 0 the top of the image?)"),
    ("flip_h", "flipped_horizontal", "Renderer::Render: your image is mirrored left-right: it "
     "matches the reference flipped horizontally (is x pointing right?)"),
    ("transpose", "transposed", "Renderer::Render: your image is transposed: it matches the "
     "reference with rows and columns swapped (are x and y exchanged?)"),
    ("swap_rb", "channel_order", "your channels are in the order BGR: your R, G, B are the "
     "reference's B, G, R (channels swapped when writing?)"),
])
def test_a_changed_image_is_named_in_every_kind_it_breaks(defect, code, message):
    """A flip, transpose or channel swap of every image: the change is the top finding of
    each failing kind, with the reference changed that way as its evidence."""
    result = checked(defect, SHADOWS, "plain")
    failing = [k for k in result.kinds if k.verdict == "fail"]
    assert [k.kind for k in failing] == (["color", "normals"] if defect == "swap_rb"
                                         else ["color", "normals", "depth"])
    for k in failing:  # depth is gray: swapping its channels changes nothing
        assert k.findings[0] == FindingRecord(code, message)
    assert result.evidence["color"].shape == (SIZE, SIZE, 3)


def test_filtered_image_twice_as_bright_names_the_filter_weights():
    """filter_2x doubles the filtered color bytes (clipped at 255): the least-squares ratio
    over unclipped lit values is exactly 2, so is its interval; the unfiltered render matches,
    so filter_weights follows the fitted kernel (every weight doubled: test_check.py)."""
    result = checked("filter_2x", JITTER_FILTER, "filter", causes=False)
    assert codes(result)["color"] == ("fail", ["filter_kernel", "filter_weights",
                                               "brightness_scale"])
    color = next(k for k in result.kinds if k.kind == "color")
    assert color.findings[1:] == [
        FindingRecord("filter_weights", "Renderer::Render: your -filter image is 2.00x as "
                      "bright as the reference (2.00-2.00), your unfiltered one is not: do "
                      "the filter weights sum to 1?"),
        FindingRecord("brightness_scale", "your image is 2.00x as bright as the "
                      "reference (2.00-2.00): do the filter weights sum to 1?")]



def test_brightness_scale_interval_from_the_residuals():
    """A ratio of 1.5 with a +-1 level alternating error: k and its 95% interval by hand."""
    ref = np.tile(np.arange(20, 120, dtype=np.int32)[:, None, None], (1, 4, 3))
    got = np.floor(ref * 1.5).astype(np.int32) + np.where(np.arange(4) % 2, 1, -1)[None, :, None]
    r, c = ref.ravel().astype(float), got.ravel().astype(float)
    k = r @ c / (r @ r)
    half = 1.96 * np.sqrt(((c - k * r) ** 2).sum() / (r.size - 1) / (r @ r))
    found = findings.brightness_scale(ref, got, findings.Fit())
    assert found.message == (f"your image is {k:.2f}x as bright as the reference "
                             f"({k - half:.2f}-{k + half:.2f})")
    assert found.message == "your image is 1.50x as bright as the reference (1.50-1.50)"


def test_gamma_encoded_color():
    result = checked("gamma", SHADOWS, "plain")
    assert codes(result)["color"] == ("fail", ["gamma_encoded"])
    assert top(result) == FindingRecord("gamma_encoded", "your image is gamma-encoded: it "
                                        "matches 255*(reference/255)^(1/2.2); the course "
                                        "writes linear values, without sRGB or gamma")


def test_constant_offset_of_twelve_levels():
    result = checked("offset", SHADOWS, "plain")
    assert codes(result)["color"] == ("fail", ["constant_offset"])
    assert top(result).message == ("your image is +12 levels off the reference everywhere "
                                      "(a constant added to every value: an ambient term "
                                      "counted twice?)")


def test_rounding_instead_of_truncating_shows_at_tolerance_zero():
    """Rounding moves bytes by one level (within the default tolerance); at --tolerance 0 it
    fails and is named, with the share of values whose fraction was >= .5 (by hand)."""
    result = checked("rounding", SHADOWS, "plain", Tolerance(levels=0))
    floats = result.images["reference"]["color"]
    fraction = np.clip(np.where(np.abs(floats) < 1e30, floats, 0), 0, 1) * np.float32(255)
    up = float(np.mean(np.floor(fraction + 0.5) > np.floor(fraction)))
    assert codes(result)["color"][1][0] == "quantisation"
    assert top(result).message == (
        f"your bytes are rounded where the course truncates (int(255*v)): {up:.1%} of the "
        "values are 1 level above the reference's, all where the fraction was >= .5")


@pytest.mark.parametrize("defect, name", [("normals_clip", "n*255 clipped to 0..255"),
                                          ("normals_abs", "|n|*255")])
def test_normals_mapping(defect, name):
    result = checked(defect, SHADOWS, "plain")
    assert codes(result) == {"color": ("pass", []), "normals": ("fail", ["normals_mapping"]),
                             "depth": ("pass", [])}
    assert top(result, "normals").message == (
        f"your normals image is {name}, not (n+1)/2*255: negative components do not map to "
        "0..127")


def test_depth_inverted():
    result = checked("depth_inverted", SHADOWS, "plain")
    assert codes(result)["depth"] == ("fail", ["depth_mapping"])
    assert np.array_equal(result.evidence["depth"], 255 - reference(result, "depth"))


# --- feature level --------------------------------------------------------------------------
def test_ignored_shadows_flag_is_no_effect_with_the_reference_share():
    """-shadows dropped: the flag changes nothing in the candidate; the message gives the
    share of pixels it changes in the reference (flag-off render by hand), then the missing
    shadows."""
    result = checked("no_shadows", SHADOWS, "shadows", causes=False)
    plain = checked("none", SHADOWS, "plain")
    share = share_changed(reference(result, "color"), reference(plain, "color"))
    assert codes(result)["color"] == ("fail", ["no_effect", "shadow_missing"])
    assert top(result).message == (f"-shadows changes nothing in your image; in the "
                                      f"reference it changes {share:.1%} of the pixels: is "
                                      "the flag read?")


def darkened(on: np.ndarray, off: np.ndarray) -> np.ndarray:
    """Pixels that shadows darken by more than one level in some channel (by hand)."""
    return (off.astype(int) - on.astype(int)).max(axis=2) > 1


def shadow_masks(result: CaseResult, scene: Path) -> tuple[np.ndarray, np.ndarray]:
    """(pixels the reference shadows, pixels the candidate shadows) against the plain render
    (the defects leave plain images as the tracer's)."""
    plain = reference(checked("none", scene, "plain"), "color")
    return (darkened(reference(result, "color"), plain),
            darkened(reference(result, "color", "candidate"), plain))


def test_shadows_on_every_fourth_row_only_are_missing_shadows():
    """Of the reference's shadowed pixels, those the candidate does not darken: 3 in 4 rows."""
    result = checked("few_shadows", MIRROR, "shadows")
    ref, got = shadow_masks(result, MIRROR)
    share = (ref & ~got).sum() / ref.sum()
    assert codes(result)["color"] == ("fail", ["shadow_missing"])
    assert top(result).message == (
        f"{share:.0%} of the {ref.sum()} pixels the reference shadows are lit in your image: "
        "is every light's shadow ray traced?")
    assert share >= 0.5


def test_speckled_self_shadowing_is_acne():
    """acne halves every other lit surface pixel: the share that the candidate darkens of the
    reference's pixels with no blocked shadow ray (its parts: auxiliary images), by hand."""
    result = checked("acne", SHADOWS, "shadows")
    ref, got = shadow_masks(result, SHADOWS)
    aux = render(load_scene(SHADOWS), RenderOptions(width=SIZE, height=SIZE, shadows=True,
                                                    aux=("shadow", "mirror_depth"))).aux
    unshadowed = (aux["object"] >= 0) & (aux["mirror_depth"] == 0) & ~aux["shadow"].any(axis=2)
    ref = ref | ~unshadowed
    acne = ~ref & got
    assert codes(result)["color"] == ("fail", ["shadow_acne"])
    assert top(result).message == (
        f"your image shadows {acne.sum() / (~ref).sum():.1%} of the pixels the reference "
        f"lights ({acne.sum()} pixels): does the shadow ray start off the surface "
        "(p + epsilon*dir)?")


def test_one_bounce_fewer_matches_the_reference_at_bounces_three():
    result = checked("one_bounce_fewer", MIRROR, "bounces", causes=False)
    assert codes(result)["color"] == ("fail", ["reflection_depth"])
    assert top(result).message == ("your mirrors trace one bounce fewer: your -bounces 4 "
                                      "image matches the reference's -bounces 3")


def test_jitter_without_noise():
    result = checked("no_jitter", SHADOWS, "jitter", causes=False)
    assert {k: v[1][:2] for k, v in codes(result).items()} == \
        {k: ["jitter_no_noise", "no_effect"] for k in ("color", "normals", "depth")}
    assert top(result).message.startswith("Renderer::Render: your -jitter image equals your "
                                             "render without -jitter; in the reference jitter "
                                             "changes ")
    # with the cause search: the mistake that makes that image, every sample at x + 0
    with_causes = checked("no_jitter", SHADOWS, "jitter")
    assert {k: v[1][:1] for k, v in codes(with_causes).items()} == \
        {k: ["cause:jitter_fixed"] for k in ("color", "normals", "depth")}
    assert "every -jitter sample at the same place, x + 0 " in top(with_causes).message


# --- the tracer itself ----------------------------------------------------------------------
@pytest.mark.parametrize("feature", ["plain", "shadows", "bounces", "filter", "jitter"])
def test_the_tracer_as_candidate_gets_no_finding(feature):
    result = checked("none", MIRROR, feature)
    assert all(k.verdict == "pass" and k.findings == [] for k in result.kinds)
    assert result.evidence == {}


# --- shading level: the candidate fitted on the reference's parts ----------------------------
def test_ambient_once_per_light_is_the_ambient_term_scaled_by_the_light_count():
    """Two lights, no shadows: every pixel gets the ambient term twice (2.00x on each object
    the fit takes, the last sphere's among them)."""
    result = checked("ambient_per_light", MIRROR, "plain", size=FIT_SIZE, causes=False)
    finding = top(result)
    assert finding.code == "term_scaled:ambient"
    assert "object 5 (sphere, line 76, material 5) 2.00x" in finding.message
    assert finding.message.startswith("your ambient term is added once per unshadowed "
                                         "light, not once (object 0 (plane, line 54")
    assert finding.message.endswith("is ambient ⊙ kd inside the loop over lights?")


def test_ambient_per_unshadowed_light_is_named_with_shadows():
    """With shadows the count of lights that add it varies per pixel: the ambient-per-light
    model fits where the scaled one cannot."""
    result = checked("ambient_per_light", MIRROR, "shadows", size=FIT_SIZE, causes=False)
    assert top(result).code == "term_scaled:ambient"
    assert top(result).message.startswith("your ambient term is added once per unshadowed "
                                             "light, not once (object 0 (plane, line 54")


def test_specular_gated_by_n_dot_l_misses_the_specular_term_behind_the_surface():
    result = checked("specular_gated", NO_GATE, "plain", size=FIT_SIZE, causes=False)
    assert top(result).code == "term_missing:specular_behind"
    assert "object 1 (plane, line 42, material 1) -0.00x" in top(result).message or \
        "object 1 (plane, line 42, material 1) 0.00x" in top(result).message


def test_half_vector_highlights_fit_about_a_quarter_of_the_shininess():
    """Blinn-Phong's (N·H)^s is close to (R·L)^(s/4) near the highlight's peak (the angle
    between R and L is twice that between N and H): the fitted exponents lie near s/4."""
    result = checked("half_vector", MIRROR, "plain", size=FIT_SIZE, causes=False)
    finding = next(k for k in result.kinds if k.kind == "color").findings[0]
    assert finding.code == "shininess"
    pairs = re.findall(r"(\d+(?:\.\d+)?) where the material says (\d+)", finding.message)
    assert pairs and all(0.12 < float(fit) / float(own) < 0.45 for fit, own in pairs)


def test_dropped_ray_offset_is_shadow_acne_and_reflection_acne():
    assert top(checked("no_offset", SHADOWS, "shadows", size=FIT_SIZE, causes=False)).code \
        == "shadow_acne"
    result = checked("no_offset", MIRROR, "bounces", size=FIT_SIZE, causes=False)
    assert top(result).code == "reflection_acne"
    assert re.fullmatch(r"your image differs on \d+% of the \d+ pixels the reference mirrors, "
                        r"and hardly elsewhere: does the reflected ray start off the surface "
                        r"\(p \+ 0\.01\*R\)\?", top(result).message)


@pytest.mark.parametrize("feature", ["plain", "shadows", "bounces"])
def test_the_tracer_explains_itself_by_its_own_parts(feature):
    """The tracer's image fitted on its own parts: every coefficient 1 within 2% or its
    99.9% interval (8-bit rounding), nothing named."""
    from raycheck.harness.cases import Case
    from raycheck.harness.judge.parts import reference_parts
    from raycheck.harness.judge.shading import fit_object, shading_findings

    matrix = Matrix(scene_headers([MIRROR]), TRACER, TRACER, size=(FIT_SIZE, FIT_SIZE),
                    features=frozenset({feature}))
    (case,), _ = matrix.cases()
    parts = reference_parts(Case(case.scene, case.feature, case.request))
    got = course_bytes(parts.color)
    assert shading_findings(parts, got) == []
    fits = [f for o in parts.objects if (f := fit_object(parts, got, o.index))]
    assert fits and all(abs(c - 1) <= max(0.02, 3.29 * se)
                        for f in fits for c, se in f.coefficients.values())
