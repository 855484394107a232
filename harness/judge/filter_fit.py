"""A -filter image's kernel, fitted: which weights of each pixel's 3x3 block of sub-pixel rays
give the candidate's pixels, by least squares against the reference rendered without -filter
at three times the size, and the same weights as a program would write them (small integers
over a divisor).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# The course's -filter: each pixel the weighted sum of its 3x3 block of sub-pixel rays.
COURSE_FILTER = np.array([[1.0, 2.0, 1.0], [2.0, 4.0, 2.0], [1.0, 2.0, 1.0]]) / 16.0
# samples the fit needs (unclipped pixels)
FILTER_FIT_MIN = 64
# The divisors a written kernel is looked for over (the course's 16, a box's 9, ...), and how
# far from a whole number each weight times the divisor may be: a fit on 8-bit images is good
# to about a hundredth of a sixteenth, so a random kernel passes with odds of 0.2^9 a divisor.
DIVISORS = range(1, 33)
WHOLE = 0.1


@dataclass(frozen=True)
class KernelFit:
    """The fitted weights (rows top-down, as the image's: `weights[0]` is the block's top
    row), the RMS residual in levels and the image the weights give (bytes)."""

    weights: np.ndarray
    rms: float
    image: np.ndarray


@dataclass(frozen=True)
class WrittenKernel:
    """A kernel as a program writes it: whole-number weights (rows top-down) over a divisor."""

    weights: tuple[tuple[int, ...], ...]
    divisor: int


def fit_kernel(big: np.ndarray, got: np.ndarray) -> KernelFit | None:
    """The candidate's -filter weights, by least squares: its pixels (unclipped) against the
    3x3 blocks of the reference rendered without -filter at three times the size (`big`,
    bytes). None where the sizes do not match or too few pixels are unclipped."""
    h, w = got.shape[:2]
    if big.shape[0] != 3 * h or big.shape[1] != 3 * w:
        return None
    blocks = np.stack([big[r::3, c::3] for r in range(3) for c in range(3)],
                      axis=-1).astype(np.float64)  # (h, w, 3, 9), rows top-down
    y = got.astype(np.float64)
    keep = (y > 0) & (y < 255) & (blocks < 255).all(axis=-1)
    if keep.sum() < FILTER_FIT_MIN:
        return None
    x, y = blocks[keep], y[keep]
    weights, *_ = np.linalg.lstsq(x, y, rcond=None)
    rms = float(np.sqrt(np.mean((x @ weights - y) ** 2)))
    image = np.clip(np.rint(blocks @ weights), 0, 255).astype(np.int32)
    return KernelFit(weights.reshape(3, 3), rms, image)


def written(weights: np.ndarray) -> WrittenKernel | None:
    """The weights as whole numbers over a divisor (DIVISORS) that makes each within WHOLE of
    one: of those, the one that changes fewest of the course's constants (twice as bright is
    the course's weights over 8, not each weight doubled), then the smallest divisor. None
    where no divisor does."""
    course = np.rint(COURSE_FILTER * 16)
    found = []
    for divisor in DIVISORS:
        scaled = weights * divisor
        whole = np.rint(scaled)
        if np.abs(scaled - whole).max() <= WHOLE and whole.any():
            changes = int((whole != course).sum()) + (divisor != 16)
            found.append((changes, divisor, whole))
    if not found:
        return None
    _, divisor, whole = min(found, key=lambda f: f[:2])
    return WrittenKernel(tuple(tuple(int(v) for v in row) for row in whole), divisor)
