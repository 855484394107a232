"""One case: a candidate's render judged against a reference's, kind by kind.

A pure function of (case, candidate, reference, tolerance): it renders, judges and returns the
images, so it can run in any process. Deterministic cases compare the two images directly.
Jittered cases cannot (two renderers draw different samples): the candidate's image is one draw,
judged by a statistical test (judge/statistics.py) against the reference's sampling
distribution, K realisations of the same request (distribution.py, cached on disk).

Roles (records.Role): the candidate, the reference and, for jittered cases, the mean (the mean
8-bit value of the reference's realisations, what the pictures compare the candidate with).
What the candidate gets wrong is a verdict; only a failing reference is an error of the
harness's own (its code starts with "reference_").
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field, replace

import numpy as np

from raycheck.tracer.mistakes import Switch

from ..case_settings import CaseSettings
from ..cases import Case
from ..diagnosis.case import Renders, crash_located, diagnose_case
from ..diagnosis.crash_site import crash_site, hang_site
from ..diagnosis.localise import NO_IMAGE, failed_saving, unwritten
from ..diagnosis.quirks import differs, judge_quirks, required_only
from ..diagnosis.refute import Refuting
from ..judge.findings import Finding
from ..judge.verdict import (
    KindVerdict,
    Tolerance,
    error_verdict,
    judge_deterministic,
    judge_distribution,
)
from ..records import CauseRecord, FindingRecord, ObjectView, Role, Verdict
from ..renderers import Renderer, RenderError, fits_request
from ..storage.disk_cache import cache_folder, engine_digest, load_arrays, save_arrays
from ..storage.distribution import Distributions, reference_distribution
from ..storage.results import content_key, request_key


@dataclass
class RoleRun:
    images: dict[str, np.ndarray]
    cold_s: float
    warm_s: float | None
    errors: dict[str, tuple[str, str]] = field(default_factory=dict)  # kind -> (code, message)
    log: str = ""


@dataclass
class CaseResult:
    case: Case
    labels: dict[Role, str]  # role -> renderer name
    kinds: list[KindVerdict]
    times: dict[Role, dict[str, float | None]]  # role -> cold_s / warm_s
    images: dict[Role, dict[str, np.ndarray]]  # role -> kind -> image
    log: str = ""  # the candidate's last output lines
    error: FindingRecord | None = None  # the whole render failed: its code and message
    evidence: dict[str, np.ndarray] = field(default_factory=dict)  # kind -> top finding's image
    quirks: tuple[str, ...] = ()  # the course program's quirks its reference shows (quirks.py)
    # the cause search's explanations: the cause's mistakes, then those the images cannot
    # tell from it (diagnosis/case.py's Searched)
    explanations: tuple[tuple[Switch, ...], ...] = ()
    cause: CauseRecord | None = None  # the cause in words (diagnosis/case.py's cause_record)
    # the geometry kinds that differ and what it shows of each intersect's work (cross_case)
    geometry: tuple[str, ...] = ()
    views: tuple[ObjectView, ...] = ()

    @property
    def passed(self) -> bool:
        return all(k.passed for k in self.kinds)

    @property
    def verdict(self) -> Verdict:
        """error if any kind erred, else fail if any failed, else pass."""
        verdicts = {k.verdict for k in self.kinds}
        return next((v for v in (Verdict.ERROR, Verdict.FAIL) if v in verdicts), Verdict.PASS)


def render_role(renderer: Renderer, case: Case, warm: bool, **changes) -> RoleRun:
    """Open, render (twice with warm=True, where the renderer re-runs warm), close. RenderError
    propagates; a kind the renderer could not deliver is in RoleRun.errors."""
    request = replace(case.request, **changes) if changes else case.request
    start = time.perf_counter()
    session = renderer.open(case.scene.path, request)
    try:
        result = session.render()
        cold = time.perf_counter() - start
        warm_s = None
        if warm and renderer.caps.warm_reruns:
            again = session.render()
            warm_s, result = again.seconds, again
    finally:
        session.close()
    errors = {k: (e.code, e.message) for k, e in result.errors.items()}
    return RoleRun(result.images, cold, warm_s, errors, result.log)


def cached_role(renderer: Renderer, case: Case, warm: bool, **changes) -> RoleRun:
    """render_role for a reference, through the disk cache (disk_cache.py): its render
    depends only on the scene's content, the request and the engine, so each is made once per
    machine, not once per run. The times are those measured when it was rendered (the report's
    time columns stay the engine's). Renders with a failed kind are not kept."""
    request = replace(case.request, **changes) if changes else case.request
    key = content_key(request_key(renderer, case.scene.path, request), warm, engine_digest())
    path = cache_folder() / "renders" / f"{key}.npz"
    data = load_arrays(path)
    if data is not None and "meta" in data:
        images = {k[len("image_"):]: v for k, v in data.items() if k.startswith("image_")}
        try:
            meta = json.loads(str(data["meta"]))
            warm_s = None if meta["warm_s"] is None else float(meta["warm_s"])
            if fits_request(images, request):
                return RoleRun(images, float(meta["cold_s"]), warm_s, log=str(meta["log"]))
        except (ValueError, KeyError, TypeError):
            pass  # a damaged or edited entry: rendered again and replaced
    run = render_role(renderer, case, warm, **changes)
    if not run.errors:
        meta = {"cold_s": run.cold_s, "warm_s": run.warm_s, "log": run.log}
        save_arrays(path, {"meta": np.array(json.dumps(meta)),
                           **{f"image_{k}": v for k, v in run.images.items()}}, compress=False)
    return run


# what a program does where its render failed this way, for a finding that says where
# (crash_located): "your program {...} only with -filter"
FAILED = {"crash": "is {}", "exit_status": "{}"}


def run_case(case: Case, candidate: Renderer, reference: Renderer,
             settings: CaseSettings = CaseSettings(),
             priors: tuple[tuple[Switch, ...], ...] = (),
             refuting: Refuting = Refuting()) -> CaseResult:
    """The case rendered, judged and diagnosed as `settings` say; priors: the causes found in
    the same program's other cases, tried first; refuting: the causes the program's passing
    cases rule out, and those cases (diagnosis/refute.py)."""
    tolerance, warm, jitter_test = settings.tolerance, settings.warm, settings.jitter_test
    labels = {Role.CANDIDATE: candidate.name, Role.REFERENCE: reference.name}
    runs: dict[Role, RoleRun] = {}
    dist: Distributions | None = None
    try:
        runs[Role.REFERENCE] = cached_role(reference, case, warm)
        if case.jittered:
            dist = reference_distribution(reference, case.scene.path, case.request,
                                          settings.realisations)
            runs[Role.MEAN] = RoleRun({k: d.mean for k, d in dist.kinds.items()}, dist.seconds,
                                   None)
            labels[Role.MEAN] = f"{reference.name} mean of {settings.realisations}"
    except RenderError as e:
        return _failed(case, labels, runs, f"reference_{e.code}",
                       f"the reference ({reference.name}) failed: {e.message}", e.log)

    def render(renderer: Renderer, case: Case, warm: bool, **changes) -> RoleRun:
        # the reference's flag-off renders are references too: cached like its first
        role = cached_role if renderer is reference else render_role
        return role(renderer, case, warm, **changes)

    renderers: dict[Role, Renderer] = {Role.CANDIDATE: candidate, Role.REFERENCE: reference}
    try:
        runs[Role.CANDIDATE] = render_role(candidate, case, warm)
    except RenderError as e:
        located = None
        if settings.causes:
            if e.code == "missing_output":
                located = unwritten().finding(NO_IMAGE)
            elif e.code == "exit_status" and e.written:
                located = failed_saving(e.message, e.written).finding(NO_IMAGE)
            elif e.code == "crash":
                located = crash_site(case.scene.path, case.request, candidate)
            elif e.code == "timeout":
                located = hang_site(case.scene.path, case.request, candidate)
            if located is None and e.code in FAILED:
                located = crash_located(case, FAILED[e.code].format(e.message),
                                        Renders(case, renderers, render))
        return _failed(case, labels, runs, e.code, e.message, e.log, located)
    got, ref = runs[Role.CANDIDATE], runs[Role.REFERENCE]
    kinds = []
    for kind in case.request.kinds:
        if kind in got.errors:
            kinds.append(error_verdict(kind, *got.errors[kind]))
            if got.errors[kind][0] == "missing_output" and settings.causes:
                where = unwritten(kind, tuple(k for k in case.request.kinds if k in got.images))
                lead = f"your program gives no {kind} image of this case"
                kinds[-1].findings.insert(0, where.finding(lead).record())
        elif dist is not None:
            image = got.images[kind]
            prepared = dist.prepared(kind, image.shape[2] if image.ndim == 3 else 1, jitter_test)
            kinds.append(judge_distribution(kind, image, prepared, dist.kinds[kind].poisoned,
                                            dist.kinds[kind].mean, jitter_test))
        else:
            kinds.append(judge_deterministic(kind, ref.images[kind], got.images[kind],
                                             tolerance))
    kinds, quirks = _quirks(case, kinds, reference, runs, tolerance, warm, settings.strict)
    images = {r: run.images for r, run in runs.items()}
    # what is wrong, not only how much: findings of the failing kinds (more renders, if needed)
    diagnosis = diagnose_case(case, kinds, images, renderers, render, settings, priors,
                              refuting)
    return CaseResult(case, labels, kinds, _times(runs), images, got.log,
                      evidence=diagnosis.evidence, quirks=quirks,
                      explanations=diagnosis.explanations, cause=diagnosis.cause,
                      geometry=diagnosis.geometry, views=diagnosis.views)


def _quirks(case: Case, kinds: list[KindVerdict], reference: Renderer,
            runs: dict[Role, RoleRun], tolerance: Tolerance, warm: bool,
            strict: bool) -> tuple[list[KindVerdict], tuple[str, ...]]:
    """The verdicts with quirks.py's judgement, and the quirks the case's reference shows."""
    required = required_only(reference, case)
    if required is None:
        return kinds, ()
    renderer, quirks = required
    try:
        plain = cached_role(renderer, case, warm)
    except RenderError:  # the course's reference rendered: this one is a variant of it
        return kinds, ()
    ref = runs[Role.REFERENCE].images
    if not any(differs(ref[k], plain.images[k]) for k in ref if k in plain.images):
        return kinds, ()
    return (judge_quirks(case, kinds, ref, plain.images, runs[Role.CANDIDATE].images, quirks,
                         tolerance, strict), tuple(q.code for q in quirks))


def _times(runs: dict[Role, RoleRun]) -> dict[Role, dict[str, float | None]]:
    return {r: {"cold_s": run.cold_s, "warm_s": run.warm_s} for r, run in runs.items()}


def _failed(case: Case, labels: dict[Role, str], runs: dict[Role, RoleRun], code: str,
            message: str, log: str, located: Finding | None = None) -> CaseResult:
    """The result of a case the candidate or the reference gave no images of; located: where
    the candidate's failure points (crash_site.py, localise.py's unwritten, case.py's
    crash_located), its kinds' top finding."""
    kinds = [error_verdict(k, code, message) for k in case.request.kinds]
    if located is not None:
        for verdict in kinds:
            verdict.findings.insert(0, located.record())
    return CaseResult(case, labels, kinds, _times(runs),
                      {r: run.images for r, run in runs.items()}, log,
                      FindingRecord(code, message))
