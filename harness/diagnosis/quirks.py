"""Requirement or quirk: a candidate that differs from the course program only where that
program has a quirk (tracer/quirks.py) passes, with a note, unless the check is --strict.

For a deterministic case whose reference is the tracer in course mode, and whose scene and
request can show a quirk, the case's "required-only" reference is the same render with the
plain reading of every such quirk switched on. Where it differs from the course's, the case
is quirk-sensitive (its record lists the quirks). A failing image that passes against the
required-only reference is the quirk's doing: `pass` with a `quirk:<code>` finding, or with
--strict `fail` with that finding first (reproduction is proof of the cause, as for the
catalogue's mistakes). Jittered cases are judged as they are: the matrix's jitter cases add
no -bounces, so the one quirk modelled so far cannot show in them."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from raycheck.tracer.mistakes import applicable
from raycheck.tracer.quirks import QUIRKS, Quirk

from ..cases import Case
from ..judge.verdict import KindVerdict, Tolerance, judge_deterministic
from ..records import FindingRecord, Verdict
from ..renderers import Renderer, TracerRenderer
from ..storage.results import CachedRenderer


def required_only(reference: Renderer, case: Case) -> tuple[Renderer, tuple[Quirk, ...]] | None:
    """The case's required-only reference and the quirks it replaces, or None where there is
    none: a jittered case, a reference other than the course-mode tracer, a scene that cannot
    show a quirk."""
    from raycheck.tracer.scene import SceneError, load_scene

    tracer = reference.inner if isinstance(reference, CachedRenderer) else reference
    if case.jittered or not isinstance(tracer, TracerRenderer) or \
            tracer.options.get("mode", "course") != "course" or "mistakes" in tracer.options:
        return None
    try:
        scene = load_scene(case.scene.path)
    except (SceneError, OSError):
        return None
    can = {m.code for m in applicable(scene, case.request)}
    quirks = tuple(q for q in QUIRKS if q.switch.code in can)
    if not quirks:
        return None
    options = {**tracer.options, "mistakes": tuple(q.switch for q in quirks)}
    return TracerRenderer(f"{tracer.name} (required only)", options, tracer.budget), quirks


def differs(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape != b.shape or bool(np.any(a != b))


def quirk_finding(quirks: tuple[Quirk, ...], strict: bool) -> FindingRecord:
    """The finding of an image that the required-only reference reproduces."""
    first = quirks[0]
    said = "; ".join(q.describe() for q in quirks)
    counted = "with --strict it counts" if strict else "it is not counted (--strict counts it)"
    return FindingRecord(f"quirk:{first.code}", f"{said}: {counted}. With the handouts' plain "
                         "reading the reference reproduces your image.")


def judge_quirks(case: Case, kinds: list[KindVerdict], reference: dict[str, np.ndarray],
                 required: dict[str, np.ndarray], candidate: dict[str, np.ndarray],
                 quirks: tuple[Quirk, ...], tolerance: Tolerance,
                 strict: bool) -> list[KindVerdict]:
    """The kinds' verdicts with every failing kind that passes against the required-only
    reference turned into a pass with a quirk finding (a fail with it first, strict)."""
    out = []
    for verdict in kinds:
        kind = verdict.kind
        if verdict.verdict != Verdict.FAIL or kind not in required or kind not in candidate or \
                not differs(reference[kind], required[kind]):
            out.append(verdict)
            continue
        plain = judge_deterministic(kind, required[kind], candidate[kind], tolerance)
        if not plain.passed:
            out.append(verdict)
        elif strict:
            out.append(replace(verdict, findings=[quirk_finding(quirks, True)]))
        else:
            out.append(replace(verdict, verdict=Verdict.PASS, failures=[],
                               findings=[quirk_finding(quirks, False)]))
    return out
