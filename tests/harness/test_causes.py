"""The cause search (harness/diagnosis/causes.py, jitter_causes.py for jittered cases): the tracer
with a catalogue mistake on is the candidate, and the top finding of its failing image names
that mistake with its parameter; pairs too; a mistake outside the catalogue is said to be
unexplained, not named wrongly. The expected causes are the candidates' own switches: the
search does not know them. 64x64 images; the quick run tries one mistake per family, the full
run (CI) every catalogue entry. The jittered searches are statistical: their candidates and
the reference's realisations are seeded, so each outcome here is fixed."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from raycheck.harness.case_settings import CaseSettings
from raycheck.harness.catalog import scene_headers
from raycheck.harness.judge.findings import as_bytes
from raycheck.harness.pipeline.case import CaseResult, run_case
from raycheck.harness.pipeline.matrix import Matrix
from raycheck.harness.renderers.builtin import TracerRenderer
from raycheck.tracer.mistakes import CATALOGUE, JITTER_MISTAKES, Switch, parse_switch
from raycheck.tracer.quirks import BY_SWITCH

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(REPO / "tests" / "wrappers"))

from bench_causes import _named, switch  # noqa: E402
from corrupt import Corrupted  # noqa: E402

SIZE = 64
COURSE, FEATURES = REPO / "scenes" / "course", REPO / "scenes" / "features"
ARCH, CUBEMAP_MESH = COURSE / "arch.txt", COURSE / "cubemap_mesh.txt"
# a scene and feature where each mistake shows at 64x64 (the first of the bundled scenes'
# cases where it fails, in their order)
WHERE = {
    "specular_gated": (FEATURES / "phong_bump.txt", "plain"),
    "ambient_per_lit_light": (ARCH, "shadows"),
    "shadow_missing": (ARCH, "shadows"), "shadow_offset": (ARCH, "shadows"),
    "shadow_inverted": (ARCH, "shadows"), "shadow_always": (ARCH, "shadows"),
    "shadow_offset_normal": (COURSE / "smooth_mesh.txt", "shadows"),
    "shadow_beyond_light": (ARCH, "shadows"),
    "shadow_distance_squared": (FEATURES / "bounces.txt", "shadows"),
    "reflection_offset_normal": (CUBEMAP_MESH, "bounces"),
    "reflection_per_lit_light": (ARCH, "shadows+bounces"),
    "reflection_depth": (CUBEMAP_MESH, "bounces"),
    "plane_offset_negated": (COURSE / "axes.txt", "plain"),
    "plane_normalised": (FEATURES / "plane_raw_normal.txt", "plain"),
    "plane_shading_normal_normalised": (FEATURES / "plane_raw_normal.txt", "plain"),
    "sphere_far_root": (CUBEMAP_MESH, "plain"),
    "sphere_inside_missed": (FEATURES / "inside_sphere.txt", "plain"),
    "filter_ignored": (ARCH, "filter"),
    **{code: (ARCH, "jitter") for code in JITTER_MISTAKES},
    **{code: (CUBEMAP_MESH, "plain") for code in (
        "triangle_flat_normals", "triangle_normal_one_vertex", "triangle_normal_weights",
        "triangle_normal_unnormalised")},
}
QUICK = {"falloff_power", "specular_half_vector", "shadow_offset", "reflection_depth",
         "triangle_flat_normals", "sphere_inside_missed", "ndc_pixel_centre", "jitter_samples"}


def where(code: str) -> tuple[Path, str]:
    default = (ARCH, "bounces" if code.startswith("reflection_") else "plain")
    return WHERE.get(code, default)


def checked(candidate, scene: Path, feature: str, priors=(), size: int = SIZE) -> CaseResult:
    # strict: byte for byte with the course program, so that reflection_gate=0 (the plain
    # reading of its mirror gate, diagnosis/quirks.py) fails and is searched like every mistake
    matrix = Matrix(scene_headers([scene]), candidate, TracerRenderer(),
                    CaseSettings(strict=True), size=(size, size),
                    features=frozenset({feature}))
    (case,), _ = matrix.cases()
    return run_case(case, matrix.candidate, matrix.reference, matrix.settings, priors)


def mistaken(*switches: Switch) -> TracerRenderer:
    return TracerRenderer("tracer --mistake " + ",".join(map(str, switches)),
                          {"mistakes": tuple(map(str, switches))})


def color(result: CaseResult):
    return next(k for k in result.kinds if k.kind == "color")


def first_failing(result: CaseResult):
    return next(k for k in result.kinds if k.verdict == "fail")


@pytest.mark.parametrize("code", [pytest.param(m.code, marks=() if m.code in QUICK
                                               else pytest.mark.full) for m in CATALOGUE])
def test_the_top_finding_names_the_mistake_with_its_parameter(code):
    on = switch(code)  # tools/bench_causes.py's value, off its sweep where it has one
    result = checked(mistaken(on), *where(code))
    failing = first_failing(result)  # color, but for a jittered normal and depth
    findings = failing.findings
    quirk = BY_SWITCH.get(on)
    if quirk is not None:  # the quirk's own finding first, then the search's
        assert findings[0].code == f"quirk:{quirk.code}"
        findings = findings[1:]
    top = findings[0]
    assert top.code.startswith("cause:") and _named(top.message, (on,)), top
    said = "the course program " if quirk is not None else "your program "
    assert f"{on.mistake.function}: {said}" in top.message
    if code in JITTER_MISTAKES - {"jitter_fixed"}:  # a distribution: its mean is shown
        assert "a likely draw of the reference's distribution" in top.message
        return
    # the evidence is the reference with the mistake found: the candidate's own image here
    kind = failing.kind
    assert np.array_equal(result.evidence[kind],
                          as_bytes(result.images["candidate"][kind]).astype(np.uint8))


def test_the_parameter_is_found_by_refining_between_the_sweeps_values():
    """falloff_power=1.5 lies between the sweep's 1 and 3: found by bisection."""
    on = parse_switch("falloff_power=1.5")
    top = color(checked(mistaken(on), ARCH, "plain")).findings[0]
    assert top.code == "cause:falloff_power"
    assert top.message.endswith("--mistake falloff_power=1.5")


