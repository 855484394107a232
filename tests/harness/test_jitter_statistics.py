"""The jitter test's statistics (harness/judge/statistics.py) on synthetic data with known
answers: Gaussian realisations and candidates with a known bias, variance ratio or shared
deviation, 8-bit-like values that never vary, and poisoned pixels. Seeded; where a property
holds only with high probability, the comment states the chance that it fails."""
from __future__ import annotations

import numpy as np
import pytest

from raycheck.harness.judge.statistics import JitterTest, _over_channels, judge, sidak

K, H, W, C = 64, 32, 32, 3
N = H * W * C
SIGMA = 10.0  # levels: quantisation (1/12 level^2) is 0.08% of the variance
EXACT = JitterTest(quantisation_variance=0.0)


def draws(rng, shift: float = 0.0, ratio: float = 1.0, shape=(K, H, W, C)
          ) -> tuple[np.ndarray, np.ndarray]:
    """(candidate, realisations): N(100, SIGMA^2) realisations, a candidate shifted by `shift`
    reference standard deviations with `ratio` times their variance."""
    ref = rng.normal(100, SIGMA, shape)
    x = rng.normal(100 + shift * SIGMA, SIGMA * np.sqrt(ratio), shape[1:])
    return x, ref


def stat(result, name: str):
    return next(s for s in result.statistics if s.name == name)


@pytest.mark.parametrize("channels", [1, 2, 3])
def test_channel_reductions_give_numpys_bits(channels):
    # prepare() reduces channel by channel for speed; its statistics must not move a bit
    a = np.random.default_rng(channels).standard_normal((8, 5, 7, channels)) * 1e3
    assert np.array_equal(_over_channels(np.add, a), a.sum(axis=3))
    assert np.array_equal(_over_channels(np.add, a * a), (a * a).sum(axis=3))
    assert np.array_equal(_over_channels(np.maximum, np.abs(a)), np.abs(a).max(axis=3))
    assert np.array_equal(_over_channels(np.logical_or, a > 1e3), (a > 1e3).any(axis=3))
    assert not np.shares_memory(_over_channels(np.add, a), a)  # prepare squares a in place


def test_sidak_level_keeps_the_familywise_rate():
    assert sidak(0.01, 1) == pytest.approx(0.01)
    assert 1 - (1 - sidak(1e-3, 49152)) ** 49152 == pytest.approx(1e-3, rel=1e-6)


def test_a_candidate_from_the_null_passes_at_the_nominal_rate():
    """200 null images (16x16, K = 32): the test's nominal false-alarm rate is 1e-3 per image,
    so at most 2 failures (the chance of 3 or more is 1.1e-3)."""
    rng = np.random.default_rng(1)
    failed = sum(not judge(*draws(rng, shape=(32, 16, 16, C)), test=EXACT).passed
                 for _ in range(200))
    assert failed <= 2


def test_bias_statistic_moves_by_the_shift_in_sigma_over_sqrt_n():
    """A shift of k sigma / sqrt(N) moves mean z by about k / sqrt(N) (the candidate's z is
    divided by sqrt(1 + 1/K)); k = 8 is twice the threshold c = 3.72, detected always (the
    chance it passes is below 1e-6), and only the bias fails."""
    rng = np.random.default_rng(2)
    for _ in range(5):
        x, ref = draws(rng, shift=8 / np.sqrt(N))
        r = judge(x, ref, test=EXACT)
        # its spread is 1 (plus 1/K from the reference's means): 4.5 sd, a 7e-6 chance
        assert stat(r, "mean z").value * np.sqrt(N) == pytest.approx(8, abs=4.5)
        assert [s.name for s in r.failed] == ["mean z"]
        assert stat(r, "mean z").high * np.sqrt(N) == pytest.approx(3.72, abs=0.15)


@pytest.mark.parametrize("ratio", [0.25, 2.0, 4.0])
def test_mean_z2_is_the_variance_ratio(ratio):
    """mean z^2 divided by its null mean ((K-1)/(K-3) for Gaussian values) is the candidate's
    variance over the reference's (with the reference mean's 1/K: (ratio + 1/K)/(1 + 1/K)),
    within 8% (3 sd of its spread sqrt(2/N) ratio, plus 1% lost to clipping at ratio 4), and
    the noise statistic fails."""
    rng = np.random.default_rng(3)
    x, ref = draws(rng, ratio=ratio)
    r = judge(x, ref, test=EXACT)
    null_mean = (K - 1) / (K - 3)
    expected = (ratio + 1 / K) / (1 + 1 / K)
    assert stat(r, "mean z^2").value / null_mean == pytest.approx(expected, rel=0.08)
    assert "mean z^2" in [s.name for s in r.failed]


def test_correlation_is_zero_for_independent_pixels_and_one_for_a_shared_pattern():
    """Independent candidates: |r| within its bound (c / sqrt(pairs) = 0.084). Deviations
    shared by neighbours (one draw per 4x4 block and channel, 3 sigma): r near 3/4 (of a
    pixel's 4 neighbour pairs, 3 on average lie in its block)."""
    rng = np.random.default_rng(4)
    x, ref = draws(rng)
    r = stat(judge(x, ref, test=EXACT), "correlation")
    assert abs(r.value) < r.high < 0.085
    blocks = rng.normal(0, 3 * SIGMA, (H // 4, W // 4, C)).repeat(4, 0).repeat(4, 1)
    r = judge(100 + blocks, ref, test=EXACT)
    assert stat(r, "correlation").value == pytest.approx(0.75, abs=0.05)
    assert "correlation" in [s.name for s in r.failed]


def test_pixels_that_never_vary_count_only_through_the_quantisation_floor():
    """Realisations all 100: a candidate one level off everywhere has z = 1/sqrt(1/12) = 3.46,
    below the per-pixel threshold, and no global statistic applies; one pixel 3 levels off
    (z = 10.4) fails there but is allowed (0.1% of 1024 pixels: 1.024), two fail the image."""
    ref = np.full((16, H, W, C), 100.0)
    x = np.full((H, W, C), 101.0)
    r = judge(x, ref)
    assert r.passed and r.z.max() == pytest.approx(np.sqrt(12))
    assert [s.value for s in r.statistics[1:4]] == [None, None, None]
    x[5, 5, 1] = 103.0
    r = judge(x, ref)
    assert r.passed and (r.counts.failing_pixels, r.counts.allowed_failing_pixels) == \
        (1, pytest.approx(1.024))
    x[9, 2, 0] = 97.0
    assert [s.name for s in judge(x, ref).failed] == ["pixels passing"]


def test_poisoned_pixels_are_counted_against_their_expected_number():
    """Pixels poisoned in half the realisations: a candidate poisoned in about half passes; one
    poisoned in none fails the poisoned count, and those pixels are not z-tested."""
    rng = np.random.default_rng(5)
    x, ref = draws(rng)
    q = np.zeros((H, W))
    q[:8] = 0.5
    half = np.zeros((H, W), bool)
    half[:4] = True
    r = judge(x, ref, q, half, EXACT)
    assert r.passed and stat(r, "poisoned pixels").value == 128
    assert r.counts.tested_pixels == (H - 8) * W
    r = judge(x, ref, q, np.zeros((H, W), bool), EXACT)
    assert [s.name for s in r.failed] == ["poisoned pixels"]
