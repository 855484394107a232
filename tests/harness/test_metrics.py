"""The comparison metrics on images whose values are worked out by hand."""
from __future__ import annotations

import numpy as np
import pytest

from raycheck.harness.judge import metrics
from raycheck.harness.judge.verdict import Tolerance, judge_deterministic, tolerated


def test_identical_images():
    a = np.random.default_rng(0).random((20, 20, 3)).astype(np.float32)
    c = metrics.compare(a, a.copy())
    assert (c.ssim, c.psnr, c.rmse, c.max_abs, c.off_by_more_than_one, c.equal_bytes,
            c.brightness_change_pct, c.flip) == (1.0, float("inf"), 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)


def test_errors_of_a_known_difference():
    a = np.full((10, 10), 0.5, np.float32)
    b = a.copy()
    b[0, :5] = 0.7  # 5 of 100 pixels off by 0.2 (51 levels)
    assert metrics.max_abs_error(a, b) == pytest.approx(0.2, abs=1e-6)
    assert metrics.mean_abs_error(a, b) == pytest.approx(0.01, abs=1e-7)
    assert metrics.rmse(a, b) == pytest.approx(np.sqrt(5 * 0.04 / 100), rel=1e-5)
    assert metrics.psnr(a, b) == pytest.approx(10 * np.log10(1 / (5 * 0.04 / 100)), rel=1e-5)
    assert metrics.share_off_by_more_than_one_level(a, b) == 0.05
    assert metrics.share_equal_bytes(a, b) == 0.95
    # 0.5 shows as byte 127, 0.7 as 178: mean 127 -> (95*127 + 5*178)/100
    assert metrics.mean_brightness_change(a, b) == pytest.approx(100 * (5 * 51 / 100) / 127,
                                                                rel=1e-5)
    assert metrics.flip(a, b) > 0


def test_one_level_of_difference_is_within_tolerance():
    a = np.full((4, 4, 3), 100 / 255, np.float32)
    b = np.full((4, 4, 3), 101.5 / 255, np.float32)
    assert metrics.share_off_by_more_than_one_level(a, b) == 0.0
    assert metrics.share_equal_bytes(a, b) == 0.0


def test_values_are_compared_as_shown():
    # the course shows 7.0 like 1.0 (255), and NaN, inf and 1e30 (a depth miss) as black
    a = np.array([[1.0, 0.0, 0.0, 0.0]], np.float32)
    b = np.array([[7.0, np.nan, np.inf, 1e30]], np.float32)
    assert metrics.bytes8(b).tolist() == [[255, 0, 0, 0]]
    assert metrics.max_abs_error(a, b) == 0.0


def test_ssim_uses_wang_settings_and_the_data_range():
    rng = np.random.default_rng(1)
    a = rng.random((32, 32)).astype(np.float32)
    b = np.clip(a + rng.normal(0, 0.05, a.shape), 0, 1).astype(np.float32)
    from skimage.metrics import structural_similarity

    expected = structural_similarity(a.astype(np.float64), b.astype(np.float64), data_range=1.0,
                                     gaussian_weights=True, sigma=1.5,
                                     use_sample_covariance=False)
    assert metrics.ssim(a, b) == pytest.approx(expected, rel=1e-12)
    score, full = metrics.ssim_map(a, b)
    # the score is the map's mean away from the borders (5 pixels for an 11x11 window)
    assert full.shape == (32, 32) and full[5:-5, 5:-5].mean() == pytest.approx(score, rel=1e-6)


def test_flip_of_byte_identical_images_is_0_without_calling_flip(monkeypatch):
    """Pictures whose 8-bit values agree are FLIP 0 (FLIP's own value for them) without the
    call; pictures that differ still get FLIP's number."""
    import flip_evaluator

    rng = np.random.default_rng(3)
    a = ((rng.integers(0, 255, (16, 16, 3)) + 0.25) / 255).astype(np.float32)
    same = a + np.float32(0.5 / 255)  # other floats, the same bytes
    assert np.array_equal(metrics.bytes8(a), metrics.bytes8(same))
    other = a * np.float32(0.5)
    real = metrics.flip(a, other)
    assert flip_evaluator.evaluate(metrics.displayed(a).astype(np.float32),
                                   metrics.displayed(a).astype(np.float32), "LDR",
                                   applyMagma=False)[1] == 0.0

    def refuse(*args, **kwargs):
        raise AssertionError("FLIP called on byte-identical images")

    monkeypatch.setattr(flip_evaluator, "evaluate", refuse)
    assert metrics.flip(a, same) == 0.0
    assert metrics.flip(a[..., 0], same[..., 0]) == 0.0
    assert real > 0.0


def test_ssim_map_of_the_same_pair_is_computed_once(monkeypatch):
    """A case's verdict and its SSIM picture ask for the same pair: one computation, the
    same numbers, and a map the caller may change without changing the next answer."""
    rng = np.random.default_rng(5)
    a = rng.random((24, 24, 3))
    b = np.clip(a + rng.normal(0, 0.05, a.shape), 0, 1)
    calls = []
    compute = metrics._ssim_map
    monkeypatch.setattr(metrics, "_ssim_map", lambda *args: calls.append(1) or compute(*args))
    score, full = metrics.ssim_map(a, b)
    full[:] = -1.0
    again, full2 = metrics.ssim_map(a.copy(), b.copy())
    assert (again, len(calls)) == (score, 1)
    assert np.array_equal(full2, compute(metrics._finite(a), metrics._finite(b), 1.0)[1])
    assert metrics.ssim(a, a) == 1.0 and len(calls) == 2


@pytest.mark.parametrize("tol", [Tolerance(), Tolerance(levels=0, share=0.0),
                                 Tolerance(share=0.05, hard=40),
                                 Tolerance(levels=1, share=0.01, ssim_min=0.99)])
def test_the_searchs_verdict_is_the_checks(tol):
    """tolerated (what the cause search asks of each render, without FLIP) passes exactly
    the pairs judge_deterministic passes: 5 of 100 pixels off by 51 levels fail 0.5% and
    pass 5%, but not a hard limit of 40; one level everywhere passes one level and fails
    zero; a checkerboard of one level up and down passes the levels and fails an SSIM
    minimum of 0.99 (flat against a standard deviation of 1/255: about 0.98)."""
    a = np.full((10, 10, 3), 0.5, np.float32)
    five = a.copy()
    five[0, :5] = 0.7
    level = a + np.float32(1 / 255)
    checker = a + np.where((np.indices((10, 10)).sum(axis=0) % 2 == 0)[..., None],
                           np.float32(1 / 255), np.float32(-1 / 255))
    expected = {
        (0.005, 1, None, None): [True, False, True, True],
        (0.0, 0, None, None): [True, False, False, False],
        (0.05, 1, 40, None): [True, False, True, True],
        (0.01, 1, None, 0.99): [True, False, True, False],
    }[(tol.share, tol.levels, tol.hard, tol.ssim_min)]
    for b, want in zip((a.copy(), five, level, checker), expected):
        assert judge_deterministic("color", a, b, tol).passed == want
        assert tolerated(a, b, tol) == want