@pytest.mark.parametrize("pair", [
    ("falloff_power=1", "specular_half_vector"),
    pytest.param(("shadow_offset=0", "ambient_per_light"), marks=pytest.mark.full),
    pytest.param(("reflection_unweighted", "shadow_missing"), marks=pytest.mark.full),
])
def test_two_mistakes_at_once_are_both_named(pair):
    switches = tuple(map(parse_switch, pair))
    feature = "shadows+bounces" if "shadow_missing" in pair else \
        "shadows" if "shadow_offset=0" in pair else "plain"
    findings = color(checked(mistaken(*switches), ARCH, feature)).findings
    assert {f.code for f in findings[:2]} == {f"cause:{s.code}" for s in switches}
    assert "together with" in findings[0].message
    assert all(_named(f.message, switches) for f in findings[:2])


def test_a_jittered_case_is_explained_by_a_cause_found_before_with_its_jitter_mistake():
    """The program's shading mistake, found in the scene's plain case, and its sample count
    together explain its jittered image: both are named, the first given as the jittered
    case's prior (as the check's runner gives it)."""
    candidate = mistaken(parse_switch("specular_half_vector"), parse_switch("jitter_samples=4"))
    plain = checked(candidate, ARCH, "plain")
    assert color(plain).findings[0].code == "cause:specular_half_vector"
    # the cause first; its images cannot tell it from the cosine raised to a quarter of the
    # shininess (R.L^(s/4) follows N.H^s closely), an explanation given as well
    assert plain.explanations[0] == (parse_switch("specular_half_vector"),)
    jittered = color(checked(candidate, ARCH, "jitter", plain.explanations)).findings
    assert {f.code for f in jittered[:2]} == {"cause:specular_half_vector",
                                                 "cause:jitter_samples"}
    assert all(_named(f.message, (parse_switch("jitter_samples=4"),
                                     parse_switch("specular_half_vector")))
               for f in jittered[:2])


def test_a_jittered_kind_that_passed_and_no_cause_changes_is_not_judged_again():
    """A falloff mistake changes the color alone. Its jittered case (128x128, the seeds the
    check uses) fails only in the color; the search judges the distribution with the cause on
    in the color, not again in the depth, which the check's test passed at 64 realisations
    and the search's 32 would reject (its mean z^2 just under the band)."""
    candidate = mistaken(parse_switch("falloff_power=1"))
    falloff = FEATURES / "falloff.txt"
    plain = checked(candidate, falloff, "plain", size=128)
    assert plain.explanations[0] == (parse_switch("falloff_power=1"),)
    jittered = checked(candidate, falloff, "jitter", plain.explanations, size=128)
    assert [k.kind for k in jittered.kinds if k.verdict == "fail"] == ["color"]
    assert color(jittered).findings[0].code == "cause:falloff_power"


