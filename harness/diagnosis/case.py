"""The findings of one case's failing kinds (judge.findings), with the renders they need.

Output-level findings need only the case's own images. Where none explains a kind, the
feature-level ones compare flag-on with flag-off images: both renderers render the case once
more with each of its flags off, and for -bounces N the reference at N-1 and N+1. These extra
renders happen only for failing cases, each at most once; a render that fails leaves its
findings out (the case's verdict stands as judged). Where neither explains a color image, the
reference's parts (the tracer's auxiliary images of the case, one render) explain it term by
term (judge.shading).
"""
from __future__ import annotations

import shlex
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Protocol

import numpy as np

from raycheck.tracer.mistakes import Switch
from raycheck.tracer.quirks import BY_SWITCH

from ..case_settings import CaseSettings
from ..cases import DEFAULT_BOUNCES, Case
from ..judge import findings, geometry, shading
from ..judge.findings import Finding, Fit, FlagPair, as_bytes
from ..judge.parts import Parts, reference_parts
from ..judge.statistics import Statistic
from ..judge.verdict import KindVerdict, Tolerance, judge_deterministic
from ..records import CauseRecord, ObjectView, Role, Verdict
from ..renderers import Renderer, RenderError
from .causes import CauseSearch, cause_findings, cause_how, kinds_how
from .cross_case import object_views
from .jitter_causes import JitterSearch, jitter_cause_findings, jitter_how
from .localise import (
    GEOMETRY_KINDS,
    NO_IMAGE,
    RENDER,
    OneRay,
    case_scene,
    follows_flag,
    geometry_changed,
    localise,
    shows_nothing,
)
from .refute import Refuting

# whole-image changes that many mistakes make (a light too bright, an ambient term too many):
# a mistake that reproduces the image goes before them
UNSPECIFIC_OUTPUT = frozenset({"brightness_scale", "constant_offset", "filter_weights"})
# flag -> the request changes that turn it off
FLAG_OFF: dict[str, dict[str, Any]] = {"-shadows": {"shadows": False}, "-bounces": {"bounces": 0},
            "-filter": {"filter": False}, "-jitter": {"jitter": False}}


# flag -> the request changes that turn it on, where a case does not ask for it (-bounces: as
# deep as a case of it goes by default)
FLAG_ON: dict[str, dict[str, Any]] = {"-shadows": {"shadows": True},
                                      f"-bounces {DEFAULT_BOUNCES}": {"bounces": DEFAULT_BOUNCES}}


def flag_off(case: Case, flag: str) -> dict[str, Any]:
    """The request changes that show a case's difference without the flag, for localise.py:
    -jitter and -filter place rays at sub-pixel positions, which a geometry bug can show at
    and one ray a pixel miss; without them they are rendered at three times the size."""
    if flag in ("-jitter", "-filter"):
        r = case.request
        return {"jitter": False, "filter": False, "width": 3 * r.width, "height": 3 * r.height}
    return FLAG_OFF[flag]


def flags_on(case: Case) -> list[str]:
    r = case.request
    on = {"-shadows": r.shadows, "-bounces": bool(r.bounces), "-filter": r.filter,
          "-jitter": r.jitter}
    return [f for f, v in on.items() if v]


class Rendered(Protocol):
    """What a role's render gives the findings: kind -> image."""

    images: dict[str, np.ndarray]


RenderRole = Callable[..., Rendered]  # (renderer, case, warm, **request changes)
RoleImages = dict[Role, dict[str, np.ndarray]]  # role -> kind -> image


@dataclass
class Renders:
    """The case's extra renders, each made once on first use; None where it failed."""

    case: Case
    renderers: dict[Role, Renderer]
    render_role: RenderRole  # pipeline/case.py's render_role, or its cached_role
    done: dict[tuple, dict[str, np.ndarray] | None] = field(default_factory=dict)
    _parts: dict[int, Parts | None] = field(default_factory=dict)  # scale -> rendered

    def images(self, role: Role, **changes: Any) -> dict[str, np.ndarray] | None:
        """The role's images of the case with the request's `changes`, as rendered."""
        key = (role, tuple(sorted(changes.items())))
        if key not in self.done:
            try:
                run = self.render_role(self.renderers[role], self.case, False, **changes)
                self.done[key] = run.images
            except RenderError:
                self.done[key] = None
        return self.done[key]

    def image(self, role: Role, kind: str, **changes: Any) -> np.ndarray | None:
        images = self.images(role, **changes)
        return None if images is None or kind not in images else as_bytes(images[kind])

    def parts(self, scale: int = 1) -> Parts | None:
        """The course-mode tracer's parts of the case's color image (without -jitter and
        -filter: one ray a pixel) at `scale` times its size, rendered once in this process;
        None where the scene cannot be rendered. Whatever the reference is: the parts are the
        course's model of the image (spec §6), which the tracer reproduces and any reference
        approximates."""
        if scale not in self._parts:
            r = self.case.request
            self._parts[scale] = reference_parts(self.case if scale == 1 else replace(
                self.case, request=replace(r, width=scale * r.width, height=scale * r.height)))
        return self._parts[scale]

    def rendered_parts(self, scale: int = 1) -> Parts | None:
        """The parts where the findings have rendered them, else None (no render here)."""
        return self._parts.get(scale)


