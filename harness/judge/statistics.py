"""A jittered image judged against the reference's sampling distribution (issue 13).

A -jitter image is one random draw. The reference renders K independent realisations of the
same request (different seeds); per pixel and channel their 8-bit values x_k give a mean mu and
a sample variance s2. A candidate's 8-bit value x is scored, as in Mitsuba's
RenderingRegressionTest (a per-pixel Z-test, Sidak-corrected) and Jung, Hanika and
Dachsbacher, JCGT 2020 (a per-pixel t-test), by

    z = (x - mu) / sqrt(s2 (1 + 1/K) + q2)

where (1 + 1/K) adds the uncertainty of mu (estimated from K draws) and q2 is a quantisation
floor (QUANTISATION_VARIANCE). Five statistics, each tested at alpha_s = 1 - (1 - alpha)^(1/5)
(Sidak over the five, so the image's false-alarm rate is at most `alpha`):

* pixels: a pixel fails when a channel's two-sided Student-t p-value (K - 1 degrees of freedom:
  s2 is estimated) is below the Sidak level 1 - (1 - alpha_s)^(1/n) over the image's n tests;
  the image fails when fewer than `min_pass_share` of its pixels pass;
* bias: mean z over the noisy tests (below); a shift of every value by k reference standard
  deviations moves it by k;
* noise: mean z^2 over the noisy tests, about the variance ratio candidate / reference: near 0
  without jitter where the pixel centre decides, 4 with 4 samples instead of 16, 1/4 with 64;
* correlation: sum of a_p a_q over horizontal and vertical neighbour pairs (a_p: the sum of a
  pixel's channel z, less its mean over the image) over sqrt(sum a_p^2 sum a_q^2), ~0 for
  independent pixels, ~1 when every pixel shares one jitter pattern (neighbours along an edge
  then err alike);
* poisoned: the number of pixels decided by an inf/NaN/missed sample among those the reference
  decides so in some but not all realisations, against its Poisson-binomial expectation.

The global statistics' null distributions come from the realisations themselves: each
realisation, scored against the mean and variance of the other K - 1 (leave one out), is a
draw of the candidate's z under the null. Per pixel that gives E[a_p] = 0, Var[a_p], E[b_p]
and Var[b_p] (b_p: the sum of
a pixel's channel z^2) honestly for 8-bit, clamped, channel-correlated and heavy-tailed values;
summed over the n_p independent pixels (every pixel draws its own sample stream):

    bias:        |sum a_p / N| <= c sqrt(sum Var[a_p]) / N                  (N: noisy tests)
    noise:       sum b_p within the Gamma(mean = sum E[b_p], var = sum Var[b_p]) quantiles
                 alpha_s/2 and 1 - alpha_s/2, divided by N (sums of squares are right-skewed)
    correlation: |r| <= c sqrt(sum Var[a_p] Var[a_q]) / sqrt(sum Var[a_p] sum Var[a_q])
    poisoned:    |n - sum q| <= c sqrt(sum q (1 - q) (1 + 1/K) + 1/4)

with c = Phi^-1(1 - alpha_s / 2); for N independent unit-variance tests the bias bound is
c / sqrt(N) and the correlation bound c / sqrt(pairs). "Noisy" tests are the channels of
pixels whose values vary across the realisations and that pass the per-pixel test; pixels
that never vary (flat background, interiors) are judged only by the per-pixel test, through the
floor q2: their null has no spread for a global statistic to measure.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..records import JitterRecord, StatisticRecord

# The variance of a uniform rounding error over one 8-bit level (1/12 level^2): the spread an
# exact value hides when it is quantised. Where every realisation gives the same byte, a
# correct candidate may still land one level off (another engine's float rounding before the
# truncation): with this floor that is z = 3.5, within every Sidak threshold used here (>= 4.5
# at 16x16), while 3 levels off (z = 10.4) fail at any image size: the same one-level tolerance
# deterministic images get.
QUANTISATION_VARIANCE = 1.0 / 12.0
# False alarms per judged image (kind) of a correct candidate. A report judges ~60 jittered
# images: 1e-3 each keeps the chance that a random seed fails any of them near 6%.
ALPHA = 1e-3
# Share of pixels that must pass the per-pixel test. Under the null a Sidak-corrected pixel
# fails with probability alpha_s / n, so 1.0 would do for a candidate drawing exactly the
# reference's distribution; 0.999 leaves room for the tracer against Mitsuba, whose
# intersectors round differently at silhouettes and shadow edges (0 to 4 pixels per 128x128
# image on the bundled scenes), and fails every defect of the benchmark by far.
MIN_PASS_SHARE = 0.999
STATISTICS = ("pixels", "bias", "noise", "correlation", "poisoned")
# |z| bound of the global statistics: far beyond the bulk of a unit-variance z (P(|z| > 6) =
# 2e-9 for Gaussian values; a candidate with 4 times the variance loses 1% of its mean z^2), so
# clipping changes nothing where values are near-Gaussian and caps a rare-value pixel's z^2 at
# 36 instead of thousands.
Z_CLIP = 6.0


@dataclass(frozen=True)
class JitterTest:
    """The test's parameters (module docstring): the false-alarm rate per image, the share of
    pixels that must pass, the quantisation floor in level^2."""

    alpha: float = ALPHA
    min_pass_share: float = MIN_PASS_SHARE
    quantisation_variance: float = QUANTISATION_VARIANCE

    @property
    def alpha_each(self) -> float:
        """Each statistic's level: Sidak over the len(STATISTICS) statistics."""
        return sidak(self.alpha, len(STATISTICS))

    def describe(self) -> str:
        return (f"false-alarm rate {self.alpha:g} per image (Sidak over "
                f"{len(STATISTICS)} statistics), at least {self.min_pass_share:.1%} of pixels "
                f"passing, quantisation floor {self.quantisation_variance:.4g} level^2")


