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

import hashlib
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
# the passing cases each cause is tried on (those it can change; one a scene first)
REFUTING_CASES = 3


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


@dataclass(frozen=True, eq=False)  # images: compared by identity
class Witness:
    """A case the program passes, and its images of it (kind -> image): what a cause of the
    program must leave as it is."""

    case: Case
    candidate: dict[str, np.ndarray]


class WitnessRenders:
    """A witness's reference, rendered once, and its renders with one switch on (one kernel:
    `compiled`'s mistakes compiled in), each switch's verdict made once."""

    def __init__(self, witness: Witness, compiled: tuple[str, ...],
                 tolerance: Tolerance) -> None:
        from raycheck.tracer.mistakes import present
        from raycheck.tracer.scene import load_scene

        self.witness, self.compiled, self.tolerance = witness, compiled, tolerance
        self.scene = load_scene(witness.case.scene.path)
        self.request = replace(witness.case.request, kinds=tuple(
            k for k in witness.case.request.kinds if k in witness.candidate))
        self.present = present(self.scene, self.request)
        self.reference = self._images(())
        self.agree = {k: _within(self.reference[k], as_bytes(witness.candidate[k]),
                                 tolerance.levels) for k in self.request.kinds}
        self.verdicts: dict[Switch, Refutation | None] = {}

    def shows(self, switch: Switch) -> bool:
        """Whether the switch's mistake can change this witness's images at all."""
        return switch.mistake.needs <= self.present

    def refutation(self, switch: Switch) -> Refutation | None:
        """The refutation of `switch` by this witness, or None."""
        if switch not in self.verdicts:
            self.verdicts[switch] = self._refutation(switch) if self.shows(switch) else None
        return self.verdicts[switch]

    def _refutation(self, switch: Switch) -> Refutation | None:
        mistaken = self._images((switch,))
        for kind in self.request.kinds:
            changed = ~_within(mistaken[kind], self.reference[kind], self.tolerance.levels) \
                & self.agree[kind]
            count = int(changed.sum())
            share = count / max(changed.size, 1)
            if count >= REFUTING_PIXELS and share > REFUTING_SHARE * self.tolerance.share:
                return Refutation(switch.exact, self.witness.case.id, kind, share)
        return None

    def _images(self, switches: tuple[Switch, ...]) -> dict[str, np.ndarray]:
        from raycheck.tracer.options import RenderOptions
        from raycheck.tracer.render import render
        from raycheck.tracer.scene.request import request_fields

        result = render(self.scene, RenderOptions(**request_fields(self.request),
                                                  mistakes=switches,
                                                  mistake_kernel=self.compiled))
        return {k: as_bytes(getattr(result, k)) for k in self.request.kinds}


@dataclass(frozen=True)
class Refuting:
    """What a case's search knows from the program's other cases: the causes they refute,
    left out, and the passing cases (witnesses) that each cause it settles on must leave as
    they are (causes.py)."""

    refuted: tuple[Refutation, ...] = ()
    witnesses: tuple[Witness, ...] = ()

    @property
    def codes(self) -> frozenset[str]:
        return frozenset(r.code for r in self.refuted)

    def key(self) -> list:
        """What a result cache's key holds of it: every refutation, each witness's case and
        a digest of its images."""
        return [[[r.switch, r.case, r.kind, r.share, list(r.explained)] for r in self.refuted],
                [[w.case.id, {k: hashlib.sha256(np.ascontiguousarray(v).tobytes()).hexdigest()
                              for k, v in sorted(w.candidate.items())}]
                 for w in self.witnesses]]


@dataclass(frozen=True)
class Trial:
    """The causes to try on one witness, each alone."""

    witness: Witness
    switches: tuple[Switch, ...]
    tolerance: Tolerance


def refutations(trial: Trial) -> tuple[Refutation, ...]:
    """The switches of the trial that its witness refutes (one render of the reference, one
    with each switch; one kernel, every switch compiled in)."""
    renders = WitnessRenders(trial.witness, tuple(dict.fromkeys(s.code for s in trial.switches)),
                             trial.tolerance)
    return tuple(r for s in trial.switches if (r := renders.refutation(s)) is not None)


def _within(a: np.ndarray, b: np.ndarray, levels: int) -> np.ndarray:
    return np.abs(a - b).max(axis=2) <= levels
