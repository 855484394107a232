"""The comparison suite: every bundled scene x every feature it can exercise, tracer against
the Mitsuba reference, with the report's thresholds (harness/thresholds.py says why each).
A failing case leaves its images, difference and SSIM maps and a page in the folder that the
failure message names."""
from __future__ import annotations

import pytest

from raycheck.harness.case_settings import CaseSettings
from raycheck.harness.cases import case_matrix
from raycheck.harness.catalog import REPO, bundled
from raycheck.harness.judge.verdict import ENGINES_JITTER_TEST, ENGINES_TOLERANCE
from raycheck.harness.pipeline.case import run_case
from raycheck.harness.pipeline.matrix import write_case
from raycheck.harness.provenance import provenance
from raycheck.harness.renderers import MitsubaRenderer, TracerRenderer

SIZE = 48  # small images keep the suite inside CI's budget; scenes with a # size keep theirs
FAILURES = REPO / "out" / "failures"
QUICK = {"plain", "shadows+bounces4", "shadows+bounces3", "jitter+filter"}
# jitter+filter, a statistical comparison, is the quick run's dearest case (a third of this
# file's time): there on two course scenes, the spheres and mirrors and the cube-mapped mesh
# (the sampling pattern and filter are the scene's camera's, whatever its geometry, which the
# deterministic cases compare on every course scene); on the others in the full run
QUICK_JITTER_SCENES = {"spheres_mirror", "cubemap_mesh"}
# realisations of Mitsuba's distribution per jittered case: fewer than the default 64 keep the
# suite inside CI's budget; the test's thresholds follow K (Student t, leave-one-out null)
REALISATIONS = 16


def _params():
    for scene in bundled("course") + bundled("features"):
        cases, _ = case_matrix(scene, scene.size or (SIZE, SIZE))
        for case in cases:
            quick = (scene.path.parent.name == "course" and case.feature in QUICK
                     and (case.feature != "jitter+filter" or scene.name in QUICK_JITTER_SCENES))
            marks = () if quick else (pytest.mark.full,)
            yield pytest.param(case, id=case.id, marks=marks)


@pytest.mark.parametrize("case", list(_params()))
def test_tracer_agrees_with_mitsuba(case):
    result = run_case(case, TracerRenderer(), MitsubaRenderer(),
                      CaseSettings(ENGINES_TOLERANCE, realisations=REALISATIONS,
                                   jitter_test=ENGINES_JITTER_TEST))
    if not result.passed:
        folder = FAILURES / case.scene.name / case.feature.replace("+", "_")
        write_case(result, folder, provenance(0))
        failures = "; ".join(f for k in result.kinds for f in k.failures)
        pytest.fail(f"{case.id}: {failures} (images and maps in {folder})")


def test_matrix_skips_what_a_scene_cannot_exercise():
    scene = next(s for s in bundled("features") if s.name == "no_lights")
    cases, skips = case_matrix(scene)
    assert {s.feature for s in skips} >= {"shadows", "shadows+bounces4"}
    assert all("no lights" in s.reason for s in skips if s.feature == "shadows")
    assert "plain" in {c.feature for c in cases}
    # a case of shadows or mirrors compares only the color image
    mirror = next(s for s in bundled("course") if s.name == "spheres_mirror")
    kinds = {c.feature: c.request.kinds for c in case_matrix(mirror)[0]}
    assert kinds["shadows"] == ("color",) and kinds["plain"] == ("color", "normals", "depth")


def test_the_jitter_test_catches_unjittered_samples():
    # the test has teeth: a "jittered" render without jitter (every sample at the pixel's
    # corner, half a pixel off the jittered mean) fails it against Mitsuba's distribution,
    # where the tracer's own 16 samples pass
    from raycheck.harness.judge.verdict import judge_distribution
    from raycheck.harness.pipeline.case import render_role
    from raycheck.harness.storage.distribution import reference_distribution

    scene = next(s for s in bundled("features") if s.name == "jitter_filter")
    case = next(c for c in case_matrix(scene, (SIZE, SIZE))[0] if c.feature == "jitter")
    d = reference_distribution(MitsubaRenderer(), scene.path, case.request,
                               REALISATIONS).kinds["color"]
    tracer = render_role(TracerRenderer(), case, False).images["color"]
    unjittered = render_role(TracerRenderer(), case, False, jitter=False).images["color"]
    assert judge_distribution("color", tracer, d.bytes, d.poisoned, d.mean).failures == []
    failed = judge_distribution("color", unjittered, d.bytes, d.poisoned, d.mean).failures
    assert [f.split(" (")[0].split(" ")[1] for f in failed] == ["pixels", "mean", "correlation"]