@dataclass(frozen=True)
class Statistic:
    """One statistic's value and its acceptance band [low, high] (None: not applicable, too few
    tests to measure it)."""

    name: str
    value: float | None
    low: float | None
    high: float | None
    meaning: str
    expected: float | None = None  # its value under the null, where not the band's middle

    @property
    def passed(self) -> bool:
        if self.value is None:
            return True
        return self.low is not None and self.high is not None and \
            bool(self.low <= self.value <= self.high)

    def failure(self) -> str:
        return (f"{self.name} {self.value:.4g} outside [{self.low:.4g}, {self.high:.4g}] "
                f"({self.meaning})")

    def record(self) -> StatisticRecord:
        def num(v: float | None) -> float | None:
            return None if v is None else float(v)

        return StatisticRecord(self.name, num(self.value), num(self.low), num(self.high),
                               self.passed)


@dataclass(frozen=True)
class PixelCounts:
    """How many pixels the test judged and how they came out (records.JitterRecord's)."""

    realisations: int
    tested_pixels: int
    failing_pixels: int
    allowed_failing_pixels: float
    noisy_pixels: int
    mixed_pixels: int
    pixel_threshold: float


@dataclass
class JitterResult:
    statistics: list[Statistic]
    z: np.ndarray  # (h, w): per pixel the largest |z| over channels (0 where not tested)
    counts: PixelCounts

    @property
    def passed(self) -> bool:
        return all(s.passed for s in self.statistics)

    @property
    def failed(self) -> list[Statistic]:
        return [s for s in self.statistics if not s.passed]

    def record(self) -> JitterRecord:
        c = self.counts
        return JitterRecord(tuple(s.record() for s in self.statistics), c.realisations,
                            c.tested_pixels, c.failing_pixels, c.allowed_failing_pixels,
                            c.noisy_pixels, c.mixed_pixels, float(c.pixel_threshold))


def _scipy_stats():
    """scipy.stats, imported where a jittered image is judged: its import takes ~0.9 s, which
    every raycheck process paid at start-up, deterministic cases only or not."""
    from scipy import stats

    return stats


