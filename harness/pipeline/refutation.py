"""A program's causes tried on the cases it passes (diagnosis/refute.py), between the run of
its unjittered cases and the run of its jittered ones: which causes to try where, and which
failing cases to search again without the ones refuted. `check`, `grade`, the pytest plugin
and the mutation benchmark all go through Refuter, so that what a case names is the same
function of the program's results wherever it runs."""
from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from raycheck.tracer.mistakes import MistakeError, Switch, parse_switch, present

from ..cases import Case
from ..diagnosis.refute import (
    REFUTING_CASES,
    Refutation,
    Refuting,
    Trial,
    Witness,
    refutations,
)
from ..judge.verdict import Tolerance
from ..records import CaseRecord, Role, Verdict
from ..storage.results import CaseOutput
from .executor import use_threads

# the passing cases a failing case searched again checks its causes against (refute.py)
WITNESSES = 6
# rounds of refutation and search again (a second round tries the new searches' causes)
ROUNDS = 2


@dataclass(frozen=True)
class Ran:
    """An unjittered case of a program, run: its record, and for a passing case the
    program's images of it (kind -> image), which the causes found elsewhere must leave as
    they are."""

    program: tuple[str, str]
    case: Case
    row: CaseRecord
    candidate: dict[str, np.ndarray] | None
    tolerance: Tolerance


def candidate_images(output: CaseOutput) -> dict[str, np.ndarray] | None:
    """The program's images of a passing case, from its picture files; None for another."""
    from PIL import Image

    if not output.row.passed:
        return None
    images = {}
    for kind, names in output.row.files.items():
        name = names.get(Role.CANDIDATE)
        if name is None or name not in output.files:
            return None
        images[kind] = np.asarray(Image.open(io.BytesIO(output.files[name])).convert("RGB"))
    return images


def run_trial(trial: Trial, threads: int | None) -> tuple[Refutation, ...]:
    """What a worker runs: the trial's refutations."""
    use_threads(threads)
    return refutations(trial)


@dataclass
class Refuter:
    """The refutations found so far, per program, and the causes already tried."""

    refuted: dict[tuple[str, str], dict[str, Refutation]] = field(default_factory=dict)
    tried: set[tuple[tuple[str, str], str]] = field(default_factory=set)

    def trials(self, ran: list[Ran]) -> list[tuple[tuple[str, str], Trial]]:
        """Each program's causes not tried yet (those of its failing cases), each on up to
        REFUTING_CASES of its passing cases that the cause's mistake can change: one trial a
        passing case, with its program."""
        from raycheck.tracer.scene import Scene, load_scene

        scenes: dict[Path, Scene] = {}
        wanted: dict[int, list[Switch]] = {}
        for program in dict.fromkeys(r.program for r in ran):
            mine = [(i, r) for i, r in enumerate(ran) if r.program == program]
            # one a scene first: a mistake that shows anywhere shows on some scene
            passing = _one_a_scene_first([(i, r) for i, r in mine if r.candidate is not None])
            for spelled in _causes(r.row for _, r in mine):
                if (program, spelled) in self.tried:
                    continue
                self.tried.add((program, spelled))
                try:
                    switch = parse_switch(spelled)
                except MistakeError:  # a results file of another catalogue
                    continue
                chosen = 0
                for i, r in passing:
                    if chosen == REFUTING_CASES:
                        break
                    path = r.case.scene.path
                    if path not in scenes:
                        scenes[path] = load_scene(path)
                    if switch.mistake.needs <= present(scenes[path], r.case.request):
                        wanted.setdefault(i, []).append(switch)
                        chosen += 1
        return [(ran[i].program, Trial(Witness(ran[i].case, ran[i].candidate or {}),
                                       tuple(switches), ran[i].tolerance))
                for i, switches in sorted(wanted.items())]

    def take(self, ran: list[Ran], trials: list[tuple[tuple[str, str], Trial]],
             outcomes: list[tuple[Refutation, ...]]) -> None:
        """Records the trials' refutations (the first, in the matrix's order, of each cause),
        with the failing cases each was the cause of."""
        for (program, _), found in zip(trials, outcomes):
            for refutation in found:
                explained = tuple(r.case.id for r in ran if r.program == program
                                  and refutation.switch in r.row.causes)
                self.refuted.setdefault(program, {}).setdefault(
                    refutation.code, Refutation(refutation.switch, refutation.case,
                                                refutation.kind, refutation.share, explained))

    def again(self, ran: list[Ran]) -> dict[int, Refuting]:
        """The failing cases to search again (index into ran): those whose cause has a
        refuted mistake, with their program's refutations, which the search leaves out, and
        up to WITNESSES of its passing cases (one a scene first), which each cause the
        search settles on must leave as they are."""
        out = {}
        for i, r in enumerate(ran):
            codes = {s.partition("=")[0] for s in r.row.causes}
            if codes & set(self.refuted.get(r.program, {})):
                passing = _one_a_scene_first([(j, q) for j, q in enumerate(ran)
                                              if q.program == r.program
                                              and q.candidate is not None])
                out[i] = Refuting(self.of(r.program).refuted, tuple(
                    Witness(q.case, q.candidate or {}) for _, q in passing[:WITNESSES]))
        return out

    def of(self, program: tuple[str, str]) -> Refuting:
        """A program's refutations, in a fixed order (a case's result depends on them)."""
        return Refuting(tuple(sorted(self.refuted.get(program, {}).values(),
                                     key=lambda r: r.code)))


def _causes(rows) -> list[str]:
    """The causes of the failing cases, each once, in the matrix's order."""
    return list(dict.fromkeys(s for row in rows if row.verdict == Verdict.FAIL
                              for s in row.causes))


def _one_a_scene_first(cases: list[tuple[int, Ran]]) -> list[tuple[int, Ran]]:
    """The cases in the matrix's order, but each scene's first case before any second."""
    seen: dict[Path, int] = {}
    ranked = []
    for order, (i, r) in enumerate(cases):
        n = seen.get(r.case.scene.path, 0)
        seen[r.case.scene.path] = n + 1
        ranked.append(((n, order), (i, r)))
    return [c for _, c in sorted(ranked, key=lambda x: x[0])]