def output_findings(case: Case, verdict: KindVerdict, images: RoleImages,
                    renders: Renders) -> list[Finding]:
    """findings.diagnose against what the kind is judged by; a brightness scale of a -filter
    image whose unfiltered render matches becomes filter_weights, first."""
    kind = verdict.kind
    if case.jittered:  # against the mean of the reference's distribution, within its noise
        mean = images[Role.MEAN][kind]
        noise = float(np.mean(np.abs(as_bytes(images[Role.REFERENCE][kind]) - as_bytes(mean))))
        return findings.diagnose(kind, case.request.filter, mean, images[Role.CANDIDATE][kind],
                                 Fit(noise=noise))
    found = findings.diagnose(kind, case.request.filter, images[Role.REFERENCE][kind],
                              images[Role.CANDIDATE][kind])
    scale = next((f for f in found if f.code == "brightness_scale"), None)
    if scale is not None and case.request.filter:
        ref_off = renders.image(Role.REFERENCE, kind, **FLAG_OFF["-filter"])
        got_off = renders.image(Role.CANDIDATE, kind, **FLAG_OFF["-filter"])
        if ref_off is not None and got_off is not None:
            weights = findings.filter_weights(scale, ref_off, got_off)
            found = ([weights] if weights else []) + found
    return found


def kernel_findings(case: Case, verdict: KindVerdict,
                    images: RoleImages, renders: Renders
                    ) -> list[Finding]:
    """A -filter image's weights fitted on the reference rendered at 3x without -filter
    (findings.filter_kernel); only where no mistake explains it (a shifted camera fits a
    shifted kernel too)."""
    if not case.request.filter or case.jittered:
        return []
    got = as_bytes(images[Role.CANDIDATE][verdict.kind])
    h, w = got.shape[:2]
    big = renders.image(Role.REFERENCE, verdict.kind, filter=False, width=3 * w, height=3 * h)
    kernel = None if big is None else findings.filter_kernel(big, got)
    return [] if kernel is None else [kernel]


def feature_findings(case: Case, verdict: KindVerdict,
                     images: RoleImages, renders: Renders
                     ) -> list[Finding]:
    """Per flag of the case (jittered cases: -jitter only), the flag-on minus flag-off
    findings: for -bounces reflection_depth (one bounce fewer or more, not none), then
    no_effect / jitter_no_noise, then for -shadows shadow_missing and shadow_acne."""
    kind, request = verdict.kind, case.request
    got = as_bytes(images[Role.CANDIDATE][kind])
    ref = as_bytes(images[Role.REFERENCE][kind])
    found: list[Finding | None] = []
    def parts() -> Parts | None:
        """The reference's parts where they describe this case's pixels."""
        found = None if case.jittered or request.filter else renders.parts()
        return found if found is not None and found.color.shape == got.shape else None

    for flag in (["-jitter"] if case.jittered else flags_on(case)):
        ref_off = renders.image(Role.REFERENCE, kind, **FLAG_OFF[flag])
        got_off = renders.image(Role.CANDIDATE, kind, **FLAG_OFF[flag])
        if ref_off is None or got_off is None:
            continue
        ref_pair, got_pair = FlagPair(ref, ref_off), FlagPair(got, got_off)
        if flag == "-bounces":
            # -bounces N traced as 0 (no mirrors) is no_effect's; N-1 and N+1 above it
            n = request.bounces
            others = {m: renders.image(Role.REFERENCE, kind, bounces=m)
                      for m in (n - 1, n + 1) if m > 0}
            found.append(findings.reflection_depth(
                got, n, {m: im for m, im in others.items() if im is not None},
                Fit(reference_misfit=Fit().misfit(ref, got))))
        found += findings.no_effect(flag, ref_pair, got_pair)
        if flag == "-bounces" and (p := parts()) is not None:
            found.append(findings.reflection_acne(ref, got, p.images["mirror_depth"] > 0,
                                                  p.dull()))
        if flag == "-shadows":
            p = parts()
            found += [findings.shadow_missing(ref_pair, got_pair),
                      findings.shadow_acne(ref_pair, got_pair,
                                           p.unshadowed() if p is not None else None)]
    return [f for f in found if f is not None]


