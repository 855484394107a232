"""Float images -> 8-bit pixels and files, with the course's quantisation rule (spec §8)."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from .scene.outputs import write_all, write_png_rgb8


def quantize(values: np.ndarray) -> np.ndarray:
    """Byte = clamp(int32(float32(c) * 255.0f), 0, 255) where the int conversion truncates with
    x86 semantics: NaN, ±inf and anything outside [-2^31, 2^31) become INT_MIN, so black."""
    with np.errstate(all="ignore"):
        v = values.astype(np.float32) * np.float32(255.0)
        # the same bytes in half the passes: below -2^31 (INT_MIN) and -inf clamp to 0 like any
        # negative value; NaN, +inf and >= 2^31 (INT_MIN too) fail the comparison and give 0;
        # the rest clamps to [0, 255] and truncates in the cast
        keep = v < np.float32(2.0**31)
        return np.where(keep, np.clip(v, np.float32(0), np.float32(255)),
                        np.float32(0)).astype(np.uint8)


def to_rgb8(image: np.ndarray) -> np.ndarray:
    """(h, w, 3) or (h, w) floats (row 0 = top) -> (h, w, 3) uint8; gray is replicated."""
    q = quantize(image)
    return np.repeat(q[..., None], 3, axis=2) if q.ndim == 2 else q


def png_writer(image: np.ndarray) -> Callable[[str], None]:
    # quantised in the writer: write_all runs the writers of an image set in threads
    return lambda tmp: write_png_rgb8(tmp, to_rgb8(image))


def write_png(path: Path, image: np.ndarray) -> None:
    write_all([(path, png_writer(image))])


def read_png(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))
