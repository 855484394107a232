"""The cause search of a jittered case: explain a failing jittered image by the mistake under
which the reference draws it.

A jittered image is one draw of a distribution, so no render reproduces it pixel for pixel.
What can be tested is whether it is a likely draw of the *mistaken* reference's distribution:
render SEARCH_REALISATIONS realisations of the reference with the mistake on and judge the
candidate against them with the check's own statistical test (judge/statistics.py). A mistake
under which every kind passes, where the course's distribution failed it, is the cause;
where mistakes of different codes pass, the images cannot tell them apart and the finding says
so. This is evidence at the test's power, not proof: a passing test means the candidate is
consistent with that distribution.

Tried, for one case: its priors, the causes the deterministic search found in the same
scene's unjittered cases of the program (given with the case: pipeline/matrix.py's Runner runs
those first, so that they are a function of the program's results, not of the order cases
ran in), then the -jitter mistakes, the catalogue's and the generated ones, that can change
the failing kinds, at their sweep's values (the sample count also at the value the
candidate's noise level suggests), then each prior with another prior's mistake or a
-jitter mistake (a program's mistakes together). A trial that reproduces the candidate pixel
for pixel ends the search. At most MAX_TRIALS distributions a case; a distribution the
candidate is far outside of after a screen's first realisations (SCREENS) is not rendered
further.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from raycheck.tracer.mistake_model import Needs
from raycheck.tracer.mistakes import Code, Switch, applicable
from raycheck.tracer.operators import GENERATED

from ..cases import Case
from ..judge.findings import Finding
from ..judge.findings import as_bytes as image_bytes
from ..judge.statistics import JitterResult, JitterTest, Statistic
from ..judge.verdict import Tolerance, jitter_result, judge_deterministic, poisoned
from ..storage.distribution import REFERENCE_SEED, as_bytes
from .causes import cannot_tell, elsewhere, own_kernel, undecided_lead

# realisations of a mistaken reference: half the check's 64, for half the cost of a trial; at
# 16 the variance estimated from so few makes a candidate drawn from the very distribution
# look 5-15% too calm, and the test rejects the right sample count
SEARCH_REALISATIONS = 32
# mistakes whose renders are all alike (every sample at one place): the distribution is one
# image
FIXED = frozenset({Code.JITTER_FIXED})
# mistakes that change only how noisy a pixel is (and so how often a missed sample decides
# it, and where values are clipped, its mean)
NOISE_ONLY = frozenset({Code.JITTER_SAMPLES, Code.JITTER_AUX_ONE_SAMPLE})
# how close in variance the candidate must be to a noise-only mistake's distribution
NOISE_MATCH = 1.5
# sample counts the search does not try: within 1.5x of the course's 16 in variance
SAMPLES_NEAR = (10.67, 24.0)
# the -jitter mistakes at their values (about 30, most of them rejected on the screen below),
# the priors, and a dozen pairs of a prior with another mistake
MAX_TRIALS = 44
# first looks at a distribution, (realisations, distance): where the candidate is this far
# off (summed half-widths outside the statistics' bands) with this many realisations, the
# mistake is rejected without the rest. Each distance is about three times the farthest a
# right mistake was (17 at 4, 9 at 8, over 30 right trials on four scenes); a wrong one is
# tens to thousands: 4 realisations reject 92% of the wrong trials that 8 do
SCREENS = ((4, 50.0), (8, 25.0))
PRIORS = 3


@dataclass(frozen=True)
class Trial:
    """The candidate judged against the reference's distribution with `switches` on."""

    switches: tuple[Switch, ...]
    passed: bool  # every kind is a likely draw of it (or, where it is one image, matches it)
    distance: float  # how far the candidate is from it (_distance)
    noise: float  # the candidate's variance over the distribution's (1: as noisy)
    means: dict[str, np.ndarray] = field(compare=False, repr=False)  # kind -> 8-bit mean


def _distance(results: list[JitterResult]) -> float:
    """Per statistic, its distance from the band's middle in half-widths (at most 1 inside
    the band), summed."""
    return sum(_deviation(s) for r in results for s in r.statistics)


def _noise(results: list[JitterResult]) -> float:
    """The candidate's noise over the distribution's: mean z^2 over its null mean, the
    geometric mean over the kinds (1 where no kind is noisy)."""
    ratios = [s.value / s.expected for r in results for s in r.statistics
              if s.name == "mean z^2" and s.value and s.expected]
    return float(np.exp(np.mean(np.log(ratios)))) if ratios else 1.0