def geometry_findings(case: Case, verdict: KindVerdict,
                      images: RoleImages, renders: Renders
                      ) -> list[Finding]:
    """Where the differences lie (judge.geometry), by the reference's parts; not for jittered
    cases, whose differences are noise everywhere."""
    parts = None if case.jittered else renders.parts()
    if parts is None:
        return []
    kind = verdict.kind
    return geometry.geometry_findings(kind, parts, as_bytes(images[Role.REFERENCE][kind]),
                                      as_bytes(images[Role.CANDIDATE][kind]))


def part_findings(case: Case, verdict: KindVerdict, images: RoleImages,
                  renders: Renders) -> list[Finding]:
    """A color image explained by the reference's parts (one ray a pixel: not for -jitter or
    -filter cases): the shading-level fit of judge.shading."""
    if verdict.kind != "color" or case.jittered or case.request.filter:
        return []
    got = as_bytes(images[Role.CANDIDATE]["color"])
    parts = renders.parts()
    if parts is None or parts.color.shape != got.shape:
        return []
    return shading.shading_findings(parts, got)


def where_and_why(geometry: list[Finding], shading: list[Finding]) -> list[Finding]:
    """Geometry-level findings (where the images differ) before the shading-level ones, except
    those of a specific shading model (a highlight of another shininess is confined to its
    object too, and says more)."""
    specific = [f for f in shading if f.specific]
    return specific + geometry + [f for f in shading if not f.specific]


def one_ray(case: Case, kinds: list[KindVerdict], images: RoleImages, renders: Renders,
            tolerance: Tolerance) -> OneRay | None:
    """What localise.py reads past the flags (OneRay), with the reference's parts rendered:
    a case of one ray a pixel as it is, with its normals and depth judged too where it asks
    for its color alone (its request places the same primary rays; as it is where a render
    fails), so that a color difference can be told from a geometry one; a -jitter or -filter
    case rendered without them at three times the size (flag_off's render, asking for the
    normals and depth too), judged; None where that render fails."""
    every = tuple(dict.fromkeys((*case.request.kinds, *GEOMETRY_KINDS)))
    if case.jittered or case.request.filter:
        changes = flag_off(case, "-jitter")  # -filter's too
        if every != case.request.kinds:
            changes["kinds"] = every
        ref, got = renders.images(Role.REFERENCE, **changes), \
            renders.images(Role.CANDIDATE, **changes)
        if ref is None or got is None or any(k not in ref or k not in got or
                                             ref[k].shape[:2] != got[k].shape[:2]
                                             for k in every):
            return None
        off = " and ".join(f for f in flags_on(case) if f in ("-jitter", "-filter"))
        return OneRay([judge_deterministic(k, ref[k], got[k], tolerance) for k in every],
                      {Role.REFERENCE: ref, Role.CANDIDATE: got}, renders.parts(3), 3,
                      f"rendered without {off} at three times the size")
    if all(k in images[Role.CANDIDATE] for k in GEOMETRY_KINDS):
        return OneRay(kinds, images, renders.parts())
    ref = renders.images(Role.REFERENCE, kinds=every)
    got = renders.images(Role.CANDIDATE, kinds=every)
    if ref is None or got is None or any(k not in ref or k not in got or
                                         ref[k].shape[:2] != got[k].shape[:2]
                                         for k in GEOMETRY_KINDS):
        return OneRay(kinds, images, renders.parts())
    added = [k for k in GEOMETRY_KINDS if k not in images[Role.CANDIDATE]]
    return OneRay(kinds + [judge_deterministic(k, ref[k], got[k], tolerance) for k in added], {
        **images, Role.REFERENCE: {**images[Role.REFERENCE], **{k: ref[k] for k in added}},
        Role.CANDIDATE: {**images[Role.CANDIDATE], **{k: got[k] for k in added}}},
        renders.parts())


