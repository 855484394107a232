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


def difference(reference: np.ndarray, image: np.ndarray) -> tuple[np.ndarray, float]:
    """|shown(image) - shown(reference)|, max over channels, and the heatmap's scale: the
    largest difference, at least one 8-bit level."""
    d = np.abs(displayed(image) - displayed(reference))
    if d.ndim == 3:
        d = d.max(axis=2)
    return d, max(float(d.max(initial=0.0)), 1.0 / 255.0)


def save_heatmap(path: Path, d: np.ndarray, scale: float) -> None:
    """A difference mapped from 0 to scale."""
    _save(path, colormap(d / scale))


def diff_heatmap(path: Path, reference: np.ndarray, image: np.ndarray) -> float:
    """The difference's heatmap; returns its scale."""
    d, scale = difference(reference, image)
    save_heatmap(path, d, scale)
    return scale


# The overview matrix shows two thumbnails a case at 44 CSS pixels: they are made at twice
# that (high-density screens), not left to the browser to shrink a full image, which costs the
# page the full files and, nearest-neighbour as its images are drawn, drops pixels.
THUMB_PX = 88


def thumb_shape(shape: tuple[int, ...]) -> tuple[int, int] | None:
    """(h, w) of an image's thumbnail, its longer side THUMB_PX; None where the image is no
    larger (it is its own thumbnail)."""
    h, w = shape[:2]
    if max(h, w) <= THUMB_PX:
        return None
    return max(1, h * THUMB_PX // max(h, w)), max(1, w * THUMB_PX // max(h, w))


def _pooled(a: np.ndarray, shape: tuple[int, int], ufunc: np.ufunc) -> np.ndarray:
    """a reduced by `ufunc` over the blocks of a shape[0] x shape[1] grid (blocks of
    floor(i*h/n)..floor((i+1)*h/n)-1, none empty as n <= h)."""
    for axis, n in enumerate(shape):
        a = ufunc.reduceat(a, np.arange(n) * a.shape[axis] // n, axis=axis)
    return a


def save_thumbnail(path: Path, image: np.ndarray, shape: tuple[int, int]) -> None:
    """The 8-bit image averaged over each thumbnail pixel's block."""
    v = displayed(image)
    sums = _pooled(v, shape, np.add)
    counts = _pooled(np.ones(v.shape[:2]), shape, np.add)
    mean = sums / (counts[..., None] if v.ndim == 3 else counts)
    q = np.round(mean * 255).astype(np.uint8)
    _save(path, np.repeat(q[..., None], 3, axis=2) if q.ndim == 2 else q)


def save_diff_thumbnail(path: Path, d: np.ndarray, scale: float,
                        shape: tuple[int, int]) -> None:
    """The difference's largest value in each thumbnail pixel's block, on the full heatmap's
    scale: a single differing pixel still shows."""
    _save(path, colormap(_pooled(d, shape, np.maximum) / scale))


def save_gray_map(path: Path, values: np.ndarray) -> None:
    """An SSIM map, [0, 1] through the colormap (SSIM below 0 is shown as 0)."""
    _save(path, colormap(values))
