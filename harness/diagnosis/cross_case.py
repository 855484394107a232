"""Where to look, by contrast across a program's cases: a located finding that leaves an
intersect and the functions one case cannot tell from it (localise.py's geometry_place: a
difference confined to one kind of objects, with no other objects in view, or only planes, or
every one of them transformed), narrowed by the program's other cases, where what those other
functions draw shows and matches.

What clears a function follows from what the starter's functions compute, whatever the scene:
* Renderer::Render's primary rays: curved objects (spheres, triangles, meshes) whose normals
  and depth match, which a ray a little off changes (a plane's normal is one vector), in a
  case's own image (not a -jitter or -filter case's at three times the size: other rays);
* Transform::intersect: transformed objects of any kind that match (its code does not depend
  on what it holds);
* the intersect the difference is confined to: objects of the kind it differs on that match
  elsewhere (a mesh's smooth normals are not a lone triangle's flat one).
Where every function the finding leaves but one is cleared, that one is named; where all are,
or more than one is left, the finding stays as it was: the program's cases contradict each
other, or do not tell. Only a case whose normals differ is narrowed: a difference of the depth
alone may be the depth image's mapping, which differs by scene (-depth).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..cases import Case
from ..judge.parts import Parts, reference_parts
from ..records import CaseRecord, FindingRecord, ObjectView, Verdict
from .localise import (
    CONTRAST_CHANGED,
    CONTRAST_PIXELS,
    CONTRAST_SHARE,
    GEOMETRY_KINDS,
    INTERSECT,
    PLURAL,
    REACH,
    RENDER,
    TRANSFORM,
    grown,
    narrowed,
)
from .program import case_name

NARROWABLE = frozenset({RENDER, TRANSFORM})  # what may stand beside the intersect
# one case's: each finding to replace -> the findings that stand in its place
Swap = dict[FindingRecord, tuple[FindingRecord, ...]]
Swaps = dict[int, Swap]  # for each case, by index


def object_views(parts: Parts, changed: np.ndarray, scale: int = 1) -> tuple[ObjectView, ...]:
    """Each kind of object in view, transformed or not: its pixels and the share `changed` of
    them and those within REACH pixels of them; of parts rendered at `scale` times the case's
    size (a -jitter or -filter case's, localise.OneRay), its pixels in the case's."""
    obj = parts.images["object"]
    groups: dict[tuple[str, bool], list[int]] = {}
    for info in parts.objects:
        groups.setdefault((info.kind, info.transformed), []).append(info.index)
    views = []
    for (kind, moved), indices in sorted(groups.items()):
        shown = np.isin(obj, indices)
        if shown.any():
            # with their silhouettes: objects that grew over the background differ only there
            views.append(ObjectView(kind, moved, int(shown.sum()) // scale ** 2,
                                    float(changed[grown(shown, REACH * scale)].mean()), scale))
    return tuple(views)


def matches(view: ObjectView, size: tuple[int, int]) -> bool:
    """Enough of the objects in view to tell (localise.py's contrast), and they match."""
    return view.pixels >= max(CONTRAST_PIXELS, CONTRAST_SHARE * size[0] * size[1]) and \
        view.changed <= CONTRAST_CHANGED


def cleared(view: ObjectView, confined: set[str]) -> dict[str, str]:
    """The functions a matching view shows right, each with why, in words; confined: the
    object kinds the open case's difference lies on."""
    out = {}
    plural = PLURAL[view.kind]
    if view.kind in confined:
        out[INTERSECT[view.kind]] = f"its {plural} match"
    if view.transformed:
        out[TRANSFORM] = f"its transformed {plural} match"
    # at another size, other primary rays: a constant of the ray's formula (w - 1.1) shifts
    # them less at three times the size
    if view.kind != "plane" and view.scale == 1:
        out[RENDER] = f"its {plural} match, which primary rays a little off would change"
    return out


def open_finding(row: CaseRecord) -> FindingRecord | None:
    """The located finding of a case whose normals differ (of one ray a pixel: localise.OneRay)
    that leaves an intersect and what one case cannot tell from it; None where the case has
    none."""
    if "normals" not in row.geometry:
        return None
    for kind in row.kinds:
        top = kind.findings[0] if kind.verdict == Verdict.FAIL and kind.findings else None
        if top is not None and top.code == "located" and top.functions is not None and \
                len(top.functions) > 1 and top.functions[0] in INTERSECT.values() and \
                set(top.functions[1:]) <= NARROWABLE:
            return top
    return None


@dataclass(frozen=True)
class Witness:
    """A case that shows a function's work right."""

    case: str
    why: str


def narrow(row: CaseRecord, top: FindingRecord, rows: list[CaseRecord]) -> FindingRecord | None:
    """`top` (row's open finding) with the one function the program's cases leave; None where
    they leave none or several."""
    assert top.functions is not None  # open_finding's
    own = top.functions[0]
    confined = {v.kind for v in row.views
                if INTERSECT[v.kind] == own and v.changed > CONTRAST_CHANGED}
    if not confined:
        return None
    witnesses: dict[str, Witness] = {}
    for other in rows:
        for view in other.views:
            if matches(view, other.size):
                for function, why in cleared(view, confined).items():
                    witnesses.setdefault(function, Witness(case_name(other), why))
    left = [f for f in top.functions if f not in witnesses]
    if len(left) != 1:
        return None
    why = "; ".join(f"not {f}: in {witnesses[f].case} {witnesses[f].why}"
                    for f in top.functions if f in witnesses)
    return narrowed(top, left[0], f"across the program's cases, {why}")


SceneViews = dict[tuple[str, tuple[int, int]], tuple[ObjectView, ...]]  # (scene, size) ->


def program_views(cases: list[Case], rows: list[CaseRecord], by_scene: SceneViews
                  ) -> list[CaseRecord]:
    """rows, each unjittered case whose normals and depth match given its views (rendered here
    once per scene and size, kept in `by_scene` for the other programs of a run: a case that
    passes renders no parts of its own)."""
    out = []
    for case, row in zip(cases, rows):
        verdicts = {k.kind: k.verdict for k in row.kinds}
        if not row.views and not case.jittered and not case.request.filter and \
                all(verdicts.get(k) == Verdict.PASS for k in GEOMETRY_KINDS):
            key = (row.scene, row.size)
            if key not in by_scene:
                parts = reference_parts(case)
                by_scene[key] = () if parts is None else object_views(
                    parts, np.zeros(parts.images["object"].shape, bool))
            row = replace(row, views=by_scene[key])
        out.append(row)
    return out


def narrowings(cases: list[Case], rows: list[CaseRecord], by_scene: SceneViews) -> Swaps:
    """For each case (by index) of one program whose located finding its other cases narrow
    to one function: that finding -> the narrowed one. Renders only where some case is open
    (program_views)."""
    if not any(open_finding(r) is not None for r in rows):
        return {}
    seen = program_views(cases, rows, by_scene)
    out: Swaps = {}
    for i, row in enumerate(seen):
        top = open_finding(row)
        found = None if top is None else narrow(row, top, seen)
        if top is not None and found is not None:
            out[i] = {top: (found,)}
    return out


def narrowed_record(row: CaseRecord, swaps: Swap) -> CaseRecord:
    """row with its kinds' findings swapped."""
    return replace(row, kinds=tuple(replace(k, findings=tuple(
        g for f in k.findings for g in swaps.get(f, (f,)))) for k in row.kinds))