def flag_off_images(case: Case, kind: str, renders: Renders, flags: list[str]
                    ) -> dict[str, tuple[np.ndarray | None, np.ndarray | None]]:
    """Each flag -> the reference's and the candidate's image of `kind` with the case's flags
    but that one (localise's follows_flag reads them)."""
    return {flag: (renders.image(Role.REFERENCE, kind, **flag_off(case, flag)),
                   renders.image(Role.CANDIDATE, kind, **flag_off(case, flag)))
            for flag in flags}


def unexplained_findings(case: Case, verdict: KindVerdict, images: RoleImages,
                         renders: Renders, named: list[Finding], one: OneRay | None
                         ) -> list[Finding]:
    """The findings of a kind no mistake and no output-level change explains: the symptoms
    whose own model explains the image (a flag with no effect, missing shadows where nothing
    else differs: split_symptoms); else where to look (localise.py, reading `one`) where the
    cause search ran (`named`: its "unexplained"), then the symptoms as observations, where
    the images differ and the shading fit, as hints."""
    leads, hints = split_symptoms(feature_findings(case, verdict, images, renders), one)
    if leads:
        return leads + hints
    located = None
    if named:
        flags = ["-jitter"] if case.jittered else flags_on(case)
        off = flag_off_images(case, verdict.kind, renders, flags)
        got = as_bytes(images[Role.CANDIDATE][verdict.kind])
        on = {} if verdict.kind != "color" or case.jittered or case.request.filter else {
            flag: (renders.image(Role.REFERENCE, "color", **changes), got)
            for flag, changes in FLAG_ON.items()
            if not any(getattr(case.request, k) for k in changes)}
        located = localise(case, verdict, off, flags, one, on)
    return ([located] if located is not None else named) + hints + where_and_why(
        geometry_findings(case, verdict, images, renders),
        part_findings(case, verdict, images, renders))


def sampling_first(case: Case, verdict: KindVerdict, renders: Renders) -> list[Finding]:
    """Where a change of the whole image explains it (a constant offset, a brightness) and no
    mistake does, but the case rendered without -jitter or -filter at three times the size
    matches the reference's: localise's follows_flag, naming the flag's code in
    Renderer::Render, to lead before the change, whose guess at a cause (an ambient term
    counted twice) would be in code the flag-off render runs too."""
    sampling = ["-jitter"] if case.jittered else \
        [f for f in flags_on(case) if f in ("-jitter", "-filter")]
    scene = case_scene(case) if sampling else None
    if scene is None:
        return []
    off = flag_off_images(case, verdict.kind, renders, sampling)
    located = follows_flag(verdict.kind, sampling, off, scene,
                           case.request.width * case.request.height)
    return [] if located is None else [located.finding()]


# the symptoms of the flags that shade a primary hit (-shadows, -bounces) and never move it:
# the normals and depth images are the primary hits'
SHADING_SYMPTOMS = frozenset({"no_effect", "shadow_missing", "shadow_acne", "reflection_acne",
                              "reflection_depth"})


def split_symptoms(features: list[Finding], one: OneRay | None
                   ) -> tuple[list[Finding], list[Finding]]:
    """The symptoms that lead (those whose model explains the image) and the rest as hints.
    Where the one-ray images (`one`) show the primary hits' normals or depth differing, no
    symptom of shading explains the case, whatever share of the color image it accounts for: a
    wrong normal darkens pixels as a shadow ray that hits its own surface does."""
    moved = one is not None and any(k.kind in GEOMETRY_KINDS and k.verdict == Verdict.FAIL
                                    for k in one.kinds)
    leading = [f.explains and not (moved and f.code in SHADING_SYMPTOMS) for f in features]
    return ([f for f, lead in zip(features, leading) if lead],
            [f.hint() for f, lead in zip(features, leading) if not lead])


def blank(case: Case, images: RoleImages, renders: Renders, cause: Finding) -> list[Finding]:
    """The lead of a case whose images show nothing but the background (localise's
    shows_nothing) where the cause found is a camera that looks away: a traceRay that never
    finds the hit gives the same images (an intersect's cause that hides its objects alone
    says more: the program's passing cases leave it standing). Not for jittered cases."""
    got = images[Role.CANDIDATE].get("color")
    if case.jittered or case.request.filter or got is None or \
            not cause.message.startswith(f"{RENDER}:"):
        return []
    flat = as_bytes(got).reshape(-1, 3)
    parts = None if (flat != flat[0]).any() else renders.parts()  # one color: read the parts
    located = None if parts is None else shows_nothing(images, parts)
    return [] if located is None else [located.finding(
        "the mistakes that make every ray miss reproduce these images alike")]