def sidak(alpha: float, n: int) -> float:
    """The per-test level that keeps the chance of any of n independent false alarms at alpha:
    1 - (1 - alpha)^(1/n), computed without cancellation for tiny levels."""
    return float(-np.expm1(np.log1p(-alpha) / max(n, 1)))


def pixel_threshold(n_tests: int, k: int, alpha_each: float) -> float:
    """|z| beyond which one of n_tests fails: Student t with k - 1 degrees of freedom at the
    two-sided Sidak level."""
    return float(_scipy_stats().t.isf(sidak(alpha_each, n_tests) / 2, k - 1))


@dataclass(frozen=True)
class Reference:
    """What the test needs of K realisations, computed once (prepare) for any number of
    candidates: per pixel and channel mu and the z denominator, per pixel the null moments of
    the global statistics."""

    k: int
    mu: np.ndarray  # (h, w, C)
    scale: np.ndarray  # (h, w, C): sqrt(s2 (1 + 1/K) + q2)
    tested: np.ndarray  # (h, w): not poisoned in some-but-not-all realisations
    mixed_q: np.ndarray  # (h, w): the poisoned share q where 0 < q < 1, else 0
    varying: np.ndarray  # (h, w): some channel varies across the realisations
    var_a: np.ndarray  # (h, w): null Var[a_p] (clipped z)
    mean_b: np.ndarray  # (h, w): null E[b_p]
    var_b: np.ndarray  # (h, w): null Var[b_p]
    limit: float  # per-pixel |z| threshold
    lam: float  # leave-one-out expected count of pixels beyond it


def null_scores(d: np.ndarray, ss: np.ndarray, q2: float) -> np.ndarray:
    """(K, ...) null draws of z, from the realisations' deviations d from their mean and the
    sum ss of d^2: realisation k scored against the other K - 1, as the candidate is against
    all K: its z then carries the same extra spread from an estimated mean and variance (about
    (K - 1)/(K - 3) in z^2 for Gaussian values) and the same outliers where a pixel rarely
    changes, which scoring a realisation against a mean and variance that include it would
    hide."""
    k = d.shape[0]
    # leave one out: mean_-k = mu - d_k/(K-1), so r_k - mean_-k = d_k K/(K-1); the sum of
    # squares without r_k is ss - d_k^2 K/(K-1). In place: the (K, h, w, C) temporaries
    # were half of the time (fresh pages for each).
    d_out = d * (k / (k - 1))
    var_out = np.multiply(d, d_out)
    np.subtract(ss, var_out, out=var_out)
    np.maximum(var_out, 0.0, out=var_out)
    np.divide(var_out, k - 2, out=var_out)
    np.multiply(var_out, 1 + 1 / (k - 1), out=var_out)
    np.add(var_out, q2, out=var_out)
    np.sqrt(var_out, out=var_out)
    return np.divide(d_out, var_out, out=d_out)


def _over_channels(ufunc: np.ufunc, a: np.ndarray) -> np.ndarray:
    """ufunc.reduce over the last axis, channel after channel as numpy adds them: the same
    values, without numpy's slow inner loop over a 1-3 element axis (half of prepare's time).
    A new array, also for one channel."""
    out = a[..., 0].copy()
    for c in range(1, a.shape[-1]):
        ufunc(out, a[..., c], out=out)
    return out