def _deviation(s: Statistic) -> float:
    if s.value is None or s.low is None or s.high is None:
        return 0.0
    if s.name == "pixels passing":  # one-sided: failing pixels over those allowed
        return (1.0 - s.value) / max(1.0 - s.low, 1e-12)
    centre = (s.high + s.low) / 2.0 if s.expected is None else s.expected
    side = s.high - centre if s.value > centre else centre - s.low
    return abs(s.value - centre) / max(side, 1e-12)


class JitterSearch:
    """The search for one jittered case: the candidate's images (kind -> image) against the
    distributions of the reference with mistakes."""

    def __init__(self, case: Case, candidate: dict[str, np.ndarray],
                 failing: dict[str, tuple[Statistic, ...]], test: JitterTest,
                 tolerance: Tolerance, priors: tuple[tuple[Switch, ...], ...] = (),
                 refuted: frozenset[str] = frozenset()) -> None:
        from raycheck.tracer.scene import load_scene

        self.case, self.test, self.tolerance = case, test, tolerance
        self.priors = priors
        self.scene = load_scene(case.scene.path)
        self.request = replace(case.request, kinds=tuple(k for k in case.request.kinds
                                                         if k in candidate))
        self.candidate = {k: candidate[k] for k in self.request.kinds}
        self.failing = failing  # kind -> the statistics the course's distribution failed
        # the program's refuted causes (refute.py) are left out, as priors too; of the
        # generated mistakes, those its priors name (the deterministic search found them) and
        # those only -jitter shows
        named = {s.code for p in priors for s in p}
        generated = tuple(m for m in applicable(self.scene, self.request, GENERATED)
                          if m.code in named or Needs.JITTER in m.needs)
        self.mistakes = tuple(m for m in applicable(self.scene, self.request) + generated
                              if m.code not in refuted)
        self.compiled = tuple(m.code for m in self.mistakes)
        self.trials: dict[tuple[Switch, ...], Trial] = {}

    def _draws(self, switches: tuple[Switch, ...], k: int):
        """The images of K realisations of the reference with these switches on: one renderer,
        reseeded (the seed is a kernel input: one kernel serves every realisation)."""
        from raycheck.tracer.options import RenderOptions
        from raycheck.tracer.render import Renderer
        from raycheck.tracer.scene.request import request_fields

        renderer = Renderer(self.scene, RenderOptions(**request_fields(self.request),
                                                      mistakes=switches,
                                                      mistake_kernel=self.compiled))
        for i in range(k):
            renderer.opts = replace(renderer.opts, seed=REFERENCE_SEED + i)
            result = renderer.render()
            yield {kind: getattr(result, kind) for kind in self.request.kinds}

    def trial(self, switches: tuple[Switch, ...], screened: bool = True) -> Trial | None:
        """The candidate against the distribution with these switches (made once; None past
        the budget); screened: rejected early where the first realisations put it far off
        (SCREENS)."""
        switches = tuple(sorted(switches))
        if switches in self.trials:
            return self.trials[switches]
        if len(self.trials) >= MAX_TRIALS:
            return None
        if any(s.code in FIXED for s in switches):
            found = self._one_image(switches)
        else:
            found = self._distribution(switches, screened)
        self.trials[switches] = found
        return found

    def _distribution(self, switches: tuple[Switch, ...], screened: bool = True) -> Trial:
        """The candidate against SEARCH_REALISATIONS realisations, or, screened, against the
        first realisations of a screen where those already put it far outside (a wrong
        mistake is tens of band widths off: its other realisations are not rendered)."""
        judged = self._judged(switches)
        stacks: dict[str, list[np.ndarray]] = {kind: [] for kind in judged}
        bad: dict[str, np.ndarray] = {}
        draws = self._draws(switches, SEARCH_REALISATIONS)
        limits = dict(SCREENS) if screened else {}
        for k in (*limits, SEARCH_REALISATIONS):
            for images in draws:
                for kind in judged:
                    stacks[kind].append(as_bytes(images[kind]))
                    bad[kind] = bad.get(kind, 0) + poisoned(images[kind])
                if len(stacks[judged[0]]) == k:
                    break
            results, means = [], {}
            for kind, stack in stacks.items():
                realised = np.stack(stack)
                results.append(jitter_result(self.candidate[kind], realised,
                                             (bad[kind] / len(stack)).astype(np.float32),
                                             self.test))
                mean = np.rint(realised.mean(axis=0)).astype(np.uint8)
                means[kind] = np.repeat(mean, 3, axis=2) if mean.shape[2] == 1 else mean
            passed = all(r.passed for r in results) and self._explains(switches, results)
            found = Trial(switches, passed, _distance(results), _noise(results), means)
            if not found.passed and found.distance > limits.get(k, np.inf):
                break  # far off already: a wrong mistake
        return found

    def _judged(self, switches: tuple[Switch, ...]) -> tuple[str, ...]:
        """The kinds a distribution is judged on: the failing ones and those its mistakes can
        change. A kind that passed the check and that no switch changes is the course's
        distribution, which the check's test (at its 64 realisations) accepted already: judged
        again at the search's 32 it could only add a false rejection, as a depth image's
        variance did for a program whose color alone was wrong."""
        changed = set(self.failing) | {k for s in switches for k in s.mistake.kinds}
        return tuple(k for k in self.request.kinds if k in changed)

    def _one_image(self, switches: tuple[Switch, ...]) -> Trial:
        """A mistake that puts every sample at one place draws one image: the candidate must
        reproduce it within the check's tolerance, as a deterministic image."""
        images = next(self._draws(switches, 1))
        verdicts = [judge_deterministic(kind, image_bytes(image).astype(np.uint8),
                                        image_bytes(self.candidate[kind]).astype(np.uint8),
                                        self.tolerance) for kind, image in images.items()]
        share = sum(v.metrics.beyond_tolerance or 0.0 for v in verdicts if v.metrics)
        return Trial(switches, all(v.passed for v in verdicts), share, 1.0,
                     {k: image_bytes(v).astype(np.uint8) for k, v in images.items()})

    def _explains(self, switches: tuple[Switch, ...], results: list[JitterResult]) -> bool:
        """Whether the mistakes can explain what the course's distribution failed: more or
        less noise cannot make the pixels' deviations correlated (one jitter pattern shared
        by every pixel); and where the mistakes only change the noise, the candidate must be
        about as noisy as their distribution (within NOISE_MATCH in variance): a noisier
        distribution accepts much."""
        if any(s.code not in NOISE_ONLY for s in switches):
            return True
        if any(s.name == "correlation" for failed in self.failing.values() for s in failed):
            return False
        return 1 / NOISE_MATCH <= _noise(results) <= NOISE_MATCH

    # --- the search
    def run(self) -> Trial | None:
        """The passing trial closest to the candidate, or None where none passes."""
        priors = [p for p in self.priors if all(s.mistake in self.mistakes for s in p)][:PRIORS]
        # every prior tried: one that passes beside the first is an explanation the image
        # cannot tell from it (alternatives), as the unjittered case could not
        # unscreened: a faint image's pixels hardly vary, and its first few realisations
        # put even its own program's mistake tens of band widths off
        tried = [self.trial(prior, screened=False) for prior in priors]
        found = next((t for t in tried if t is not None and t.passed), None)
        if found is not None:
            return found
        jitter = self._jitter_switches()
        for sw in jitter:
            found = self.trial((sw,))
            if self._proof(found):
                return found
        passing = [t for t in self.trials.values() if t.passed]
        if not passing:  # a program's mistakes together: each cause found before with another
            # one, or with a -jitter mistake
            # the -jitter mistakes that came closest alone first
            jitter.sort(key=lambda sw: self.trials[(sw,)].distance
                        if self.trials.get((sw,)) is not None else np.inf)
            partners = list(dict.fromkeys(s for p in priors for s in p)) + jitter
            for prior in priors:
                for sw in partners:
                    if all(s.code != sw.code for s in prior):
                        found = self.trial(prior + (sw,))
                        if self._proof(found):
                            return found
            passing = [t for t in self.trials.values() if t.passed]
        if not passing:
            return None
        best = min(passing, key=lambda t: (len(t.switches), t.distance))
        return self._counted(best)

    def _proof(self, found: Trial | None) -> bool:
        """Whether a trial reproduced the candidate pixel for pixel (a one-image mistake: no
        jitter at all, or every sample at the pixel's centre): proof, as in the deterministic
        search; the search ends there."""
        return found is not None and found.passed and any(s.code in FIXED
                                                          for s in found.switches)

    def _counted(self, best: Trial) -> Trial:
        """Where the cause is a sample count n, the count the candidate's noise says: a mean
        of n samples is 16/n times as noisy as the course's, so the count is n over the
        candidate's noise relative to n's distribution; taken where it passes too."""
        counts = [s for s in best.switches if s.code == Code.JITTER_SAMPLES]
        if not counts or counts[0].value is None:
            return best
        n = float(max(1, round(counts[0].value / best.noise)))
        if n == counts[0].value or SAMPLES_NEAR[0] < n < SAMPLES_NEAR[1]:
            return best
        other = tuple(s for s in best.switches if s != counts[0]) + (Switch(counts[0].code, n),)
        found = self.trial(other)
        return found if found is not None and found.passed else best

    def _jitter_switches(self) -> list[Switch]:
        """The -jitter mistakes that can change the failing kinds, at their sweep's values and,
        for the sample count, at what the candidate's noise level says."""
        failing = set(self.failing)
        out = []
        for m in self.mistakes:
            if Needs.JITTER not in m.needs or not failing & m.kinds:
                continue
            p = m.parameter
            if p is None:
                out.append(Switch(m.code))
                continue
            values = set(p.sweep)
            if m.code == Code.JITTER_SAMPLES:
                values |= self._samples_suggested()
                # a count near the course's changes the noise by less than the test can tell
                # from other mistakes (one pattern for every pixel): not named
                values = {v for v in values if not SAMPLES_NEAR[0] < v < SAMPLES_NEAR[1]}
            out += [Switch(m.code, v) for v in sorted(values)
                    if v != p.course and p.low <= v <= p.high]
        return out

    def _samples_suggested(self) -> set[float]:
        """A mean of n samples has 16/n times the variance of the course's 16: the candidate's
        mean z^2 over its band's middle (about its variance over the reference's) suggests n,
        and its neighbours."""
        ratios = [s.value / ((s.low + s.high) / 2) for failed in self.failing.values()
                  for s in failed if s.name == "mean z^2" and s.value and s.low and s.high]
        if not ratios:
            return set()
        n = round(self.request.samples / max(ratios))
        return {float(v) for v in (n - 1, n, n + 1) if v >= 1}

    def alternatives(self, found: Trial) -> list[Trial]:
        """Passing trials of other mistakes: the images cannot tell them from the cause."""
        codes = {s.code for s in found.switches}
        return [t for t in self.trials.values()
                if t.passed and not codes & {s.code for s in t.switches}]

    def fitting_values(self, switch: Switch) -> list[float]:
        """The values of the switch's parameter that passed alone."""
        return sorted(t.switches[0].value for t in self.trials.values()
                      if t.passed and len(t.switches) == 1 and t.switches[0].code == switch.code
                      and t.switches[0].value is not None)