def crash_located(case: Case, message: str, renders: Renders) -> Finding | None:
    """Where a program that gives no image of a case with flags (it crashed: `message`) is
    wrong: the first flag without which it runs and every image matches the reference's
    (localise.follows_flag); None where no flag does."""
    flags = flags_on(case)
    scene = case_scene(case)
    if not flags or scene is None:
        return None
    found = []
    for kind in case.request.kinds:
        # the candidate first: one that fails without the flag too needs no reference
        off = {}
        for flag in flags:
            got = renders.image(Role.CANDIDATE, kind, **flag_off(case, flag))
            off[flag] = (None if got is None else
                         renders.image(Role.REFERENCE, kind, **flag_off(case, flag)), got)
        located = follows_flag(kind, flags, off, scene,
                               case.request.width * case.request.height, message)
        if located is None:
            return None
        found.append(located)
    return found[0].finding(NO_IMAGE)


@dataclass(frozen=True)
class Searched:
    """A case's cause search: its findings per kind, and the explanations it found: the
    cause's mistakes first, then each other set the images cannot tell from it (() where
    nothing in the catalogue explains the images)."""

    findings: Callable[[str], list[Finding]]
    explanations: tuple[tuple[Switch, ...], ...]
    cause: CauseRecord | None = None


def cause_record(case: Case, switches: tuple[Switch, ...], how: str,
                 reproduces: bool) -> CauseRecord:
    """The cause in words: each mistake's function and what the program does (a quirk's
    plain reading as the quirk says it), and the command that renders the case with it."""
    command = shlex.join(["raycheck", "render", *case.request.to_argv(case.scene.path),
                          "--mistake", ",".join(str(s) for s in switches)])
    return CauseRecord(tuple(BY_SWITCH[s].describe() if s in BY_SWITCH
                             else f"{s.mistake.function}: your program {s.describe()}"
                             for s in switches), how, reproduces, command)


def search_causes(case: Case, kinds: list[KindVerdict],
                  images: RoleImages, settings: CaseSettings,
                  priors: tuple[tuple[Switch, ...], ...] = (),
                  refuting: Refuting = Refuting()) -> Searched | None:
    """The cause search of a case (causes.py; jitter_causes.py for a jittered case, whose
    images are one draw of a distribution), `priors` (the program's other causes) first,
    without the program's refuted causes, checking its cause against the program's passing
    cases (`refuting`, refute.py), or None where it cannot run (a scene the tracer cannot
    render)."""
    from raycheck.tracer.process import interrupt_in
    from raycheck.tracer.scene import SceneError

    try:
        if case.jittered:
            failed = {v.kind: tuple(Statistic(s.name, s.value, s.low, s.high, "")
                                    for s in v.jitter.statistics if not s.passed)
                      for v in kinds if v.verdict == Verdict.FAIL and v.jitter is not None}
            jittered = JitterSearch(case, images[Role.CANDIDATE], failed, settings.jitter_test,
                                    settings.tolerance, priors, refuting.codes)
            trial = jittered.run()
            if trial is None:
                return Searched(lambda kind: jitter_cause_findings(jittered, None, kind), ())
            return Searched(lambda kind: jitter_cause_findings(jittered, trial, kind),
                            (trial.switches, *(t.switches for t in jittered.alternatives(trial))),
                            cause_record(case, trial.switches, jitter_how(trial), True))
        search = CauseSearch(case, images[Role.CANDIDATE], settings.tolerance, refuting, priors)
        found = search.run()
        if found is None:
            per_kind = search.per_kind()
            if not per_kind:
                return Searched(lambda kind: cause_findings(search, None, kind), ())
            # no one cause of every kind: each kind's own, all of them the case's causes
            causes = tuple(sorted({s for a in per_kind.values() for s in a.switches}))
            return Searched(lambda kind: cause_findings(search, None, kind, per_kind),
                            (causes,), cause_record(case, causes,
                                                    kinds_how(search, per_kind), False))
        return Searched(lambda kind: cause_findings(search, found, kind),
                        (found.switches, *(a.switches for a in search.alternatives(found))),
                        cause_record(case, found.switches, cause_how(search, found),
                                     found.reproduces))
    except (SceneError, ValueError, OSError, RuntimeError, MemoryError) as e:  # Dr.Jit's too
        stop = interrupt_in(e)
        if stop is not None:
            raise stop from None
        return None


