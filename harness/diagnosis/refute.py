"""Refutation of a cause by the cases a program passes.

A cause search sees one case. A mistake that reproduces a failing case's images is the
program's mistake only if it leaves the program's other images as they are: a program with
it would fail every case where it changes the reference. So a cause found in a failing case
is tried on a few of the program's passing cases it can change (mistakes.applicable), and
where the reference with it differs from the reference on pixels where the program's image
agrees with the reference (more than REFUTING_SHARE of them), the program does not make that
mistake: the cause is refuted there, and its failing cases are searched again without it.
Comparing the change against the candidate's agreement, not the reference with the mistake
against the candidate, keeps a case that passes with a difference of its own (a quirk the
check forgives, a second mistake within the tolerance) from refuting a true cause.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from raycheck.tracer.mistakes import Switch, parse_switch

from ..cases import Case
from ..judge.findings import as_bytes
from ..judge.verdict import Tolerance

# a cause is refuted where it changes more than this many times the tolerance's share of a
# passing image's pixels (and at least REFUTING_PIXELS of them) where the program's image
# agrees with the reference
REFUTING_SHARE = 2.0
REFUTING_PIXELS = 8


@dataclass(frozen=True)
class Refutation:
    """A cause the program's passing case `case` rules out: with `switch` on, the reference
    changes `share` of that case's `kind` image where the program's image agrees with it.
    `explained`: the failing cases whose cause it was."""

    switch: str  # Switch.exact
    case: str  # scene/feature
    kind: str
    share: float
    explained: tuple[str, ...] = ()

    @property
    def code(self) -> str:
        return self.switch.partition("=")[0]

    def describe(self) -> str:
        return (f"{parse_switch(self.switch)} would change {self.share:.0%} of your "
                f"program's {self.kind} image of {self.case}, which passes")


@dataclass(frozen=True)
class Trial:
    """The causes to try on one passing case: its request, the program's images of it (kind
    -> 8-bit image), and the switches, each alone."""

    case: Case
    candidate: dict[str, np.ndarray]
    switches: tuple[Switch, ...]
    tolerance: Tolerance


def refutations(trial: Trial) -> tuple[Refutation, ...]:
    """The switches of the trial that its case refutes (one render of the reference, one
    with each switch; one kernel, every switch compiled in)."""
    from raycheck.tracer.options import RenderOptions
    from raycheck.tracer.render import render
    from raycheck.tracer.scene import load_scene
    from raycheck.tracer.scene.request import request_fields

    request = replace(trial.case.request, kinds=tuple(k for k in trial.case.request.kinds
                                                       if k in trial.candidate))
    scene = load_scene(trial.case.scene.path)
    compiled = tuple(dict.fromkeys(s.code for s in trial.switches))

    def images(switches: tuple[Switch, ...]) -> dict[str, np.ndarray]:
        result = render(scene, RenderOptions(**request_fields(request), mistakes=switches,
                                             mistake_kernel=compiled))
        return {k: as_bytes(getattr(result, k)) for k in request.kinds}

    levels = trial.tolerance.levels
    reference = images(())
    agree = {k: _within(reference[k], as_bytes(trial.candidate[k]), levels)
             for k in request.kinds}
    out = []
    for switch in trial.switches:
        mistaken = images((switch,))
        for kind in request.kinds:
            changed = ~_within(mistaken[kind], reference[kind], levels) & agree[kind]
            count = int(changed.sum())
            share = count / max(changed.size, 1)
            if count >= REFUTING_PIXELS and share > REFUTING_SHARE * trial.tolerance.share:
                out.append(Refutation(switch.exact, trial.case.id, kind, share))
                break
    return tuple(out)


def _within(a: np.ndarray, b: np.ndarray, levels: int) -> np.ndarray:
    return np.abs(a - b).max(axis=2) <= levels
