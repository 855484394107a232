"""Geometry-level findings: where the differences of a failing image lie, read off the
reference's parts (judge.parts: the object hit by each pixel's primary ray, the shadow masks).

* normal_length: the candidate's decoded normals are not as long as the reference's on some
  objects (a transformed normal not renormalised);
* shifted: the candidate is the reference moved by a sub-pixel offset, found by
  cross-correlation against the reference resampled bilinearly (primary rays through x+0.5);
* edges_only: the candidate is the reference rescaled by (n-1)/n about the image centre (the
  pixel-centre convention ndc = 2*(x+0.5)/n - 1 instead of the course's 2*x/(n-1) - 1);
  for both, what the resampling leaves lies at silhouettes and shadow edges, where
  interpolating the reference cannot reproduce a hard edge;
* object:<index>: the differences are confined to one object; transformed_objects: to
  several objects, all transformed.
A resampling that explains changes away from edges is named before the objects, one whose
changes are all at edges anyway after them.
Images are int (h, w, 3) bytes as findings.as_bytes makes them.
"""
from __future__ import annotations

import numpy as np

from .findings import MODEL_LEVELS, Finding, differs, mask_image
from .parts import Parts

# Of the differing pixels, the share on one object (or on transformed objects) that confines
# the differences to it: silhouette pixels where two renderers round differently can fall on
# the neighbours.
OBJECT_SHARE = 0.9
# Decoded normals carry up to 1/255 of quantisation error per component (a length error under
# 0.015); a median length this far from the reference's is a different normal.
NORMAL_LENGTH_TOL = 0.05
# Sub-pixel offsets searched for a shift: every SHIFT_STEP pixel up to SHIFT_MAX each way (a
# larger shift is a camera or flip problem, not a pixel convention).
SHIFT_STEP = 0.125
SHIFT_MAX = 0.75
# The correlation's peak, dominated by edges, is refined by the smooth parts within this.
REFINE = 0.375
# A resampling explains the candidate when, away from edges (silhouettes and shadow edges),
# at most AWAY_SHARE of the pixels are more than MODEL_LEVELS off it: bilinear interpolation
# reproduces smooth shading and depth, never a hard edge (measured at 24x24: a right
# resampling leaves 0-4% there, a wrong one 10-60% where anything but edges changed).
AWAY_SHARE = 0.05
# ... and, where the candidate differs away from edges, removes all but RESIDUAL_GAIN of it.
RESIDUAL_GAIN = 0.5
# An offset under this (in pixels, both axes) is no shift.
SHIFT_MIN = 0.25
# The offset is searched in the SHIFT_WINDOW-pixel square (at most) with the most differing
# pixels: the shift is the image's, and 169 resamplings of an 800x800 image take a minute.
SHIFT_WINDOW = 96


def geometry_findings(kind: str, parts: Parts, ref: np.ndarray, got: np.ndarray
                      ) -> list[Finding]:
    """The geometry-level findings of one failing kind, most specific first."""
    changed = differs(ref, got)
    if not changed.any() or parts.images["object"].shape != ref.shape[:2]:
        return []
    band = edges(parts)
    # a resampling that explains changes away from edges comes first; one whose changes are
    # all at edges anyway only after the objects: a change of one small object's pixels is
    # nearly all edge pixels at small sizes, and it is the object's
    interior = (changed & ~band).sum() > AWAY_SHARE * (~band).sum()
    moved = resampled(band, ref, got, changed)
    found = [normal_length(parts, ref, got) if kind == "normals" else None,
             moved if interior else None,
             one_object(parts, changed) or transformed_objects(parts, changed),
             None if interior else moved]
    return [f for f in found if f is not None]


# --- normals --------------------------------------------------------------------------------
def decoded_length(normals: np.ndarray) -> np.ndarray:
    """|n| per pixel of a normals image of bytes (n+1)/2*255."""
    n = 2.0 * (normals + 0.5) / 255.0 - 1.0
    return np.sqrt((n * n).sum(axis=2))


def normal_length(parts: Parts, ref: np.ndarray, got: np.ndarray) -> Finding | None:
    """Objects whose candidate normals' median length is off the reference's."""
    obj = parts.images["object"]
    ref_len, got_len = decoded_length(ref), decoded_length(got)
    off = []
    for info in parts.objects:
        on = obj == info.index
        if on.any():
            r, g = float(np.median(ref_len[on])), float(np.median(got_len[on]))
            if abs(g - r) > NORMAL_LENGTH_TOL:
                off.append((abs(g - r), info, r, g))
    if not off:
        return None
    _, info, r, g = max(off, key=lambda o: o[0])
    more = f" (and {len(off) - 1} more objects)" if len(off) > 1 else ""
    mask = np.isin(obj, [o[1].index for o in off])
    return Finding("normal_length",
                   f"your normals on {info.describe()} have median length {g:.2f}, the "
                   f"reference's {r:.2f}{more}: is the normal renormalised after the "
                   "transform?", outlined(mask, mask), (g, r))


