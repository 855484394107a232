"""Float images -> 8-bit pixels and files on the Mitsuba side (spec §8), written independently
of the tracer's image code so that a quantisation bug shows up as a difference.

Quantisation of a channel value c: v = c * 255.0f in float32 (may overflow to inf); convert to
int32 by truncation toward zero with x86 semantics (cvttss2si: NaN, ±inf and values outside
[-2^31, 2^31) give INT_MIN); clamp to [0, 255]. So 1.7 -> 255, 0.5 -> 127, -0.2 -> 0 and
huge, inf and NaN -> 0 (black). Arrays have row 0 at the top, as PNG files do (course y = 0, the
bottom row, is the file's last row).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

INT32_MIN = -(2 ** 31)


def to_bytes(values: np.ndarray) -> np.ndarray:
    """The course's quantisation of float values (any shape) to uint8."""
    with np.errstate(all="ignore"):
        scaled = np.asarray(values, dtype=np.float32) * np.float32(255.0)
        wide = scaled.astype(np.float64)  # exact: every float32 is a float64
        representable = np.isfinite(wide) & (wide >= -2.0 ** 31) & (wide < 2.0 ** 31)
        as_int = np.where(representable, np.trunc(np.where(representable, wide, 0.0)),
                          float(INT32_MIN))
    return np.clip(as_int, 0, 255).astype(np.uint8)


def rgb_bytes(image: np.ndarray) -> np.ndarray:
    """(h, w, 3) colour or normals, or (h, w) depth (written as gray) -> (h, w, 3) uint8."""
    q = to_bytes(image)
    if q.ndim == 2:
        q = np.stack([q, q, q], axis=-1)
    return q


def png_writer(image: np.ndarray) -> Callable[[str], None]:
    from PIL import Image

    pixels = rgb_bytes(image)
    return lambda tmp: Image.fromarray(pixels, "RGB").save(tmp, format="PNG")
