"""A program's causes shared between its cases (harness/diagnosis/causes.py's priors and
pipeline/matrix.py's first_waves): a cause found in one case is tried first in the others, and
where it reproduces their images the search ends there; where it does not, the search is the
one it would have been without it."""
from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

from raycheck.harness.case_settings import CaseSettings
from raycheck.harness.diagnosis.causes import CauseSearch
from raycheck.harness.judge.verdict import Tolerance
from raycheck.harness.pipeline.matrix import Job, first_waves
from raycheck.harness.records import CaseRecord, Verdict
from raycheck.harness.renderers.builtin import TracerRenderer
from raycheck.tracer.mistakes import Switch, parse_switch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_refutation import ARCH, FEATURES, SIZE, cases, tracer_images  # noqa: E402


def searched(case, program: tuple[Switch, ...], priors=()) -> tuple[CauseSearch, tuple]:
    search = CauseSearch(case, tracer_images(case, *program), Tolerance(), priors=priors)
    found = search.run()
    assert found is not None and found.reproduces
    return search, found.switches


def test_a_prior_that_reproduces_the_images_is_the_cause_after_one_attempt():
    (case,) = cases([ARCH], "plain")
    falloff = parse_switch("falloff_power=1")
    alone, cause = searched(case, (falloff,))
    assert cause == (falloff,) and len(alone.attempts) > 20
    known, cause = searched(case, (falloff,), priors=((falloff,),))
    assert cause == (falloff,) and len(known.attempts) == 1


def test_a_prior_that_does_not_reproduce_them_leaves_the_search_as_it_was():
    (case,) = cases([ARCH], "plain")
    falloff, other = parse_switch("falloff_power=1"), parse_switch("specular_half_vector")
    alone, cause = searched(case, (falloff,))
    tried, same = searched(case, (falloff,), priors=((other,),))
    assert same == cause
    assert set(tried.attempts) == set(alone.attempts) | {(other,)}


def test_two_priors_from_two_cases_are_tried_together():
    """A program with two mistakes whose other cases showed one each: the two together
    reproduce this case, after the two alone."""
    (case,) = cases([ARCH], "plain")
    falloff, half = parse_switch("falloff_power=1"), parse_switch("specular_half_vector")
    search, cause = searched(case, (falloff, half), priors=((falloff,), (half,)))
    assert cause == (falloff, half) and len(search.attempts) == 3


def _row(job: Job, causes: tuple[str, ...]) -> CaseRecord:
    case = job.case
    return CaseRecord(case=case.id, scene=case.scene.id, feature=case.feature,
                      description="", flags=(), size=(SIZE, SIZE), jittered=False,
                      passed=not causes, verdict=Verdict.FAIL if causes else Verdict.PASS,
                      labels={}, times={}, log="", error=None, depth_range=(0.0, 1.0),
                      depth_origin="", kinds=(), causes=causes)


def test_the_waves_are_each_programs_first_case_its_first_of_each_scene_then_the_rest():
    """Programs A and B on two scenes with two features each: the first wave runs each
    program's first case (2 jobs), the second its first case of the other scene (2), the
    third the other 4; each job has the causes its own program's earlier waves found (A: one
    a scene, in the order found; B: none), and the results come back in the jobs' order."""
    scene_cases = cases([ARCH, FEATURES / "triangle.txt"], "plain,shadows")
    assert [c.id for c in scene_cases] == ["arch/plain", "arch/shadows", "triangle/plain",
                                            "triangle/shadows"]
    jobs = [Job(c, TracerRenderer(), TracerRenderer(), CaseSettings(), label=label)
            for label in ("A", "B") for c in scene_cases]
    found = {("A", "arch/plain"): ("falloff_power=1",),
             ("A", "triangle/plain"): ("specular_half_vector",)}
    waves: list[list[Job]] = []

    def run(wave: list[Job]) -> list[CaseRecord]:
        waves.append(list(wave))
        return [_row(j, found.get((j.label, j.case.id), ())) for j in wave]

    first = list(jobs)
    rows = first_waves(first, run, lambda row: row)
    assert [[(j.label, j.case.id) for j in wave] for wave in waves] == [
        [("A", "arch/plain"), ("B", "arch/plain")],
        [("A", "triangle/plain"), ("B", "triangle/plain")],
        [("A", "arch/shadows"), ("A", "triangle/shadows"), ("B", "arch/shadows"),
         ("B", "triangle/shadows")]]
    falloff, half = parse_switch("falloff_power=1"), parse_switch("specular_half_vector")
    assert [j.priors for wave in waves for j in wave] == [
        (), (), ((falloff,),), (), ((falloff,), (half,)), ((falloff,), (half,)), (), ()]
    assert [r.case for r in rows] == [j.case.id for j in jobs]
    # the jobs run are the ones with priors, in place
    assert first == [next(j for wave in waves for j in wave
                          if (j.label, j.case.id) == (job.label, job.case.id))
                     for job in jobs]
    assert first[2] == replace(jobs[2], priors=((falloff,),))
    # the scenes given the other way round: the same waves, the same priors
    waves.clear()
    backwards = [j for label in ("A", "B") for j in reversed(jobs) if j.label == label]
    first_waves(backwards, run, lambda row: row)
    assert {(j.label, j.case.id): j.priors for j in backwards} == {
        (j.label, j.case.id): j.priors for j in first}


def test_a_jittered_case_takes_a_generated_cause_its_unjittered_cases_found():
    """The jittered search tries the generated mistakes its priors name (not the whole
    space): a program with ndc's scale 3 has that cause in its jittered cases too."""
    from test_causes import checked, first_failing, mistaken

    scale = parse_switch("ndc_x_scale.constant=3")
    result = checked(mistaken(scale), ARCH, "jitter", priors=((scale,),))
    top = first_failing(result).findings[0]
    assert top.code == "cause:ndc_x_scale.constant", top
