"""Report pictures: the renders as the 8-bit course output, difference heatmaps with a stated
scale, SSIM maps. One colormap (a viridis approximation) for every map."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..judge.metrics import displayed

# viridis at 0, 0.25, 0.5, 0.75, 1 (linear interpolation between them)
_ANCHORS = np.array([[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]],
                    np.float64)


def colormap(values: np.ndarray) -> np.ndarray:
    """[0, 1] -> (..., 3) uint8 colors."""
    v = np.clip(np.nan_to_num(values, nan=0.0), 0.0, 1.0) * (len(_ANCHORS) - 1)
    i = np.minimum(v.astype(int), len(_ANCHORS) - 2)
    f = (v - i)[..., None]
    return np.round(_ANCHORS[i] * (1 - f) + _ANCHORS[i + 1] * f).astype(np.uint8)


def colormap_css() -> str:
    """The same colormap as a CSS gradient, for colorbars."""
    stops = ", ".join(f"rgb({r:.0f},{g:.0f},{b:.0f}) {100 * k / 4:.0f}%"
                      for k, (r, g, b) in enumerate(_ANCHORS))
    return f"linear-gradient(to right, {stops})"


def _save(path: Path, rgb: np.ndarray) -> None:
    from PIL import Image

    Image.fromarray(rgb, "RGB").save(path, format="PNG")


def save_png(path: Path, image: np.ndarray) -> None:
    """A float image as the course writes it (8-bit quantisation; gray for depth)."""
    q = np.round(displayed(image) * 255).astype(np.uint8)
    _save(path, np.repeat(q[..., None], 3, axis=2) if q.ndim == 2 else q)


def diff_heatmap(path: Path, reference: np.ndarray, image: np.ndarray) -> float:
    """|shown(image) - shown(reference)|, max over channels, mapped from 0 to the returned
    scale (the largest difference, at least one 8-bit level)."""
    d = np.abs(displayed(image) - displayed(reference))
    if d.ndim == 3:
        d = d.max(axis=2)
    scale = max(float(d.max(initial=0.0)), 1.0 / 255.0)
    _save(path, colormap(d / scale))
    return scale


def save_gray_map(path: Path, values: np.ndarray) -> None:
    """An SSIM map, [0, 1] through the colormap (SSIM below 0 is shown as 0)."""
    _save(path, colormap(values))