def prepare(realisations: np.ndarray, poisoned_share: np.ndarray | None = None,
            test: JitterTest = JitterTest()) -> Reference:
    """The test's view of K realisations (K, h, w, C) in 8-bit levels; poisoned_share (h, w):
    the share of realisations in which the pixel is decided by an inf/NaN/missed sample."""
    k, h, w, channels = realisations.shape
    if k < 4:
        raise ValueError("the reference distribution needs at least 4 realisations")
    d = realisations.astype(np.float64)
    mu = d.mean(axis=0)
    np.subtract(d, mu, out=d)
    ss = np.square(d).sum(axis=0)  # the sample variance's terms, as np.var adds them
    scale = np.sqrt(ss / (k - 1) * (1 + 1 / k) + test.quantisation_variance)
    q = np.zeros((h, w)) if poisoned_share is None else np.asarray(poisoned_share, np.float64)
    mixed = (q > 0) & (q < 1)
    tested = ~mixed
    null = null_scores(d, ss, test.quantisation_variance)
    limit = pixel_threshold(int(tested.sum()) * channels, k, test.alpha_each)
    # A correct candidate also fails pixels where it draws a value none of the K realisations
    # showed (an edge pixel where one sample in 16 rarely hits: about 1/(e (K + 1)) per such
    # pixel, z unbounded as the realisations' variance there is 0). Their expected number is
    # the leave-one-out count over the realisations, plus the pixels poisoned in all but one
    # realisation or in one only, over K (left out, that one is alone: the candidate's
    # counterpart is a pixel the others always, or never, decide by a missed sample).
    beyond = _over_channels(np.maximum, np.abs(null)) > limit
    lam = float((beyond & tested).sum(axis=(1, 2)).mean()
                + np.isin(np.rint(q * k), (1, k - 1)).sum() / k)
    # The global statistics clip z (and the null draws alike, so the null stays exact) at
    # Z_CLIP: a sum of squares would otherwise be ruled by the few rare-value pixels above.
    np.clip(null, -Z_CLIP, Z_CLIP, out=null)
    a_null = _over_channels(np.add, null)
    b_null = _over_channels(np.add, np.square(null, out=null))
    # a null draw is 0 exactly where its deviation is: where every realisation agrees
    varying = tested & _over_channels(np.logical_or, ss > 0)
    return Reference(k, mu, scale, tested, np.where(mixed, q, 0.0), varying,
                     (a_null**2).mean(axis=0), b_null.mean(axis=0), b_null.var(axis=0, ddof=1),
                     limit, lam)


