"""Image metrics: plain functions over float arrays, like skimage.metrics.

Images are (h, w) or (h, w, 3) float arrays of one image kind: colors, normals values (n+1)/2 or
depth values (t-min)/(max-min). The course never clamps these floats, but its 8-bit output shows
only [0, 1] (and NaN, inf and FLT_MAX-sized values as black), so the float metrics compare the
values as shown: non-finite and huge values as 0, the rest clipped to [0, 1]. A color of 7 and
one of 9 look the same and count as equal; data_range is therefore 1 for every image kind.
"""
from __future__ import annotations

import numpy as np

from ..records import ImageMetrics

# Wang et al. 2004 (the SSIM paper's settings): 11x11 Gaussian window of sigma 1.5, population
# covariance, K1 = 0.01, K2 = 0.03.
SSIM_SETTINGS = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False)


def _shown_mask(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(c·255 in float32, whether the course's int conversion keeps it): NaN, ±inf and values
    outside the int32 range become INT_MIN, i.e. black."""
    with np.errstate(all="ignore"):
        v = np.asarray(a, np.float32) * np.float32(255.0)
        return v, np.isfinite(v) & (v >= -(2.0**31)) & (v < 2.0**31)


def _finite(a: np.ndarray) -> np.ndarray:
    """The values as shown, before the 8-bit rounding: what turns black is 0, the rest is
    clipped to [0, 1]."""
    _, ok = _shown_mask(a)
    with np.errstate(invalid="ignore"):
        return np.clip(np.where(ok, np.asarray(a, np.float64), 0.0), 0.0, 1.0)


def displayed(a: np.ndarray) -> np.ndarray:
    """What a viewer of the 8-bit image sees, as floats in [0, 1]: the course quantisation."""
    v, ok = _shown_mask(a)
    return np.clip(np.where(ok, np.trunc(np.where(ok, v, 0)), 0), 0, 255) / 255.0


def bytes8(a: np.ndarray) -> np.ndarray:
    return np.round(displayed(a) * 255).astype(np.int16)


_SSIM_MEMO: dict[tuple, tuple[float, np.ndarray]] = {}
_SSIM_MEMO_SIZE = 8  # a case's kinds: its verdicts and then its pictures ask for each map


def ssim_map(a: np.ndarray, b: np.ndarray, data_range: float = 1.0) -> tuple[float, np.ndarray]:
    """SSIM and its per-pixel map. A case's verdict (compare) and its pictures (the SSIM map)
    ask for the same pair: the last few results are kept by the images' content, so each map
    is computed once (a digest of two 128x128 images costs a hundredth of the map)."""
    import hashlib

    a, b = _finite(a), _finite(b)
    key = (a.shape, b.shape, data_range, hashlib.blake2b(a.tobytes()).digest(),
           hashlib.blake2b(b.tobytes()).digest())
    if key not in _SSIM_MEMO:
        if len(_SSIM_MEMO) >= _SSIM_MEMO_SIZE:
            del _SSIM_MEMO[next(iter(_SSIM_MEMO))]
        _SSIM_MEMO[key] = _ssim_map(a, b, data_range)
    score, full = _SSIM_MEMO[key]
    return score, full.copy()


def _ssim_map(a: np.ndarray, b: np.ndarray, data_range: float) -> tuple[float, np.ndarray]:
    from skimage.metrics import structural_similarity

    channel_axis = 2 if a.ndim == 3 else None
    win = 11 if min(a.shape[:2]) >= 11 else (min(a.shape[:2]) // 2) * 2 - 1
    if win < 3:
        # SSIM needs a window of at least 3x3; tiny images fall back to exact equality.
        same = float(np.array_equal(a, b))
        return same, np.full(a.shape[:2], same)
    score, full = structural_similarity(a, b, data_range=data_range, channel_axis=channel_axis,
                                        full=True, win_size=win, **SSIM_SETTINGS)
    if full.ndim == 3:
        full = full.mean(axis=2)
    return float(score), full


def ssim(a: np.ndarray, b: np.ndarray, data_range: float = 1.0) -> float:
    return ssim_map(a, b, data_range)[0]


def psnr(a: np.ndarray, b: np.ndarray, data_range: float = 1.0) -> float:
    mse = float(np.mean((_finite(a) - _finite(b)) ** 2))
    return float("inf") if mse == 0 else float(10.0 * np.log10(data_range**2 / mse))


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((_finite(a) - _finite(b)) ** 2)))


def mean_abs_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.mean(np.abs(_finite(a) - _finite(b))))


def max_abs_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(_finite(a) - _finite(b)), initial=0.0))


def share_off_by_more_than_one_level(a: np.ndarray, b: np.ndarray) -> float:
    """Share of 8-bit pixels (any channel) whose bytes differ by more than 1."""
    d = np.abs(bytes8(a) - bytes8(b))
    if d.ndim == 3:
        d = d.max(axis=2)
    return float(np.mean(d > 1))


def share_equal_bytes(a: np.ndarray, b: np.ndarray) -> float:
    """Share of 8-bit pixels equal in every channel."""
    d = bytes8(a) != bytes8(b)
    if d.ndim == 3:
        d = d.any(axis=2)
    return float(np.mean(~d))


def mean_brightness_change(a: np.ndarray, b: np.ndarray) -> float:
    """Mean displayed brightness of b relative to a, in percent (positive: b is brighter)."""
    ma, mb = float(displayed(a).mean()), float(displayed(b).mean())
    if ma == 0:
        return 0.0 if mb == 0 else float("inf")
    return 100.0 * (mb - ma) / ma


_flip_threads_set = False


def _flip_on_one_thread() -> None:
    """FLIP's OpenMP threads compete with the renderers' Dr.Jit threads (and with other case
    workers) for the same cores: measured 94-112 ms a 128x128 call under that contention,
    29-52 ms on one thread. Set through the package's own bundled libgomp, once, so that the
    environment of the processes we start (a candidate's OMP_NUM_THREADS) stays untouched."""
    global _flip_threads_set
    if _flip_threads_set:
        return
    _flip_threads_set = True
    import ctypes
    from pathlib import Path

    import flip_evaluator

    libs = Path(flip_evaluator.__file__).parent.parent / "flip_evaluator.libs"
    for lib in sorted(libs.glob("libgomp*.so*")):  # already loaded by the extension
        try:
            ctypes.CDLL(str(lib)).omp_set_num_threads(1)
        except (OSError, AttributeError):
            pass  # another build without it: FLIP keeps its default threads


def flip(a: np.ndarray, b: np.ndarray) -> float:
    """Mean FLIP error (NVIDIA's perceptual metric, flip-evaluator) of b against a, on the 8-bit
    images as a viewer sees them: the bytes as sRGB, i.e. LDR input; gray is replicated.
    Byte-identical images are 0 without a call: FLIP's error map is a function of the two
    pictures' per-pixel difference, 0 wherever they agree."""
    import flip_evaluator

    def rgb(d: np.ndarray) -> np.ndarray:
        d = d.astype(np.float32)
        return np.ascontiguousarray(np.repeat(d[..., None], 3, axis=2) if d.ndim == 2 else d)

    da, db = displayed(a), displayed(b)
    if da.shape == db.shape and np.array_equal(da, db):
        return 0.0
    _flip_on_one_thread()
    try:
        _, mean, _ = flip_evaluator.evaluate(rgb(da), rgb(db), "LDR", applyMagma=False)
    except SystemExit as e:  # the package exits the process on arguments it rejects
        raise ValueError(f"FLIP rejected the images: {e}") from None
    return float(mean)


def compare(a: np.ndarray, b: np.ndarray, data_range: float = 1.0) -> ImageMetrics:
    """Every metric of b against a (a is the reference)."""
    return ImageMetrics(
        ssim=ssim(a, b, data_range), psnr=psnr(a, b, data_range), rmse=rmse(a, b),
        mean_abs=mean_abs_error(a, b), max_abs=max_abs_error(a, b),
        off_by_more_than_one=share_off_by_more_than_one_level(a, b),
        equal_bytes=share_equal_bytes(a, b),
        brightness_change_pct=mean_brightness_change(a, b), flip=flip(a, b),
    )
