"""Named findings: why a failing image differs from the reference, not only by how much.

Plain functions over the 8-bit images of one kind (int arrays (h, w, 3) of bytes, gray depth
replicated, as `as_bytes` makes them): each returns a Finding (a code, a one-line message with
the numbers and, where one helps, an evidence image: the reference changed the way the finding
says) or None. Output-level findings explain the whole image by one change of the reference
(a flip, a channel order, a brightness scale, ...); feature-level findings compare the flag-on
minus flag-off differences of both renderers (a flag that changes nothing, missing shadows, one
mirror bounce too few). `diagnose` runs the output-level ones in order of specificity.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ..records import FindingRecord
from . import metrics, thresholds
from .filter_fit import COURSE_FILTER, fit_kernel
from .verdict import as_values

# A model of the candidate applied to the reference's bytes (not its floats) is off by a level
# or two where the model is steep (gamma near black, a 2x scale doubles the quantisation step):
# an expected image explains the candidate when at most MODEL_SHARE of its pixels are more than
# MODEL_LEVELS off (silhouette and shadow-edge pixels where two renderers round differently).
MODEL_LEVELS = 3
MODEL_SHARE = 0.02
# An output-level change is named only where it fits the candidate this many times better
# than the unchanged reference: where the reference nearly fits too (a nearly symmetric
# scene's flip against an image with a few wrong pixels), the change explains nothing.
CLEAR_MISFIT = 2.0
# Values darker than this take no part in the brightness fit: their ratio is all quantisation.
LIT_LEVEL = 8
# A brightness ratio closer to 1 than this is not a scale bug (two correct renderers differ by
# well under 1% in mean brightness on every bundled scene).
SCALE_MIN = 0.03
# z of a two-sided 95% interval.
Z95 = 1.96
# The course writes linear values; a gamma-encoded image is 255 * v^(1/GAMMA).
GAMMA = 2.2
# Of the pixels the reference shadows, the share lit in the candidate that names missing
# shadows (half: less is an offset or acne problem, not shadows that are not traced).
SHADOW_MISSING_SHARE = 0.5
# Of the pixels the reference mirrors, the share a candidate must get wrong for its mirrors
# to be named, with at most OUTSIDE_SHARE of its differing pixels elsewhere (silhouettes).
MIRROR_SHARE = 0.1
OUTSIDE_SHARE = 0.1
# Of the pixels the reference lights, the share the candidate shadows that names acne (a
# correct shadow ray differs from the reference's only at shadow edges, far under 2%).
ACNE_SHARE = 0.02


@dataclass(frozen=True)
class Finding:
    """A named explanation of a failing image, with the picture that shows it and the numbers
    its message holds (for findings built on this one); `record()` is what is kept of it."""

    code: str
    message: str
    evidence: np.ndarray | None = None  # (h, w, 3) bytes that show what the finding says
    numbers: tuple[float, ...] = ()  # the message's numbers, for findings built on this one
    # named by the model of one bug (a shading model), not by where or how much the images
    # differ: it goes before the geometry-level findings
    specific: bool = False
    # a symptom's: the share of the image's pixels that differ outside the region it accounts
    # for (None: its model is fitted to the whole image); it leads only where that is within
    # the verdict's FAIL_SHARE, else it is a hint: its observation without the question
    unexplained: float | None = None
    question: str = ""  # asked only where it leads: "is every light's shadow ray traced?"
    # a located finding's: the starter functions it leaves; a cause's where the images cannot
    # tell it from a mistake in another function: its function and those
    functions: tuple[str, ...] = ()

    @property
    def explains(self) -> bool:
        return self.unexplained is None or self.unexplained <= thresholds.FAIL_SHARE

    def hint(self) -> Finding:
        """The observation alone, for a symptom that does not explain the image."""
        return replace(self, question="")

    def record(self) -> FindingRecord:
        """What check.json and the pages keep of it: the code and the message."""
        return FindingRecord(self.code, f"{self.message}: {self.question}" if self.question
                             else self.message, self.functions or None)


# A jittered image "fits" an explanation when its mean error against it is about the
# reference's own noise: within this ratio, or this many levels apart (two 16-sample errors of
# one renderer agree within ~20% where noise covers many pixels; a few noisy edge pixels make
# errors of a few tenths of a level, where only the absolute allowance is meaningful).
NOISE_RATIO = 1.6
NOISE_LEVELS = 0.5


@dataclass(frozen=True)
class Fit:
    """Whether an expected image explains the candidate's. Deterministic images: at most
    MODEL_SHARE of the pixels more than MODEL_LEVELS off. Jittered ones (against the mean of
    the reference's distribution): a mean error of the size of the reference's own 16-sample
    error, `noise` levels (within NOISE_RATIO, or NOISE_LEVELS apart)."""

    noise: float | None = None
    # the unchanged reference's misfit: a change must fit CLEAR_MISFIT times better than that
    reference_misfit: float = float("inf")

    def misfit(self, expected: np.ndarray, got: np.ndarray) -> float:
        """The error of expected against got as a multiple of what fits (<= 1: fits)."""
        d = np.abs(expected - got)
        if self.noise is None:
            return float(np.mean(d.max(axis=2) > MODEL_LEVELS)) / MODEL_SHARE
        return float(d.mean()) / (NOISE_RATIO * self.noise + NOISE_LEVELS)

    def __call__(self, expected: np.ndarray, got: np.ndarray) -> bool:
        misfit = self.misfit(expected, got)
        return misfit <= 1 and CLEAR_MISFIT * misfit < self.reference_misfit


def as_bytes(image: np.ndarray) -> np.ndarray:
    """An image of any kind as the course's 8-bit output: int (h, w, 3), gray replicated."""
    b = metrics.bytes8(as_values(image)).astype(np.int32)
    return np.repeat(b[..., None], 3, axis=2) if b.ndim == 2 else b


def differs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per pixel, whether any channel differs by more than the verdict's per-pixel tolerance."""
    return np.abs(a - b).max(axis=2) > thresholds.PIXEL_LEVELS


# --- output level: one change of the reference explains the candidate ------------------------
# (code, change, message); a change returns None where it does not apply (a transpose of a
# non-square image). Where a pixel's value lands (the pixel a camera ray's ndc is made from,
# the pixel it is written to) is Renderer::Render's alone of the functions a student fills in:
# the starter's camera and image are given.
GEOMETRIC: list[tuple[str, Callable[[np.ndarray], np.ndarray | None], str]] = [
    ("flipped_vertical", lambda r: r[::-1],
     "Renderer::Render: your image is upside down: it matches the reference flipped "
     "vertically (is row 0 the top of the image?)"),
    ("flipped_horizontal", lambda r: r[:, ::-1],
     "Renderer::Render: your image is mirrored left-right: it matches the reference flipped "
     "horizontally (is x pointing right?)"),
    ("transposed", lambda r: r.transpose(1, 0, 2) if r.shape[0] == r.shape[1] else None,
     "Renderer::Render: your image is transposed: it matches the reference with rows and "
     "columns swapped (are x and y exchanged?)"),
]


def geometric(ref: np.ndarray, got: np.ndarray, fit: Fit) -> Finding | None:
    """flipped_vertical, flipped_horizontal or transposed: the first whose change fits."""
    for code, change, message in GEOMETRIC:
        expected = change(ref)
        if expected is not None and fit(expected, got):
            return Finding(code, message, expected)
    return None


def channel_order(ref: np.ndarray, got: np.ndarray, fit: Fit) -> Finding | None:
    """A permutation of the reference's R, G, B that fits: the candidate's channel order."""
    for order in itertools.permutations(range(3)):
        if order == (0, 1, 2):
            continue
        expected = ref[..., list(order)]
        if fit(expected, got):
            names = "".join("RGB"[i] for i in order)
            return Finding("channel_order",
                           f"your channels are in the order {names}: your R, G, B are the "
                           f"reference's {', '.join(names)} (channels swapped when writing?)",
                           expected)
    return None


def scale_fit(ref: np.ndarray, got: np.ndarray) -> tuple[float, float] | None:
    """Least-squares ratio k of got to ref over lit, unsaturated values, and the half width
    of its 95% interval; None without such values."""
    use = (ref >= LIT_LEVEL) & (got < 255) & (ref < 255)
    r, c = ref[use].astype(np.float64), got[use].astype(np.float64)
    if r.size < 2:
        return None
    k = float(np.dot(r, c) / np.dot(r, r))
    residual = c - k * r
    se = float(np.sqrt(np.dot(residual, residual) / (r.size - 1) / np.dot(r, r)))
    return k, Z95 * se


def brightness_scale(ref: np.ndarray, got: np.ndarray, fit: Fit,
                     filtered: bool = False) -> Finding | None:
    """The candidate is the reference times a constant (clipped at 255)."""
    found = scale_fit(ref, got)
    if found is None or abs(found[0] - 1) < SCALE_MIN:
        return None
    k, half = found
    expected = np.clip(np.floor(ref * k), 0, 255).astype(np.int32)
    if fit.noise is not None:  # a jittered image's noise is scaled with it
        fit = replace(fit, noise=fit.noise * k)
    if not fit(expected, got):
        return None
    hint = ": do the filter weights sum to 1?" if filtered else ""
    return Finding("brightness_scale",
                   f"your image is {k:.2f}x as bright as the reference "
                   f"({k - half:.2f}-{k + half:.2f}){hint}", expected,
                   (k, k - half, k + half))


def gamma_encoded(ref: np.ndarray, got: np.ndarray, fit: Fit) -> Finding | None:
    """The candidate is 255 * (reference/255)^(1/2.2): gamma-encoded instead of linear."""
    v = np.where(ref > 0, (ref + 0.5) / 255.0, 0.0)  # black stays black
    expected = np.floor(255.0 * v ** (1 / GAMMA)).astype(np.int32)
    if not fit(expected, got):
        return None
    return Finding("gamma_encoded",
                   f"your image is gamma-encoded: it matches 255*(reference/255)^(1/{GAMMA:g}); "
                   "the course writes linear values, without sRGB or gamma", expected)


def constant_offset(ref: np.ndarray, got: np.ndarray, fit: Fit) -> Finding | None:
    """The candidate is the reference plus a constant number of levels (clipped)."""
    use = (ref > 0) & (ref < 255) & (got > 0) & (got < 255)
    if not use.any():
        return None
    offset = int(np.median(got[use] - ref[use]))
    if abs(offset) <= thresholds.PIXEL_LEVELS:
        return None
    expected = np.clip(ref + offset, 0, 255)
    if not fit(expected, got):
        return None
    return Finding("constant_offset",
                   f"your image is {offset:+d} levels off the reference everywhere (a constant "
                   "added to every value: an ambient term counted twice?)", expected)


def quantisation(reference: np.ndarray, got: np.ndarray) -> Finding | None:
    """The candidate rounds the float values where the course truncates them (needs the
    reference's floats): a byte 1 above the reference's exactly where the fraction was >= .5.
    Off by one level only, so visible only with --tolerance 0."""
    if reference.dtype == np.uint8:
        return None
    ref = as_bytes(reference)
    v = metrics._finite(reference).astype(np.float32) * np.float32(255.0)
    rounded = np.clip(np.floor(v + np.float32(0.5)), 0, 255).astype(np.int32)
    if rounded.ndim == 2:
        rounded = np.repeat(rounded[..., None], 3, axis=2)
    up = rounded != ref
    if not up.any() or np.mean((rounded != got).any(axis=2)) > thresholds.FAIL_SHARE:
        return None
    return Finding("quantisation",
                   f"your bytes are rounded where the course truncates (int(255*v)): "
                   f"{np.mean(up):.1%} of the values are 1 level above the reference's, all "
                   "where the fraction was >= .5", rounded)


def normals_mapping(ref: np.ndarray, got: np.ndarray, fit: Fit) -> Finding | None:
    """Normals written as n*255 (clipped) or |n|*255 instead of (n+1)/2*255."""
    n = 2.0 * (ref + 0.5) / 255.0 - 1.0
    for name, values in (("n*255 clipped to 0..255", n), ("|n|*255", np.abs(n))):
        expected = np.clip(np.floor(values * 255.0), 0, 255).astype(np.int32)
        if fit(expected, got):
            return Finding("normals_mapping",
                           f"your normals image is {name}, not (n+1)/2*255: negative "
                           "components do not map to 0..127", expected)
    return None


def depth_mapping(ref: np.ndarray, got: np.ndarray, fit: Fit,
                  reference: np.ndarray | None = None) -> Finding | None:
    """A depth image with its range inverted (near is dark in the course, bright in yours), or,
    from the reference's floats, not clamped: bytes wrapped as C's (unsigned char)(int)(255*v)."""
    expected = 255 - ref
    if fit(expected, got):
        return Finding("depth_mapping",
                       "your depth image is inverted: it matches 255 - the reference (the "
                       "course writes (t-min)/(max-min): near is dark)", expected)
    if reference is None or reference.dtype == np.uint8 or reference.ndim != 2:
        return None  # clamped bytes keep no trace of where the values wrapped
    expected, outside = wrapped_bytes(reference)
    if not outside.any() or not fit(expected, got):
        return None
    return Finding("depth_mapping",
                   f"your depth image is not clamped to [0, 1]: it matches the reference's "
                   f"(t-min)/(max-min) written as (unsigned char)(int)(255*v), which wraps "
                   f"on the {outside.mean():.1%} of the pixels outside the -depth range",
                   expected, (float(outside.mean()),))


def wrapped_bytes(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """float32 values as (unsigned char)(int)(255.0f*v) with x86 conversion (NaN, inf and
    values outside int32 give INT_MIN, whose low byte is 0), replicated to (h, w, 3); and
    where that int is outside 0..255, so that the bytes wrap instead of clamping."""
    with np.errstate(all="ignore"):
        v = values.astype(np.float32) * np.float32(255.0)
        ok = np.isfinite(v) & (v >= -2.0**31) & (v < 2.0**31)
        i = np.trunc(np.where(ok, v, 0)).astype(np.int64)
    return np.repeat((i & 0xFF).astype(np.int32)[..., None], 3, axis=2), (i < 0) | (i > 255)


def diagnose(kind: str, filtered: bool, reference: np.ndarray, candidate: np.ndarray,
             fit: Fit = Fit()) -> list[Finding]:
    """The output-level findings of one failing kind, most specific first. `reference` may be
    floats (then rounding can be told from truncation); `filtered`: the request has -filter."""
    ref, got = as_bytes(reference), as_bytes(candidate)
    rounded = quantisation(reference, got) if fit.noise is None else None
    fit = replace(fit, reference_misfit=fit.misfit(ref, got))
    if fit.reference_misfit <= 1:
        # the reference itself fits within the model's tolerance: no change of it explains
        # the candidate better (a gray image fits every channel order), but rounding, below it
        return [rounded] if rounded else []
    checks: list[Callable[[], Finding | None]] = [
        lambda: rounded,
        lambda: geometric(ref, got, fit),
        lambda: channel_order(ref, got, fit),
        lambda: normals_mapping(ref, got, fit) if kind == "normals" else None,
        lambda: depth_mapping(ref, got, fit, reference) if kind == "depth" else None,
        lambda: gamma_encoded(ref, got, fit),
        lambda: constant_offset(ref, got, fit),
        lambda: brightness_scale(ref, got, fit, filtered),
    ]
    return [f for f in (check() for check in checks) if f is not None]


# --- feature level: the flag-on minus flag-off differences of both renderers ----------------
@dataclass(frozen=True)
class FlagPair:
    """One renderer's images of a case with a flag on and with it off (bytes, as_bytes)."""

    on: np.ndarray
    off: np.ndarray

    def changed(self) -> np.ndarray:
        return differs(self.on, self.off)


def no_effect(flag: str, ref: FlagPair, got: FlagPair) -> list[Finding]:
    """The flag changes nothing in the candidate's image while it changes the reference's;
    except for -jitter, the candidate's image without the flag must match the reference's
    (else what the flag would change may be missing for another reason: a highlight the
    candidate never draws cannot be shadowed). For -jitter jitter_no_noise comes first, the
    more specific name of the same observation."""
    if np.mean(got.changed()) > thresholds.FAIL_SHARE:
        return []
    if flag != "-jitter" and np.mean(differs(ref.off, got.off)) > thresholds.FAIL_SHARE:
        return []
    share = float(np.mean(ref.changed()))
    if share <= thresholds.FAIL_SHARE:
        return []
    found = [Finding("no_effect",
                     f"{flag} changes nothing in your image; in the reference it changes "
                     f"{share:.1%} of the pixels: is the flag read?", got.off)]
    if flag == "-jitter":
        found.insert(0, Finding("jitter_no_noise",
                                "Renderer::Render: your -jitter image equals your render "
                                f"without -jitter; in "
                                f"the reference jitter changes {share:.1%} of the pixels: are "
                                "the samples placed at random inside the pixel?", got.off))
    return found


def shadowed(pair: FlagPair) -> np.ndarray:
    """Pixels that turning shadows on darkens."""
    return (pair.off - pair.on).max(axis=2) > thresholds.PIXEL_LEVELS


def shadow_missing(ref: FlagPair, got: FlagPair) -> Finding | None:
    """Of the pixels the reference shadows, most are lit in the candidate; counted where
    both renders without shadows agree (elsewhere the candidate misses what would be
    shadowed, e.g. a highlight, for another reason), which must be most of them."""
    in_shadow = shadowed(ref) & ~differs(ref.off, got.off)
    if not in_shadow.any() or in_shadow.sum() < SHADOW_MISSING_SHARE * shadowed(ref).sum():
        return None
    lit = in_shadow & ~shadowed(got)
    share = float(lit.sum() / in_shadow.sum())
    if share < SHADOW_MISSING_SHARE:
        return None
    return Finding("shadow_missing",
                   f"{share:.0%} of the {int(in_shadow.sum())} pixels the reference shadows are "
                   "lit in your image", mask_image(lit),
                   unexplained=outside(ref.on, got.on, shadowed(ref)),
                   question="is every light's shadow ray traced?")


def shadow_acne(ref: FlagPair, got: FlagPair, unshadowed: np.ndarray | None = None
                ) -> Finding | None:
    """The candidate shadows pixels that the reference lights (self-shadowing speckle).
    `unshadowed` (from the reference's parts): the pixels none of whose shadow rays is
    blocked in the reference; a candidate darker only where some is has another bug (a term
    that shadows take away with the light's)."""
    lit = ~shadowed(ref) if unshadowed is None else ~shadowed(ref) & unshadowed
    acne = lit & shadowed(got)
    share = float(acne.sum() / max(lit.sum(), 1))
    if share < ACNE_SHARE:
        return None
    return Finding("shadow_acne",
                   f"your image shadows {share:.1%} of the pixels the reference lights "
                   f"({int(acne.sum())} pixels)", mask_image(acne),
                   # its model: darker where the reference is not (shadow rays blocked or
                   # not, the share's count leaves the former out)
                   unexplained=outside(ref.on, got.on, ~shadowed(ref) & shadowed(got)),
                   question="does the shadow ray start off the surface (p + epsilon*dir)?")


def reflection_depth(got: np.ndarray, bounces: int, ref_by_bounces: dict[int, np.ndarray],
                     fit: Fit = Fit()) -> Finding | None:
    """The candidate matches the reference rendered with one bounce fewer or more."""
    for n, image in sorted(ref_by_bounces.items()):
        if n != bounces and fit(image, got):
            fewer = "fewer" if n < bounces else "more"
            return Finding("reflection_depth",
                           f"your mirrors trace one bounce {fewer}: your -bounces {bounces} "
                           f"image matches the reference's -bounces {n}", image)
    return None


def reflection_acne(ref: np.ndarray, got: np.ndarray, mirrored: np.ndarray,
                    dull: np.ndarray) -> Finding | None:
    """The candidate differs on many of the pixels whose primary ray the reference mirrors
    (the parts' mirror depth > 0) and hardly anywhere else: reflected rays that hit the
    surface they leave. Counted on `dull` mirror pixels (no highlight of their own: a
    wrong highlight on a mirror is a shading bug)."""
    d = differs(ref, got)
    counted = mirrored & dull
    if not counted.any() or not d.any():
        return None
    share = float(d[counted].mean())
    # highlighted mirror pixels count as elsewhere: a wrong highlight on a mirror differs
    # there (measured: counting them as mirrored named 17 of 44 half-vector kinds acne)
    if share < MIRROR_SHARE or d[~counted].sum() > OUTSIDE_SHARE * d.sum():
        return None
    return Finding("reflection_acne",
                   f"your image differs on {share:.0%} of the {int(counted.sum())} pixels the "
                   "reference mirrors, and hardly elsewhere", mask_image(d & mirrored),
                   unexplained=float(np.mean(d & ~mirrored)),
                   question="does the reflected ray start off the surface (p + 0.01*R)?")


def filter_weights(scale: Finding, ref_off: np.ndarray, got_off: np.ndarray,
                   fit: Fit = Fit()) -> Finding | None:
    """A -filter image off by a brightness scale whose unfiltered render matches: the scale
    comes from the filter."""
    if scale.code != "brightness_scale" or not fit(ref_off, got_off) or \
            np.mean(differs(ref_off, got_off)) > thresholds.FAIL_SHARE:
        return None
    k, lo, hi = scale.numbers
    return Finding("filter_weights",
                   f"Renderer::Render: your -filter image is {k:.2f}x as bright as the "
                   f"reference ({lo:.2f}-"
                   f"{hi:.2f}), your unfiltered one is not: do the filter weights sum to 1?",
                   scale.evidence, scale.numbers)


# A fitted kernel explains the image where it leaves at most this RMS residual in levels (8-bit
# rounding of both images alone leaves ~0.4), and names another filter where a weight is this
# far from the course's (half a sixteenth).
FILTER_FIT_LEVELS = 1.5
FILTER_WEIGHT_OFF = 1.0 / 32.0


def filter_kernel(big: np.ndarray, got: np.ndarray) -> Finding | None:
    """The candidate's -filter weights (filter_fit.fit_kernel on the reference rendered
    without -filter at three times the size, `big`, bytes). Named where the fit explains the
    image and the weights are not the course's."""
    fit = fit_kernel(big, got)
    if fit is None or fit.rms > FILTER_FIT_LEVELS or \
            np.abs(fit.weights - COURSE_FILTER).max() < FILTER_WEIGHT_OFF:
        return None
    rows = "; ".join(" ".join(f"{16 * v:.2g}" for v in row) for row in fit.weights)
    return Finding("filter_kernel",
                   f"Renderer::Render: your -filter weights are [{rows}]/16, sum "
                   f"{fit.weights.sum():.2f} (least squares on the reference rendered at 3x "
                   f"without -filter, {fit.rms:.2f} levels RMS left); the course's are "
                   "[1 2 1; 2 4 2; 1 2 1]/16, sum 1", fit.image, tuple(fit.weights.ravel()),
                   specific=True)


def outside(ref: np.ndarray, got: np.ndarray, region: np.ndarray) -> float:
    """The share of the image's pixels that differ outside `region`."""
    return float(np.mean(differs(ref, got) & ~region))


def mask_image(mask: np.ndarray) -> np.ndarray:
    """A mask as an evidence image: white where set."""
    return np.repeat(np.where(mask, 255, 0)[..., None], 3, axis=2).astype(np.int32)