@dataclass
class Diagnosis:
    """What diagnose_case gives back besides the findings it appends: kind -> the top
    finding's evidence image (8-bit), and the explanations the cause search found
    (Searched's)."""

    evidence: dict[str, np.ndarray] = field(default_factory=dict)
    explanations: tuple[tuple[Switch, ...], ...] = ()
    cause: CauseRecord | None = None
    # case_views': the geometry kinds that differ and cross_case.py's views, where read
    geometry: tuple[str, ...] = ()
    views: tuple[ObjectView, ...] = ()


def diagnose_case(case: Case, kinds: list[KindVerdict],
                  images: RoleImages, renderers: dict[Role, Renderer],
                  render_role: RenderRole, settings: CaseSettings = CaseSettings(),
                  priors: tuple[tuple[Switch, ...], ...] = (),
                  refuting: Refuting = Refuting()) -> Diagnosis:
    """Appends the findings of every failing kind to its verdict, most specific first;
    returns the top findings' evidence images and the explanations found. priors: the
    explanations found in the program's other cases, tried first (causes.py,
    jitter_causes.py); refuting: what the program's passing cases rule out (refute.py).

    A kind one change of the whole output explains (a flip, a channel order) gets that (a
    brightness scale or offset after a mistake that reproduces it); else the cause search's
    mistake, where one reproduces the case's images; else the
    feature-level findings, or where there are none, "no known mistake reproduces this image"
    followed by where the images differ and the shading fit, as hints."""
    renders = Renders(case, renderers, render_role)
    diagnosis = Diagnosis()
    searched: list[Searched | None] = []

    def cause(kind: str) -> list[Finding]:
        if not settings.causes:
            return []
        if not searched:
            searched.append(search_causes(case, kinds, images, settings, priors, refuting))
            if searched[0] is not None:
                diagnosis.explanations = searched[0].explanations
                diagnosis.cause = searched[0].cause
        return [] if searched[0] is None else searched[0].findings(kind)

    read: list[OneRay | None] = []  # one_ray's, once

    def geometry() -> OneRay | None:
        if not read:
            read.append(one_ray(case, kinds, images, renders, settings.tolerance))
        return read[0]

    for verdict in kinds:
        if verdict.verdict != Verdict.FAIL:
            continue
        found = output_findings(case, verdict, images, renders)
        if not found or found[0].code in UNSPECIFIC_OUTPUT:
            named = cause(verdict.kind)
            if named and named[0].code != "cause:unexplained":
                found = blank(case, images, renders, named[0]) + named + found
            elif kernel := kernel_findings(case, verdict, images, renders):
                found = kernel + found
            elif not found:
                found = unexplained_findings(case, verdict, images, renders, named,
                                             geometry() if named else None)
            elif named:
                found = sampling_first(case, verdict, renders) + found
        verdict.findings += [f.record() for f in found]
        if found and found[0].evidence is not None:
            diagnosis.evidence[verdict.kind] = found[0].evidence.astype(np.uint8)
    diagnosis.geometry, diagnosis.views = case_views(
        read[0] if read else None if case.jittered or case.request.filter else
        OneRay(kinds, images, renders.rendered_parts()))
    return diagnosis


def case_views(one: OneRay | None) -> tuple[tuple[str, ...], tuple[ObjectView, ...]]:
    """The geometry kinds that differ and what the case shows of each intersect's work
    (cross_case.py), where its parts were rendered and it has normals and depth images of one
    ray a pixel; else nothing. Nothing too where a change of the whole image explains a
    failing geometry kind (a transposed image): it says nothing of which objects differ, and
    its objects would read as matching."""
    if one is None or one.parts is None or \
            any(k not in one.images[Role.CANDIDATE] for k in GEOMETRY_KINDS):
        return (), ()
    changed = geometry_changed(one.kinds, one.images, one.parts.images["object"].shape)
    failing = {k.kind for k in one.kinds if k.verdict == Verdict.FAIL}
    if changed is None or any(k in failing and k not in changed[0] for k in GEOMETRY_KINDS):
        return (), ()
    return tuple(changed[0]), object_views(one.parts, changed[1], one.scale)
