"""Refutation of a cause by the cases a program passes (harness/diagnosis/refute.py, and the
rounds of pipeline/refutation.py): a mistake that would change a passing image where the
program's image agrees with the reference is ruled out; the program's own mistake, and one
that changes only what the program already gets wrong, are not."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from raycheck.harness.case_settings import CaseSettings
from raycheck.harness.catalog import scene_headers
from raycheck.harness.diagnosis.refute import (
    REFUTING_CASES,
    REFUTING_SHARE,
    Refutation,
    Trial,
    Witness,
    refutations,
)
from raycheck.harness.judge.findings import as_bytes
from raycheck.harness.judge.verdict import Tolerance
from raycheck.harness.pipeline.matrix import Matrix
from raycheck.harness.pipeline.refutation import WITNESSES, Ran, Refuter
from raycheck.harness.records import CaseRecord, Verdict
from raycheck.harness.renderers.builtin import TracerRenderer
from raycheck.tracer.mistakes import Switch, parse_switch

REPO = Path(__file__).resolve().parents[2]
COURSE, FEATURES = REPO / "scenes" / "course", REPO / "scenes" / "features"
ARCH = COURSE / "arch.txt"
SIZE = 32


def cases(scenes: list[Path], features: str):
    matrix = Matrix(scene_headers(scenes), TracerRenderer(), TracerRenderer(),
                    CaseSettings(strict=True), size=(SIZE, SIZE),
                    features=frozenset(features.split(",")))
    return matrix.cases()[0]


def tracer_images(case, *switches: Switch) -> dict[str, np.ndarray]:
    from raycheck.tracer.options import RenderOptions
    from raycheck.tracer.render import render
    from raycheck.tracer.scene import load_scene
    from raycheck.tracer.scene.request import request_fields

    result = render(load_scene(case.scene.path),
                    RenderOptions(**request_fields(case.request), mistakes=switches))
    return {k: as_bytes(getattr(result, k)).astype(np.uint8) for k in case.request.kinds}


def test_a_passing_case_rules_out_a_mistake_it_would_show_and_keeps_the_programs_own():
    """The program (the tracer with falloff_power=1) on arch, plain: a mirrored camera would
    change the image where the program's agrees with the reference: ruled out; the program's
    own mistake is not; nor is falloff_power=1.5, which changes only the pixels the program
    already gets wrong (a case that passes with a difference of its own)."""
    (case,) = cases([ARCH], "plain")
    own, other, mirror = (parse_switch(s) for s in
                          ("falloff_power=1", "falloff_power=1.5", "ndc_x_scale.constant=-2"))
    tolerance = Tolerance()
    found = refutations(Trial(Witness(case, tracer_images(case, own)), (own, other, mirror),
                              tolerance))
    assert [(r.switch, r.case, r.kind) for r in found] == [(mirror.exact, case.id, "color")]
    assert found[0].share > REFUTING_SHARE * tolerance.share
    assert found[0].describe().startswith("ndc_x_scale.constant=-2 would change ")
    assert found[0].describe().endswith(f"of your program's color image of {case.id}, "
                                        "which passes")


def test_the_course_program_refutes_nothing_that_does_not_show_on_its_case():
    """A shadow mistake on a case without -shadows cannot change its images: no refutation
    (and the rounds would not even try it there: mistakes.applicable)."""
    (case,) = cases([ARCH], "plain")
    switch = parse_switch("shadow_always")
    assert refutations(Trial(Witness(case, tracer_images(case)), (switch,), Tolerance())) == ()


def _row(case, verdict: Verdict, causes: tuple[str, ...] = ()) -> CaseRecord:
    return CaseRecord(case=case.id, scene=case.scene.id, feature=case.feature,
                      description="", flags=(), size=(SIZE, SIZE), jittered=False,
                      passed=verdict == Verdict.PASS, verdict=verdict, labels={}, times={},
                      log="", error=None, depth_range=(0.0, 1.0), depth_origin="",
                      kinds=(), causes=causes)


def test_the_rounds_try_each_cause_on_passing_cases_it_can_change_one_a_scene_first():
    """Program A fails arch/plain with cause shadow_always and ndc_x_scale.constant=-2; it
    passes arch/shadows, arch/bounces and the plain and shadows cases of two more scenes.
    shadow_always is tried only where -shadows is on (arch/shadows, then the other scenes'
    shadows cases), the mirrored camera on every passing case, each scene's first before any
    second: at most REFUTING_CASES each. Program B's passing cases are not A's."""
    scenes = [ARCH, COURSE / "spheres_mirror.txt", FEATURES / "triangle.txt"]
    all_cases = {c.id: c for c in cases(scenes, "plain,shadows,bounces")}
    assert REFUTING_CASES == 3
    image = {"color": np.zeros((SIZE, SIZE, 3), np.uint8)}
    tolerance = Tolerance()
    a, b = ("", "A"), ("", "B")
    failing_id = "arch/plain"
    ran = []
    for cid, case in all_cases.items():
        if cid == failing_id:
            ran.append(Ran(a, case, _row(case, Verdict.FAIL, (
                "shadow_always", "ndc_x_scale.constant=-2.0")), None, tolerance))
        else:
            ran.append(Ran(a, case, _row(case, Verdict.PASS), image, tolerance))
    ran += [Ran(b, r.case, r.row, r.candidate, tolerance) for r in ran if r.candidate]
    refuter = Refuter()
    trials = refuter.trials(ran)
    assert {program for program, _ in trials} == {a}
    trials = [t for _, t in trials]
    tried = {(t.witness.case.id, str(s)) for t in trials for s in t.switches}
    ids = sorted(all_cases)
    shadows = [i for i in ids if i.endswith("/shadows")]
    firsts = ["arch/shadows", "spheres_mirror/plain", "triangle/plain"]  # matrix order
    assert {c for c, s in tried if s == "shadow_always"} == set(shadows)
    assert {c for c, s in tried if s == "ndc_x_scale.constant=-2"} == set(firsts)
    assert all(t.witness.case.id != failing_id for t in trials)
    assert len(trials) == len({t.witness.case.id for t in trials})  # one trial a case
    # tried once: a second call finds nothing new to try
    assert refuter.trials(ran) == []
    mirror = next(t for t in trials if t.witness.case.id == "spheres_mirror/plain")
    refuted = Refutation("ndc_x_scale.constant=-2.0", mirror.witness.case.id, "color", 0.5)
    refuter.take(ran, [(a, t) for t in trials], [(refuted,) if t is mirror else ()
                                                 for t in trials])
    assert refuter.of(b).refuted == ()
    (kept,) = refuter.of(a).refuted
    assert (kept.switch, kept.case, kept.explained) == ("ndc_x_scale.constant=-2.0",
                                                       "spheres_mirror/plain", (failing_id,))
    # the failing case is searched again without it, with A's passing cases as witnesses
    # (each scene's first, then each one's second, ..., up to WITNESSES); nothing of B's
    ((index, again),) = refuter.again(ran).items()
    assert index == [r.case.id for r in ran].index(failing_id) and again.refuted == (kept,)
    assert WITNESSES == 6
    assert [w.case.id for w in again.witnesses] == firsts + [
        "arch/bounces3", "spheres_mirror/shadows", "triangle/shadows"]