def test_one_jitter_pattern_for_every_pixel_is_not_named_as_another_jitter_mistake():
    """srand(seed) in the pixel loop: every pixel draws the same offsets. No catalogue entry
    makes that distribution; the statistical search must not name a sample count for it.
    Without -jitter, at three times the size, the images match: it is located in the sampling
    (localise.py)."""
    result = checked(Corrupted("shared_pattern"), ARCH, "jitter")
    for k in result.kinds:
        assert k.verdict == "fail"
        assert k.findings[0].code == "located", k.findings[0]
        assert k.findings[0].message.startswith(
            "Renderer::Render: no known mistake reproduces this image; the evidence points "
            f"here: your {k.kind} image differs only with -jitter: rendered without it at "
            "three times the size")


def test_a_mistake_outside_the_catalogue_is_unexplained_not_misnamed():
    """One object rendered with the next material (tests/wrappers/geometry_bugs.py): no
    catalogue mistake reproduces it; its normals and depth match, so the shading is where to
    look, and no one function of it is named (localise.py); the object-level finding follows
    as a hint."""
    findings = color(checked(Corrupted("one_material"), FEATURES / "shadows.txt",
                             "plain")).findings
    assert [f.code for f in findings[:2]] == ["located", "object:0"]
    assert findings[0].message.startswith(
        "no known mistake reproduces this image; look at Material::shade, "
        "DirectionalLight::getIllumination, PointLight::getIllumination or Renderer::traceRay: "
        "the color differs on ")


def test_the_tracer_itself_gets_no_finding():
    result = checked(TracerRenderer(), ARCH, "shadows+bounces")
    assert all(k.verdict == "pass" and not k.findings for k in result.kinds)


def test_without_the_search_the_flag_level_finding_comes_first():
    """--no-causes (causes=False): -shadows ignored is named by its flag-level finding."""
    matrix = Matrix(scene_headers([ARCH]), mistaken(parse_switch("shadow_missing")),
                    TracerRenderer(), CaseSettings(causes=False), size=(SIZE, SIZE),
                    features=frozenset({"shadows"}))
    (case,), _ = matrix.cases()
    result = run_case(case, matrix.candidate, matrix.reference, matrix.settings)
    assert [f.code for f in color(result).findings][:1] == ["no_effect"]


def test_a_kind_that_fails_for_a_second_reason_leaves_the_others_their_cause():
    """falloff_power=1 and the depth image inverted (an output change no mistake makes): no
    set of mistakes reproduces every kind, but the falloff alone reproduces the color image
    and leaves the normals passing: the color gets it as its cause (the bench counts it as
    a reproduction), the depth its own finding."""
    result = checked(Corrupted("depth_inverted@falloff_power=1"), FEATURES / "shadows.txt",
                     "plain")
    kinds = {k.kind: k for k in result.kinds}
    assert kinds["normals"].verdict == "pass"
    top = kinds["color"].findings[0]
    assert top.code == "cause:falloff_power"
    assert "With this mistake, the reference reproduces your image of this kind (color); " \
        "your depth image differs for another reason: " in top.message
    assert kinds["depth"].findings[0].code == "depth_mapping"


def test_a_cause_another_functions_mistake_matches_as_well_names_both_functions_first():
    """Where an alternative of the cause has the cause's images, to the level, and no mistake
    in the cause's function, the images cannot tell which function is wrong: the first
    finding opens with both and lists them; alternatives that share the cause's function, or
    whose images differ within the tolerance, leave it as it is."""
    from raycheck.harness.diagnosis.causes import elsewhere, undecided_lead

    loop = parse_switch("trace_light_loop.constant=1")
    unset = parse_switch("directional_intensity_set.deleted")
    ambient = parse_switch("trace_ambient.sign")  # traceRay's too
    image = {"color": np.zeros((2, 2, 3), np.uint8)}
    darker = {"color": np.zeros((2, 2, 3), np.uint8) + np.uint8([[[0], [1]]])}
    assert elsewhere(((loop,), image), [((unset,), image)]) == \
        ("DirectionalLight::getIllumination",)
    assert elsewhere(((loop,), image), [((unset,), darker)]) == ()
    assert elsewhere(((loop,), image), [((ambient,), image), ((ambient, unset), image)]) == ()
    assert undecided_lead(loop, ()) == (f"Renderer::traceRay: your program {loop.describe()}",
                                        ())
    said, functions = undecided_lead(loop, ("DirectionalLight::getIllumination",))
    assert functions == ("Renderer::traceRay", "DirectionalLight::getIllumination")
    assert said == ("Renderer::traceRay or DirectionalLight::getIllumination: these images "
                    f"cannot tell which of them is wrong; your program {loop.describe()}")