def jitter_how(found: Trial) -> str:
    """How the reference with the cause matches a jittered case's images."""
    if any(s.code in FIXED for s in found.switches):
        return "the reference reproduces your image"
    return (f"your image is a likely draw of the reference's distribution "
            f"({SEARCH_REALISATIONS} realisations: every statistic within its bounds)")


def jitter_cause_findings(search: JitterSearch, found: Trial | None,
                          kind: str) -> list[Finding]:
    """The findings of a failing jittered kind from the search: one per mistake of the cause,
    or `unexplained`."""
    if found is None:
        return [Finding("cause:unexplained", "no known mistake explains this jittered image "
                        f"(it is an unlikely draw of the reference's distribution with each "
                        f"of the {len(search.trials)} tried)")]
    was = "; ".join(f"{s.name} {s.value:.4g} outside [{s.low:.4g}, {s.high:.4g}]"
                    for s in search.failing.get(kind, ()) if s.value is not None) or "passing"
    alternatives = search.alternatives(found)
    undecided = cannot_tell(t.switches for t in alternatives)
    others = elsewhere((found.switches, found.means),
                       ((t.switches, t.means) for t in alternatives))
    spelled = ",".join(str(s) for s in found.switches)
    how = jitter_how(found)
    kernel = own_kernel(found.switches)
    if kernel is not None:  # one finding, the whole kernel
        return [Finding(f"cause:{found.switches[0].code}",
                        f"{kernel}. With it, {how}; without it: {was}.{undecided} Render it: "
                        f"python -m raycheck.tracer ... --mistake {spelled}",
                        evidence=found.means.get(kind),
                        numbers=tuple(s.value for s in found.switches if s.value is not None),
                        specific=True)]
    out: list[Finding] = []
    for switch in found.switches:
        also = "".join(f" and {s}" for s in found.switches if s != switch)
        fits = search.fitting_values(switch)
        span = (f" (values {fits[0]:g} to {fits[-1]:g} fit)" if len(fits) > 1 else "")
        said, functions = undecided_lead(switch, () if out else others)
        out.append(Finding(
            f"cause:{switch.code}",
            f"{said}{span}. With this mistake{also}, {how}; without it: {was}.{undecided} "
            f"Render it: python -m raycheck.tracer ... --mistake {spelled}",
            evidence=found.means.get(kind),
            numbers=() if switch.value is None else (switch.value,), specific=True,
            functions=functions))
    return out
