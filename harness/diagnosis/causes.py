"""The cause search: explain a failing case by the mistake that reproduces it.

raycheck owns an exact reference (the tracer's course mode), so it can render the reference
*with a known mistake switched on* (tracer/mistakes.py) and see whether that reproduces the
candidate's images. A render that matches the candidate within the check's tolerance, every
kind of the case at once, proves the cause; one that matches at least EXPLAINED_MIN of the
pixels where the candidate differs from the reference, and differs from the candidate nowhere
else (at most the tolerance's share of pixels), names it with that share.

The search, for one case, its priors and nothing else (what it names is a function of them
and the candidate's images, whatever ran before in the process): first the causes the
program's other cases found (priors: a program's mistakes are the same in every case), the
first that reproduces the images taken; then every catalogue mistake the scene
and request can show, at each value of its parameter's sweep, the best parameter refined
between its neighbours; then, where no single mistake explains the images, the best few
combined with each other one, and the best pair with a third (real programs have two or
three mistakes). Where the catalogue reproduces nothing, the same again with the mistakes
operators generate at the sites of the course's formulas (tracer/operators.py) whose kinds are
the failing ones, combined with the catalogue's too, with a budget of its own. Renders are the
tracer's, in this process, of the case's request: warm, a few milliseconds to a few tenths of a
second each, and the kernels of one mistake's sweep are compiled once (its parameter is a
kernel input).
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from raycheck.tracer.mistakes import Mistake, MistakeError, Switch, applicable, check_switch
from raycheck.tracer.operators import GENERATED, K, Operator, Site, op_code
from raycheck.tracer.pixel_index import OUTPUT_FORMS, TAP_FORMS, filter_taps, read_output
from raycheck.tracer.quirks import BY_SWITCH
from raycheck.tracer.scene.request import RenderRequest

from ..cases import Case
from ..judge.filter_fit import WrittenKernel, fit_kernel, written
from ..judge.findings import Finding, as_bytes
from ..judge.verdict import Tolerance, tolerated
from .localise import either
from .refute import REFUTING_CASES, Refuting, WitnessRenders

# a mistake that matches this share of the differing pixels, and adds no new difference, names
# the cause even where a few pixels stay different (a second, smaller mistake; silhouettes)
EXPLAINED_MIN = 0.95
# a cause that leaves more of the differing pixels unexplained is tried with a second mistake
ALL_EXPLAINED = 0.995
# where the candidate matches the reference on fewer pixels than this, a single mistake that
# reproduces it is not the only explanation tried: pairs are too, and named beside it
AMBIGUOUS_MATCH = 0.5
MAX_ALTERNATIVES = 3
# the attempts one case's search may make (renders of the reference with mistakes) in the
# catalogue, and then with the generated mistakes
MAX_ATTEMPTS = 160
MAX_OPERATOR_ATTEMPTS = 240
# the best single mistakes whose parameters are refined; that go on to be combined with the
# others; and the others each is combined with
REFINED = 3
PAIR_SEEDS = 3
WIDE_SEEDS = 2
PARTNERS = 8
# the -filter's constants: K[j][i] (j counting sub-rows from the bottom) at 3 j + i, then the
# divisor
FILTER_CODES = tuple(op_code(site, Operator.CONSTANT) for site in (
    *(Site[f"FILTER_WEIGHT_{j}{i}"] for j in range(3) for i in range(3)), Site.FILTER_DIVISOR))
# the index mistakes, each form's image predicted from the reference's buffer (_indexed)
# rather than rendered; of their forms, those that come closest are rendered
OUTPUT_INDEX = op_code(Site.OUTPUT_INDEX, Operator.INDEX)
FILTER_TAP_INDEX = op_code(Site.FILTER_TAP_INDEX, Operator.INDEX)
INDEXED = 2
# the program's causes found in its other cases that a search tries first (_prior)
PRIORS = 8
# refinement of the best single mistakes' parameters: rounds, values a round
REFINE_ROUNDS = 2
REFINE = 9


@dataclass(frozen=True)
class Attempt:
    """One render of the reference with `switches` on, scored against the candidate."""

    switches: tuple[Switch, ...]
    explained: float  # of the pixels where the candidate differs from the reference, matched
    new: float  # of the pixels where they agree, those this render gets wrong
    matching: float  # of all pixels, those within tolerance of the candidate
    error: float  # mean level difference from the candidate over the differing pixels
    reproduces: bool  # every kind passes the check's tolerance against the candidate
    images: dict[str, np.ndarray] = field(compare=False, repr=False)
    passing: frozenset[str] = frozenset()  # the kinds that pass against the candidate

    def accepted(self, tolerance: Tolerance) -> bool:
        return self.reproduces or (self.explained >= EXPLAINED_MIN
                                   and self.new <= tolerance.share)

    @property
    def score(self) -> float:
        return self.explained - 4.0 * self.new + (1.0 if self.reproduces else 0.0)

    @property
    def rank(self) -> tuple[float, float]:
        """What makes an attempt better: its score, then a smaller error (which guides a
        parameter toward the candidate's where no value matches a pixel yet)."""
        return self.score, -self.error


class CauseSearch:
    """The search for one case: the candidate's images (kind -> image) against renders of the
    case's request with mistakes."""

    def __init__(self, case: Case, candidate: dict[str, np.ndarray],
                 tolerance: Tolerance, refuting: Refuting = Refuting(),
                 priors: tuple[tuple[Switch, ...], ...] = ()) -> None:
        """priors: the causes found in the program's other cases, tried first (_prior)."""
        from raycheck.tracer.scene import load_scene

        self.case, self.tolerance = case, tolerance
        self.scene = load_scene(case.scene.path)
        self.request = replace(case.request, kinds=tuple(k for k in case.request.kinds
                                                         if k in candidate))
        self.candidate = {k: as_bytes(candidate[k]) for k in self.request.kinds}
        self.attempts: dict[tuple[Switch, ...], Attempt] = {}
        # the program's refuted causes (refute.py) are left out; those its passing cases (the
        # witnesses) refute during the search join them (refutes)
        self.refuting = refuting
        self.priors = priors
        self.refuted = list(refuting.refuted)
        self.mistakes = tuple(m for m in applicable(self.scene, self.request)
                              if m.code not in refuting.codes)
        self.operators = tuple(m for m in applicable(self.scene, self.request, GENERATED)
                               if m.code not in refuting.codes)
        self.witness_renders: dict[tuple[int, tuple[str, ...]], WitnessRenders] = {}
        # every attempt of the search runs one kernel: all its mistakes compiled in (the
        # catalogue's; with the operators' where it goes on to them or a prior has one: _widen)
        self.compiled = tuple(m.code for m in self.mistakes)
        self.budget = MAX_ATTEMPTS
        self.reference = reference = self._render(())
        self.differs = {k: _beyond(reference[k], self.candidate[k], tolerance)
                        for k in self.request.kinds}
        self.differing = sum(int(d.sum()) for d in self.differs.values())
        self.pixels = sum(d.size for d in self.differs.values())
        self.before = 1.0 - self.differing / max(self.pixels, 1)

    def _render(self, switches: tuple[Switch, ...],
                request: RenderRequest | None = None) -> dict[str, np.ndarray]:
        from raycheck.tracer.options import RenderOptions
        from raycheck.tracer.render import render
        from raycheck.tracer.scene.request import request_fields

        request = self.request if request is None else request
        result = render(self.scene, RenderOptions(**request_fields(request),
                                                  mistakes=switches,
                                                  mistake_kernel=self.compiled))
        return {k: as_bytes(getattr(result, k)) for k in request.kinds}

    def attempt(self, switches: tuple[Switch, ...]) -> Attempt | None:
        """The attempt with these switches (made once; None past the budget)."""
        switches = tuple(sorted(switches))
        if switches in self.attempts:
            return self.attempts[switches]
        if len(self.attempts) >= self.budget:
            return None
        images = self._render(switches)
        explained = new = matching = 0
        error = 0.0
        passing = set()
        for kind, got in self.candidate.items():
            wrong = _beyond(images[kind], got, self.tolerance)
            error += float(np.abs(images[kind] - got).max(axis=2)[self.differs[kind]].sum())
            explained += int((self.differs[kind] & ~wrong).sum())
            new += int((~self.differs[kind] & wrong).sum())
            matching += int((~wrong).sum())
            if tolerated(images[kind].astype(np.uint8), got.astype(np.uint8), self.tolerance):
                passing.add(kind)
        agree = self.pixels - self.differing
        found = Attempt(switches, explained / max(self.differing, 1), new / max(agree, 1),
                        matching / max(self.pixels, 1), error / max(self.differing, 1),
                        passing == set(self.candidate), images, frozenset(passing))
        self.attempts[switches] = found
        return found

    # --- the search
    def run(self) -> Attempt | None:
        """The best accepted attempt, or None where nothing in the catalogue explains the
        images."""
        if not self.differing:
            return None
        prior = self._prior()
        if prior is not None:
            return prior
        singles = self._singles()
        best = self._best(singles)
        if best is None or not best.reproduces:
            best = _better(best, self._kernel())
        if (best is None or not best.reproduces) and self.operators:
            self._widen()
            singles = sorted(singles + self._singles(among=self.operators),
                             key=lambda a: a.rank, reverse=True)
            best = _better(best, self._best(singles))
        if best is None or not best.reproduces:
            # whole pixels moved, last: less specific than a formula's site (where every ray
            # misses, the background image is its own left column read everywhere)
            best = _better(best, self._indexed())
        best = self._unrefuted(best)
        if best is None or not best.accepted(self.tolerance):
            return None
        if best.reproduces and self.before < AMBIGUOUS_MATCH:
            self._combined(singles)  # other explanations (alternatives) of an image so changed
        return best

    def _prior(self) -> Attempt | None:
        """The first of the program's other causes (priors; then all of them at once) that
        reproduces these images where no witness refutes it: a program's mistakes are the
        same in every case, so that one found once need not be searched for again; those
        after it that reproduce them too are its alternatives. None where none does (the
        search goes on as if there were none: the attempts are kept)."""
        known = {m.code: m for m in self.mistakes + self.operators}
        usable = [p for p in self.priors if p and all(s.code in known for s in p)][:PRIORS]
        together = tuple(sorted({s for p in usable for s in p}))
        if len(usable) > 1 and len({s.code for s in together}) == len(together):
            usable.append(together)
        if any(known[s.code].generated for p in usable for s in p):
            self._widen()
        # each tried, so that those that reproduce the images too are its alternatives
        tried = [self.attempt(prior) for prior in usable]
        return next((found for found in tried if found is not None and found.reproduces
                     and not self.refutes(found)), None)

    def _kernel(self) -> Attempt | None:
        """Where the case has -filter (not -jitter), the attempt with the candidate's own
        kernel: its weights fitted on the reference rendered without -filter at three times
        the size (filter_fit), written as whole numbers over a divisor, each weight and the
        divisor that differ from the course's switched on at their sites. A program that
        filters with a kernel of its own (a box, a tap left out, a loop bound one short)
        gives such images whatever the kernel. None where no kind's fit is a written kernel
        other than the course's."""
        if not self.request.filter or self.request.jitter or not self.operators:
            return None
        for kind in self.request.kinds:
            fit = fit_kernel(self.big[kind], self.candidate[kind]) \
                if self.differs[kind].any() else None
            kernel = None if fit is None else written(fit.weights)
            switches = () if kernel is None else kernel_switches(kernel)
            if switches:
                return self._widened_attempt(switches)
        return None

    @cached_property
    def big(self) -> dict[str, np.ndarray]:
        """The reference rendered without -filter at three times the size: the buffer the
        -filter image is made from."""
        request = self.request
        return self._render((), replace(request, filter=False, width=3 * request.width,
                                        height=3 * request.height))

    def _indexed(self) -> Attempt | None:
        """Where the case is not jittered, the attempt with the form of the pixels' index
        (pixel_index.py: an unfiltered pixel's, a -filter tap's) whose image, predicted from
        the reference's buffer, comes closest to the candidate's, of the INDEXED closest
        rendered. A program that reads its buffer at another index (y / w + x: row 0 for
        every row) moves whole pixels, which no formula's constant does. None where no
        form's prediction explains EXPLAINED_MIN of the differing pixels, and for images of
        one color, which say nothing of where their pixels were read."""
        code = FILTER_TAP_INDEX if self.request.filter else OUTPUT_INDEX
        mistake = next((m for m in self.operators if m.code == code), None)
        # an image of one color (every ray missed) is any of its pixels read everywhere
        uniform = all((got == got[:1, :1]).all() for got in self.candidate.values())
        if self.request.jitter or mistake is None or uniform:
            return None
        scored = []
        buffers = {kind: self.big[kind].astype(np.float64) if self.request.filter
                   else self.reference[kind] for kind in self.candidate}
        for k in range(1, len(TAP_FORMS if self.request.filter else OUTPUT_FORMS)):
            explained = 0
            for kind, got in self.candidate.items():
                if self.request.filter:
                    predicted = filter_taps(buffers[kind], TAP_FORMS[k], K, 16.0)
                    predicted = None if predicted is None else np.round(predicted)
                else:
                    predicted = read_output(buffers[kind], OUTPUT_FORMS[k])
                if predicted is None:
                    break
                explained += int((self.differs[kind]
                                  & ~_beyond(predicted, got, self.tolerance)).sum())
            else:
                scored.append((explained / max(self.differing, 1), k))
        self.budget = max(self.budget, len(self.attempts) + INDEXED)  # their own renders
        tried = [a for share, k in sorted(scored, reverse=True)[:INDEXED]
                 if share >= EXPLAINED_MIN
                 and (a := self._widened_attempt((Switch(code, float(k)),)))]
        return max(tried, key=lambda a: a.rank, default=None)

    def _widened_attempt(self, switches: tuple[Switch, ...]) -> Attempt | None:
        self._widen()
        return self.attempt(switches)

    def _best(self, singles: list[Attempt]) -> Attempt | None:
        """The best single, or where it leaves some of the images unexplained, the best
        combination where that is better."""
        best = max(singles, key=lambda a: a.rank, default=None)
        # a second mistake may explain the rest, or undo what the first changes wrongly
        if best is None or not best.reproduces or best.explained < ALL_EXPLAINED:
            combined = self._combined(singles)
            if combined is not None and (best is None or combined.rank > best.rank):
                best = combined
        return best

    def _unrefuted(self, best: Attempt | None) -> Attempt | None:
        """`best`, or where a witness refutes one of its mistakes, the best attempt made
        without the mistakes refuted (which stay out from then on)."""
        while best is not None and best.accepted(self.tolerance) and self.refutes(best):
            best = max((a for a in self.attempts.values() if self.allowed(a)),
                       key=lambda a: a.rank, default=None)
        return best

    def allowed(self, attempt: Attempt) -> bool:
        """Whether none of the attempt's mistakes is refuted."""
        refuted = {r.code for r in self.refuted}
        return not any(s.code in refuted for s in attempt.switches)

    def refutes(self, attempt: Attempt) -> bool:
        """Whether a witness (a case the program passes) refutes one of the attempt's
        mistakes; each one it refutes is recorded. Each switch is tried on the first
        REFUTING_CASES witnesses whose images it can change."""
        refuted = False
        for switch in attempt.switches:
            tried = 0
            for i, witness in enumerate(self.refuting.witnesses):
                if tried == REFUTING_CASES:
                    break
                key = (i, self.compiled)
                if key not in self.witness_renders:
                    self.witness_renders[key] = WitnessRenders(witness, self.compiled,
                                                               self.tolerance)
                renders = self.witness_renders[key]
                if not renders.shows(switch):
                    continue
                tried += 1
                found = renders.refutation(switch)
                if found is not None:
                    self.refuted.append(replace(found, explained=(self.case.id,)))
                    refuted = True
                    break
        return refuted or not self.allowed(attempt)

    @property
    def widened(self) -> bool:
        """Whether the search has gone on to the generated mistakes (_widen)."""
        return self.budget > MAX_ATTEMPTS

    def _widen(self) -> None:
        """Compiles the generated mistakes in beside the catalogue's and gives the search
        their budget (once)."""
        if self.operators and not self.widened:
            self.compiled += tuple(m.code for m in self.operators)
            self.budget += MAX_OPERATOR_ATTEMPTS

    def alternatives(self, found: Attempt) -> list[Attempt]:
        """Other mistakes (up to MAX_ALTERNATIVES, fewest first; not the cause's with more) that
        reproduce the images too, or where the cause
        only explains them, whose renders equal its: these images cannot tell them apart (two
        ways to add the ambient term where no light is shadowed)."""
        codes = {s.code for s in found.switches}

        def same(a: Attempt) -> bool:
            if found.reproduces:
                return a.reproduces
            return all(np.array_equal(a.images[k], found.images[k]) for k in a.images)

        others = [a for a in self.attempts.values()
                  if not codes <= {s.code for s in a.switches} and same(a)
                  and self.allowed(a)]
        others = sorted(others, key=lambda a: len(a.switches))
        return [a for a in others[:2 * MAX_ALTERNATIVES] if not self.refutes(a)][
            :MAX_ALTERNATIVES]

    def per_kind(self) -> dict[str, Attempt]:
        """Where no cause explains the case, the failing kinds one attempt reproduces on its
        own, another failing kind differing for a second reason: kind -> the attempt (fewest
        mistakes first, then the one that reproduces most kinds) that reproduces it and leaves
        every kind that passes passing. Of the attempts made, after each mistake that can
        change one of the failing kinds is tried alone."""
        failing = {k for k, d in self.differs.items() if d.any()}
        if len(failing) < 2:
            return {}
        # the mistakes that change some of the failing kinds
        self._singles(some=True, among=self.mistakes + (
            self.operators if self.widened else ()))
        passing = set(self.candidate) - failing
        fits = sorted((a for a in self.attempts.values()
                       if passing <= a.passing and failing & a.passing),
                      key=lambda a: (len(a.switches), -len(failing & a.passing), -a.score,
                                     a.switches))
        out: dict[str, Attempt] = {}
        for attempt in fits:
            if not set(failing & attempt.passing) - set(out) or self.refutes(attempt):
                continue
            for kind in sorted(failing & attempt.passing):
                out.setdefault(kind, attempt)
        return out

    def closest(self) -> Attempt | None:
        """The attempt that explained most, accepted or not."""
        return max(self.attempts.values(), key=lambda a: a.rank, default=None)

    def _singles(self, some: bool = False,
                 among: tuple[Mistake, ...] | None = None) -> list[Attempt]:
        """Per mistake (of the catalogue's, or `among`) that could explain the failing kinds
        alone (some: at least one of them), its best attempt (its parameter swept; the best
        REFINED parameters refined; a choice, not refined)."""
        failing = {k for k, d in self.differs.items() if d.any()}
        out = []
        for mistake in self.mistakes if among is None else among:
            if not (failing & mistake.kinds if some else failing <= mistake.kinds) \
                    or mistake.code in (OUTPUT_INDEX, FILTER_TAP_INDEX):
                continue
            # a generated mistake changes each of its kinds wherever it changes one: where
            # one of them passes, it is not the cause (localisation by kind)
            if mistake.generated and not some and mistake.kinds & set(self.candidate) \
                    != failing:
                continue
            tried = [a for v in _values(mistake) if (a := self.attempt((Switch(mistake.code,
                                                                               v),)))]
            if tried:
                out.append(max(tried, key=lambda a: a.rank))
        out.sort(key=lambda a: a.rank, reverse=True)
        swept = [i for i, a in enumerate(out) if (p := a.switches[0].mistake.parameter)
                 is not None and a.switches[0].value is not None and not p.names][:REFINED]
        for i in swept:
            out[i] = self._refine(out[i].switches[0].mistake, out[i])
        return sorted(out, key=lambda a: a.rank, reverse=True)

    def _refine(self, mistake: Mistake, best: Attempt) -> Attempt:
        """The parameter on a finer grid between the best value's neighbours, twice: REFINE
        evenly spaced values (log-spaced for an offset) each round."""
        p = mistake.parameter
        assert p is not None

        def value_of(attempt: Attempt) -> float:
            value = attempt.switches[0].value
            assert value is not None  # a mistake with a parameter is switched with a value
            return value

        grid = sorted({*(v for v in p.sweep if v != p.course), p.low, p.high})
        value = value_of(best)
        for _ in range(REFINE_ROUNDS):
            if best.reproduces:
                break
            i = grid.index(value)
            grid = _spaced(grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)], p.geometric)
            if p.integer:
                grid = [float(round(v)) for v in grid]
            grid = sorted({*grid, value})
            for other in grid:
                if other == value or other == p.course:
                    continue
                found = self.attempt((Switch(mistake.code, other),))
                if found is not None and found.rank > best.rank:
                    best = found
            value = value_of(best)
        # the round numbers near it: a program's constant is 1.5 or 0.05, not 1.46875
        for other in _rounded(value):
            if p.low <= other <= p.high and other != p.course and not best.reproduces:
                found = self.attempt((Switch(mistake.code, other),))
                if found is not None and found.rank > best.rank:
                    best = found
        return best

    def _combined(self, singles: list[Attempt]) -> Attempt | None:
        """The best of the PAIR_SEEDS best singles (and the WIDE_SEEDS that explain most)
        each combined with the PARTNERS singles
        that best change what it leaves unexplained, then that pair with a third; None where
        no combination is accepted."""
        ranked = [a for a in singles if a.explained > 0.0]
        # the best, and those that explain most whatever else they change (a second mistake
        # may undo that: blockers beyond the light with the light reversed)
        wide = sorted(ranked, key=lambda a: a.explained, reverse=True)[:WIDE_SEEDS]
        seeds = ranked[:PAIR_SEEDS] + [a for a in wide if a not in ranked[:PAIR_SEEDS]]
        best: Attempt | None = None
        for seed in seeds:
            for other in self._partners(seed, singles):
                found = self.attempt(seed.switches + other.switches)
                if found is not None and (best is None or found.rank > best.rank):
                    best = found
        if best is not None and best.explained < ALL_EXPLAINED:
            for other in self._partners(best, singles):
                found = self.attempt(best.switches + other.switches)
                if found is not None and found.rank > best.rank:
                    best = found
        return best if best is not None and best.accepted(self.tolerance) else None

    def _partners(self, seed: Attempt, singles: list[Attempt]) -> list[Attempt]:
        """The singles of other mistakes whose change of the reference, added to the seed's
        render, brings most of the pixels the seed gets wrong toward the candidate's (as if
        the two changes added up, which they nearly do where they touch other terms), and
        those that change most of those pixels and little else."""
        codes = {s.code for s in seed.switches}
        wrong = {k: _beyond(seed.images[k], self.candidate[k], self.tolerance)
                 for k in self.candidate}
        before = sum(float(np.abs(self.candidate[k] - seed.images[k])[wrong[k]].sum())
                     for k in wrong)

        def gain(a: Attempt) -> float:
            after = 0.0
            for k in wrong:
                moved = seed.images[k] + (a.images[k] - self.reference[k])
                after += float(np.abs(self.candidate[k] - moved)[wrong[k]].sum())
            return (before - after) / max(before, 1.0)

        count = sum(int(w.sum()) for w in wrong.values())

        def touch(a: Attempt) -> float:
            """How closely the pixels `a` changes are the seed's wrong ones (F1 of the two
            sets), less what it changes where the candidate is right: where two changes do
            not add up (a highlight of another shape under another falloff), that they meet
            the same pixels."""
            changed = {k: _beyond(a.images[k], self.reference[k], self.tolerance)
                       for k in wrong}
            both = sum(int((wrong[k] & changed[k]).sum()) for k in wrong)
            size = sum(int(c.sum()) for c in changed.values())
            return 2.0 * both / max(count + size, 1) - 4.0 * a.new

        others = [a for a in singles if a.switches[0].code not in codes]
        chosen: list[Attempt] = []
        for measure in (gain, touch):
            scored = sorted(((measure(a), a) for a in others), key=lambda ma: -ma[0])
            chosen += [a for m, a in scored[:PARTNERS // 2] if m > 0.0 and a not in chosen]
        return chosen


def _better(best: Attempt | None, found: Attempt | None) -> Attempt | None:
    """`found` where it ranks above `best` (or there is no best), else `best`."""
    return found if found is not None and (best is None or found.rank > best.rank) else best


def kernel_switches(kernel: WrittenKernel) -> tuple[Switch, ...]:
    """The generated mistakes that make the tracer's -filter `kernel`: each weight other than
    the course's at its site (the fit's rows are top-down, the course's K counts sub-rows from
    the bottom: render.box_filter_3x3) and the divisor where it is not 16; none where a
    value lies outside its site's range (a fit of images no kernel makes: weights of 60)."""
    switches = [Switch(FILTER_CODES[3 * j + i], float(kernel.weights[2 - j][i]))
                for j in range(3) for i in range(3) if kernel.weights[2 - j][i] != K[j][i]]
    if kernel.divisor != 16:
        switches.append(Switch(FILTER_CODES[9], float(kernel.divisor)))
    try:
        return tuple(check_switch(s) for s in switches)
    except MistakeError:
        return ()


def own_kernel(switches: tuple[Switch, ...]) -> str | None:
    """Where `switches` are two or more of the -filter's constants and nothing else, the
    kernel they make said as a cause (rows top-down: "... kernel is [1 1 1; 1 1 1; 1 1 1]/9,
    not the course's ..."); else None."""
    values = {s.code: s.value for s in switches}
    if len(switches) < 2 or not set(values) <= set(FILTER_CODES) or None in values.values():
        return None
    rows = ("; ".join(" ".join(f"{values.get(FILTER_CODES[3 * (2 - r) + i], K[2 - r][i]):g}"
                               for i in range(3)) for r in range(3)))
    return (f"{switches[0].mistake.function}: your program's -filter kernel is "
            f"[{rows}]/{values.get(FILTER_CODES[9], 16.0):g}, not the course's "
            "[1 2 1; 2 4 2; 1 2 1]/16")


def _beyond(a: np.ndarray, b: np.ndarray, tolerance: Tolerance) -> np.ndarray:
    return np.abs(a - b).max(axis=2) > tolerance.levels


def _values(mistake: Mistake) -> tuple[float | None, ...]:
    p = mistake.parameter
    return (None,) if p is None else tuple(v for v in p.sweep if v != p.course)


def _rounded(value: float) -> list[float]:
    """value to one, two and three significant digits."""
    if value == 0:
        return []
    return sorted({float(f"{value:.{d}g}") for d in (1, 2, 3)} - {value})


def _spaced(lo: float, hi: float, geometric: bool) -> list[float]:
    """REFINE values from lo to hi, evenly spaced, or on a log scale for an offset (from
    hi/1000 where lo is 0)."""
    if geometric and hi > 0:
        lo = max(lo, hi / 1000)
        return [float(lo * (hi / lo) ** (k / (REFINE - 1))) for k in range(REFINE)]
    return [lo + (hi - lo) * k / (REFINE - 1) for k in range(REFINE)]


# --- findings ------------------------------------------------------------------------------
def cause_findings(search: CauseSearch, found: Attempt | None, kind: str,
                   per_kind: dict[str, Attempt] | None = None) -> list[Finding]:
    """The findings of a failing kind from the search: one per mistake of the cause, the one
    that explains most first (its evidence: the reproducing render), or `unexplained`.
    per_kind: where no cause explains the case, the search's per_kind()."""
    if found is None and per_kind and kind in per_kind:
        return _findings(search, per_kind[kind], kind, per_kind_how(search, per_kind, kind),
                         "")
    if found is None:
        closest = search.closest()
        hint = ""
        if closest is not None and closest.explained > 0.5:
            hint = (f" (the closest, {' + '.join(str(s) for s in closest.switches)}, matches "
                    f"{closest.explained:.0%} of the differing pixels and is not a cause)")
        ruled_out = "".join(f" Ruled out: {r.describe()}." for r in search.refuted
                            if search.case.id in r.explained)
        return [Finding("cause:unexplained",
                        "no known mistake reproduces this image" + hint + ruled_out)]
    how = ("reproduces your images" if found.reproduces
           else f"matches {found.explained:.1%} of the pixels where your images differ")
    alternatives = search.alternatives(found)
    return _findings(search, found, kind, how, cannot_tell(a.switches for a in alternatives),
                     elsewhere((found.switches, found.images),
                               ((a.switches, a.images) for a in alternatives)))


# a render (or a jittered search's means): its switches and its images, kind -> image
Rendered = tuple[tuple[Switch, ...], Mapping[str, np.ndarray]]


def elsewhere(cause: Rendered, alternatives: Iterable[Rendered]) -> tuple[str, ...]:
    """The functions of the alternatives whose images are the cause's, to the level, and
    that have no mistake in a function of the cause's: where there are any, these images
    cannot tell which function is wrong (a light's term missing is a light's function
    returning nothing, or the light loop ending before it). One that only passes the
    tolerance as well fits less closely than the cause, which stays first."""
    switches, images = cause
    own = {s.mistake.function for s in switches}
    return tuple(dict.fromkeys(
        s.mistake.function for others, theirs in alternatives
        if not own & {t.mistake.function for t in others}
        and theirs.keys() == images.keys()
        and all(np.array_equal(theirs[k], images[k]) for k in images) for s in others))


def undecided_lead(switch: Switch, others: tuple[str, ...]) -> tuple[str, tuple[str, ...]]:
    """How a cause's first finding opens ("Class::function: your program ..."), and the
    functions it names, where the images cannot tell it from mistakes in `others`: both
    functions, neither first."""
    m = switch.mistake
    if not others:
        return f"{m.function}: your program {switch.describe()}", ()
    functions = (m.function, *others)
    return (f"{either(functions)}: these images cannot tell which of them is wrong; your "
            f"program {switch.describe()}", functions)


def per_kind_how(search: CauseSearch, per_kind: dict[str, Attempt], kind: str) -> str:
    """How a kind's own cause matches: its image, the other failing kinds differing for
    another reason."""
    others = sorted(k for k, d in search.differs.items()
                    if d.any() and k not in per_kind[kind].passing)
    return (f"reproduces your image of this kind ({kind}); your {' and '.join(others)} "
            f"image{'s differ' if len(others) > 1 else ' differs'} for another reason")


def _findings(search: CauseSearch, found: Attempt, kind: str, how: str,
              undecided: str, others: tuple[str, ...] = ()) -> list[Finding]:
    """One finding per mistake of `found`, the one whose single attempt explained most
    first, each saying `how` the reference with them matches; where alternatives in `others`
    (other functions) match as well, the first names its function and those, none first."""
    together = len(found.switches) > 1
    spelled = ",".join(str(s) for s in found.switches)
    matches = (f"the reference {how}: {found.matching:.1%} of pixels match (was "
               f"{search.before:.1%}).{undecided} Render it: python -m raycheck.tracer ... "
               f"--mistake {spelled}")
    kernel = own_kernel(found.switches)
    if kernel is not None:  # one finding, the whole kernel
        return [Finding(f"cause:{_by_weight(search, found)[0].code}",
                        f"{kernel}. With it, {matches}",
                        evidence=found.images[kind].astype(np.uint8),
                        numbers=tuple(s.value for s in found.switches if s.value is not None),
                        specific=True)]
    out: list[Finding] = []
    for switch in _by_weight(search, found):
        m = switch.mistake
        also = (" together with " + ", ".join(
            str(s) + (" (a quirk of the course program's)" if s in BY_SWITCH else "")
            for s in found.switches if s != switch) if together else "")
        quirk = BY_SWITCH.get(switch)
        said, functions = undecided_lead(switch, () if out else others)
        if quirk is not None:
            said, functions = f"{quirk.describe()}: not counted unless --strict", ()
        out.append(Finding(
            f"cause:{m.code}", f"{said}. With this mistake{also}, {matches}",
            evidence=found.images[kind].astype(np.uint8),
            numbers=() if switch.value is None else (switch.value,), specific=True,
            functions=functions))
    return out


def kinds_how(search: CauseSearch, per_kind: dict[str, Attempt]) -> str:
    """How the causes found per kind match, for the case's CauseRecord."""
    return "; ".join(f"with {' + '.join(str(s) for s in a.switches)} the reference "
                     f"{per_kind_how(search, per_kind, k)}" for k, a in per_kind.items())


def cause_how(search: CauseSearch, found: Attempt) -> str:
    """How the reference with the cause matches the case's images, for its CauseRecord; and
    where a mistake in another function matches as well, that these images cannot tell."""
    others = elsewhere((found.switches, found.images),
                       ((a.switches, a.images) for a in search.alternatives(found)))
    undecided = (f"; these images cannot tell it from a mistake in {either(others)}"
                 if others else "")
    if found.reproduces:
        return (f"the reference with them reproduces your images: {found.matching:.1%} of "
                f"pixels match (was {search.before:.1%}){undecided}")
    return (f"the reference with them matches {found.explained:.1%} of the pixels where your "
            f"images differ; the rest differ for another reason{undecided}")


def cannot_tell(alternatives) -> str:
    """The sentences naming other mistakes (each a tuple of switches) that the images cannot
    tell from the cause."""
    return "".join(f" These images cannot tell it from: your program "
                   f"{'; and '.join(s.describe() for s in switches)} "
                   f"(--mistake {','.join(str(s) for s in switches)})."
                   for switches in alternatives)


def _by_weight(search: CauseSearch, found: Attempt) -> list[Switch]:
    """The cause's switches, the one whose single attempt explained most first."""
    def alone(s: Switch) -> float:
        a = search.attempts.get((s,))
        return a.explained if a is not None else 0.0
    return sorted(found.switches, key=lambda s: -alone(s))