def judge(x: np.ndarray, realisations: np.ndarray | Reference,
          poisoned_share: np.ndarray | None = None, x_poisoned: np.ndarray | None = None,
          test: JitterTest = JitterTest()) -> JitterResult:
    """Judges candidate values x (h, w, C) in 8-bit levels against K realisations (K, h, w, C)
    of the reference, or their prepare()d Reference (made with the same test). x_poisoned
    (h, w): whether the candidate's pixel is decided by an inf/NaN/missed sample. Pixels
    poisoned in some but not all realisations are judged by the poisoned count only."""
    ref = realisations if isinstance(realisations, Reference) else \
        prepare(realisations, poisoned_share, test)
    if x.shape != ref.mu.shape:
        raise ValueError(f"candidate {x.shape} and realisations {ref.mu.shape} differ")
    k, tested, limit = ref.k, ref.tested, ref.limit
    alpha_s = test.alpha_each
    c = float(_scipy_stats().norm.isf(alpha_s / 2))
    z = (np.asarray(x, np.float64) - ref.mu) / ref.scale

    # per pixel: allowed is the Poisson 1 - alpha_s quantile of the leave-one-out count, or
    # the share 1 - min_pass_share of the pixels if that is more
    zmax = np.where(tested, np.abs(z).max(axis=2), 0.0)
    n_pixels = int(tested.sum())
    failing = int((zmax > limit).sum())
    allowed = max(float(_scipy_stats().poisson.ppf(1 - alpha_s, ref.lam)) if ref.lam > 0 else 0.0,
                  (1 - test.min_pass_share) * n_pixels)
    share = 1 - failing / n_pixels if n_pixels else 1.0
    out = [Statistic("pixels passing", share if n_pixels else None,
                     1 - allowed / n_pixels if n_pixels else None, 1.0,
                     f"share of pixels with every channel within |z| <= {limit:.3g}; "
                     f"{failing} fail, {allowed:.0f} allowed")]
    z = np.clip(z, -Z_CLIP, Z_CLIP)

    # global statistics over the noisy pixels that pass the per-pixel test: those that fail
    # are counted above (and are where two engines' systematic differences, such as ties
    # between coplanar faces, sit); under the null they are a share alpha_s / n of the pixels
    noisy = ref.varying & (zmax <= limit)
    n = int(noisy.sum()) * x.shape[2]
    a, b = z.sum(axis=2), (z * z).sum(axis=2)
    var_a = np.where(noisy, ref.var_a, 0.0)
    if n and var_a.sum() > 0:
        bound = c * np.sqrt(var_a.sum()) / n
        out.append(Statistic("mean z", float(a[noisy].sum() / n), -bound, bound,
                             "bias: the candidate is brighter (+) or darker (-) than the "
                             "reference's distribution"))
    else:
        out.append(Statistic("mean z", None, None, None, "no noisy pixels"))
    m, v = float(ref.mean_b[noisy].sum()), float(ref.var_b[noisy].sum())
    if n and v > 0:
        lo, hi = _scipy_stats().gamma.ppf([alpha_s / 2, 1 - alpha_s / 2], m * m / v, scale=v / m)
        out.append(Statistic("mean z^2", float(b[noisy].sum() / n), float(lo / n),
                             float(hi / n), "noise level: about the variance ratio candidate/"
                             f"reference (null mean {m / n:.3g}); low: too little noise (no "
                             "jitter, more samples), high: too much (fewer samples) or a "
                             "wrong distribution", expected=m / n))
    else:
        out.append(Statistic("mean z^2", None, None, None, "no noisy pixels"))
    out.append(_correlation(a, var_a, noisy, c))

    # poisoned count
    mixed = ~tested
    if mixed.any():
        q = ref.mixed_q
        expected = float(q[mixed].sum())
        got = int((np.zeros(mixed.shape, bool) if x_poisoned is None else x_poisoned)[mixed]
                  .sum())
        spread = c * np.sqrt(float((q * (1 - q))[mixed].sum()) * (1 + 1 / k) + 0.25)
        out.append(Statistic("poisoned pixels", float(got), expected - spread,
                             expected + spread, "pixels decided by an inf/NaN/missed sample "
                             f"where the reference's are in some realisations (expected "
                             f"{expected:.1f})"))
    else:
        out.append(Statistic("poisoned pixels", None, None, None, "none in the reference"))
    counts = PixelCounts(k, n_pixels, failing, allowed, int(noisy.sum()), int(mixed.sum()),
                         limit)
    return JitterResult(out, zmax, counts)


def _correlation(a: np.ndarray, var_a: np.ndarray, noisy: np.ndarray, c: float) -> Statistic:
    meaning = ("spatial correlation of z between neighbouring pixels: one jitter pattern "
               "shared by the pixels")
    if not noisy.any():
        return Statistic("correlation", None, None, None, meaning)
    a = a - a[noisy].mean()  # spatial structure beyond a bias (the bias has its statistic)
    pairs = [(a[:, :-1], a[:, 1:], var_a[:, :-1], var_a[:, 1:], noisy[:, :-1] & noisy[:, 1:]),
             (a[:-1], a[1:], var_a[:-1], var_a[1:], noisy[:-1] & noisy[1:])]
    cross = sum(float((p * q)[m].sum()) for p, q, _, _, m in pairs)
    sp = sum(float((p * p)[m].sum()) for p, _, _, _, m in pairs)
    sq = sum(float((q * q)[m].sum()) for _, q, _, _, m in pairs)
    vpq = sum(float((vp * vq)[m].sum()) for _, _, vp, vq, m in pairs)
    vp = sum(float(v[m].sum()) for _, _, v, _, m in pairs)
    vq = sum(float(v[m].sum()) for _, _, _, v, m in pairs)
    if sp <= 0 or sq <= 0 or vpq <= 0:
        return Statistic("correlation", None, None, None, meaning)
    bound = c * np.sqrt(vpq) / np.sqrt(vp * vq)
    return Statistic("correlation", cross / np.sqrt(sp * sq), -bound, bound, meaning)