# --- resampled primary rays -----------------------------------------------------------------
def bilinear(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """image (h, w, c) at fractional positions x of its columns (one per output column) and y
    of its rows (top down; one per output row), clamped at the border. Separable: each row is
    interpolated once along x, then the rows along y, the same products and sums a pixel's
    four-tap formula makes, at a fraction of a gathered image's cost."""
    return _along_y(_along_x(image, x), y)


def _along_x(image: np.ndarray, x: np.ndarray) -> np.ndarray:
    """bilinear's first pass: every row of `image` at the fractional columns x."""
    x0, x1, fx = _taps(x, image.shape[1])
    fx = fx[None, :, None]
    return image[:, x0] * (1 - fx) + image[:, x1] * fx


def _along_y(rows: np.ndarray, y: np.ndarray) -> np.ndarray:
    """bilinear's second pass: the rows of _along_x's result at the fractional rows y."""
    y0, y1, fy = _taps(y, rows.shape[0])
    fy = fy[:, None, None]
    return rows[y0] * (1 - fy) + rows[y1] * fy


def _taps(at: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The two pixels on either side of each position along an axis of n pixels (clamped),
    and the position's fraction of the way from the first to the second."""
    at = np.clip(at, 0, n - 1)
    first = np.maximum(np.minimum(np.floor(at).astype(int), n - 2), 0)
    return first, np.minimum(first + 1, n - 1), at - first


def shifted_by(ref: np.ndarray, dx: float, dy: float) -> np.ndarray:
    """The reference as seen by pixels whose rays pass dx right and dy down of the course's."""
    h, w = ref.shape[:2]
    return bilinear(ref.astype(np.float64), np.arange(w) + dx, np.arange(h) + dy)


def rescaled(ref: np.ndarray) -> np.ndarray:
    """The reference as rays with ndc = 2*(x+0.5)/n - 1 see it: pixel x samples the course's
    x' = (x+0.5)(n-1)/n, a scale by (n-1)/n about the centre (n-1)/2, in both axes."""
    h, w = ref.shape[:2]
    return bilinear(ref.astype(np.float64), (np.arange(w) + 0.5) * (w - 1) / w,
                    (np.arange(h) + 0.5) * (h - 1) / h)


def best_shift(ref: np.ndarray, got: np.ndarray, away: np.ndarray) -> tuple[float, float]:
    """The sub-pixel offset (dx right, dy down) at which the shifted reference explains the
    candidate: the peak of the normalised cross-correlation, refined within REFINE pixels to
    the offset that leaves the fewest pixels more than MODEL_LEVELS off away from edges (then
    in all): edges dominate the correlation, the smooth parts tell the offset within a step.
    Images larger than SHIFT_WINDOW are searched in their window of most differences."""
    rows, cols = busiest_window(np.abs(ref - got).max(axis=2) > MODEL_LEVELS, SHIFT_WINDOW)
    ref, got, away = ref[rows, cols].astype(np.float64), got[rows, cols], away[rows, cols]
    h, w = ref.shape[:2]
    g = got.astype(np.float64) - got.mean()
    gg = (g * g).sum()
    steps = np.arange(-SHIFT_MAX, SHIFT_MAX + SHIFT_STEP / 2, SHIFT_STEP)
    grid = [(float(dx), float(dy)) for dy in steps for dx in steps]
    # shifted_by's first pass depends on dx alone: made once per column of the grid
    along_x = {dx: _along_x(ref, np.arange(w) + dx) for dx, _ in grid[:len(steps)]}

    def shifted(at: tuple[float, float]) -> np.ndarray:
        return _along_y(along_x[at[0]], np.arange(h) + at[1])

    def correlation(at: tuple[float, float]) -> float:
        s = shifted(at)
        s -= s.mean()
        return float((s * g).sum() / (np.sqrt((s * s).sum() * gg) or 1.0))

    def left(at: tuple[float, float]) -> tuple[int, int]:
        off = np.abs(shifted(at) - got).max(axis=2) > MODEL_LEVELS
        return int((off & away).sum()), int(off.sum())

    peak = max(grid, key=correlation)
    near = [at for at in grid if max(abs(at[0] - peak[0]), abs(at[1] - peak[1])) <= REFINE]
    return min(near, key=left)


def busiest_window(mask: np.ndarray, side: int) -> tuple[slice, slice]:
    """The side x side square (or the whole extent, where smaller) holding most of `mask`,
    among squares placed every side/4 pixels."""
    h, w = mask.shape
    sh, sw = min(side, h), min(side, w)
    total = np.pad(mask.astype(np.int64).cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    step = max(side // 4, 1)
    starts = [(y, x) for y in sorted({*range(0, h - sh + 1, step), h - sh})
              for x in sorted({*range(0, w - sw + 1, step), w - sw})]

    def count(at: tuple[int, int]) -> int:
        y, x = at
        return int(total[y + sh, x + sw] - total[y, x + sw] - total[y + sh, x] + total[y, x])

    y, x = max(starts, key=count)
    return slice(y, y + sh), slice(x, x + sw)


def edges(parts: Parts) -> np.ndarray:
    """Pixels within a pixel of a change of the hit object or of a light's shadow mask."""
    shadow = parts.images["shadow"]  # (h, w, 0) without lights
    labels = [parts.images["object"]] + [shadow[:, :, i] for i in range(shadow.shape[2])]
    near = np.zeros(labels[0].shape, bool)
    for lab in labels:
        p = np.pad(lab, 1, mode="edge")
        h, w = lab.shape
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                near |= p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] != lab
    return near


def resampled(band: np.ndarray, ref: np.ndarray, got: np.ndarray, changed: np.ndarray
              ) -> Finding | None:
    """shifted or edges_only: of the resamplings of the reference that explain the candidate
    away from edges, the one that leaves the fewest pixels off there (then in all)."""
    away = int((~band).sum())
    away_changed = int((changed & ~band).sum())
    dx, dy = best_shift(ref, got, ~band)
    options = [("edges_only", rescaled(ref))]
    if max(abs(dx), abs(dy)) >= SHIFT_MIN:
        options.append(("shifted", shifted_by(ref, dx, dy)))
    fits = []
    for code, expected in options:
        left = np.abs(expected - got).max(axis=2) > MODEL_LEVELS
        n_away = int((left & ~band).sum())
        if n_away <= AWAY_SHARE * away and (n_away <= RESIDUAL_GAIN * away_changed or
                                            away_changed <= AWAY_SHARE * away):
            fits.append((n_away, int(left.sum()), code))
    if not fits:
        return None
    code = min(fits)[2]
    total = int(changed.sum())
    share = float((changed & band).sum() / total)
    evidence = outlined(changed, band)
    if code == "shifted":
        return Finding("shifted",
                       f"your image is the reference shifted by ({dx:+.2f}, {dy:+.2f}) pixels "
                       f"(x right, y down; by cross-correlation), {share:.0%} of the {total} "
                       "differing pixels at edges: do your primary rays pass through x+0.5 "
                       "with the course's 2*x/(w-1) - 1?", evidence, (dx, dy))
    return Finding("edges_only",
                   f"your image differs from the reference at silhouettes ({share:.0%} of the "
                   f"{total} differing pixels within a pixel of an edge) and elsewhere only as "
                   "the reference rescaled by (n-1)/n about its centre: is your ndc "
                   "2*(x+0.5)/w - 1 instead of the course's 2*x/(w-1) - 1?", evidence, (share,))


# --- objects --------------------------------------------------------------------------------
def one_object(parts: Parts, changed: np.ndarray) -> Finding | None:
    """object:<index>: at least OBJECT_SHARE of the differing pixels on one object."""
    obj = parts.images["object"]
    ids, counts = np.unique(obj[changed], return_counts=True)
    top = int(np.argmax(counts))
    index, count, total = int(ids[top]), int(counts[top]), int(changed.sum())
    if index < 0 or count < OBJECT_SHARE * total:
        return None
    on = obj == index
    return Finding(f"object:{index}",
                   f"the differences are confined to {parts.objects[index].describe()}: "
                   f"{count / total:.0%} of the {total} differing pixels, {count / on.sum():.0%} "
                   "of its pixels: is its material or normal the reference's?",
                   outlined(changed, on), (count / total, count / on.sum()))


def transformed_objects(parts: Parts, changed: np.ndarray) -> Finding | None:
    """At least OBJECT_SHARE of the differing pixels on transformed objects."""
    obj = parts.images["object"]
    moved = [o.index for o in parts.objects if o.transformed]
    on = np.isin(obj, moved)
    total = int(changed.sum())
    share = float((changed & on).sum() / total)
    if not moved or share < OBJECT_SHARE:
        return None
    which = sorted(set(obj[changed & on].tolist()))
    return Finding("transformed_objects",
                   f"the differences are confined to transformed objects: {share:.0%} of the "
                   f"{total} differing pixels are on objects {', '.join(map(str, which))} "
                   f"(of {len(moved)} transformed, {len(parts.objects)} in all): is the normal "
                   "renormalised after the transform?", outlined(changed, on), (share,))


def outlined(mask: np.ndarray, region: np.ndarray) -> np.ndarray:
    """Evidence: the mask white, the region's outline red where the mask is not set."""
    image = mask_image(mask)
    p = np.pad(region, 1, mode="edge")
    h, w = region.shape
    border = region & ~(p[:-2, 1:-1] & p[2:, 1:-1] & p[1:-1, :-2] & p[1:-1, 2:])
    image[border & ~mask] = (255, 0, 0)
    return image
