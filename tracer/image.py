"""Float images -> 8-bit pixels and files, with the course's quantisation rule (spec §8)."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from .scene.outputs import write_all

INT_MIN = np.int32(-(2**31))


def quantize(values: np.ndarray) -> np.ndarray:
    """Byte = clamp(int32(float32(c) * 255.0f), 0, 255) where the int conversion truncates with
    x86 semantics: NaN, ±inf and anything outside [-2^31, 2^31) become INT_MIN, so black."""
    with np.errstate(all="ignore"):
        v = values.astype(np.float32) * np.float32(255.0)
        in_range = np.isfinite(v) & (v >= np.float32(-(2.0**31))) & (v < np.float32(2.0**31))
        as_int = np.where(in_range, np.trunc(np.where(in_range, v, 0)), INT_MIN).astype(np.int64)
    return np.clip(as_int, 0, 255).astype(np.uint8)


def to_rgb8(image: np.ndarray) -> np.ndarray:
    """(h, w, 3) or (h, w) floats (row 0 = top) -> (h, w, 3) uint8; gray is replicated."""
    q = quantize(image)
    return np.repeat(q[..., None], 3, axis=2) if q.ndim == 2 else q


def png_writer(image: np.ndarray) -> Callable[[str], None]:
    from PIL import Image

    rgb = to_rgb8(image)
    return lambda tmp: Image.fromarray(rgb, "RGB").save(tmp, format="PNG")


def write_png(path: Path, image: np.ndarray) -> None:
    write_all([(path, png_writer(image))])


def read_png(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))
