"""Shading-level findings: the candidate's color explained by the reference's Phong terms.

Per object of the reference's object image, the candidate's values are fitted by least squares
as a·ambient + b·diffuse + c·specular + c'·specular behind + d·reflection, the reference's
parts (judge/parts.py; "specular behind": where the light is behind the surface, N·L <= 0,
which the course lights too). A coefficient far from 1 names the term: `term_missing:<term>`
near 0, else `term_scaled:<term>`. Two other models compete with the scaled terms where they
leave half the residual: the ambient term once per unshadowed light (`term_scaled:ambient`,
the message says so), and the specular terms with another shininess (`shininess`, with the
exponent that fits best). An object none of them fits (more than GOOD_FIT_LEVELS of RMS
residual) gets no shading finding: its values are not made of the reference's terms.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .findings import Finding, mask_image
from .parts import Parts

TERMS = ("ambient", "diffuse", "specular", "specular_behind", "reflection")
# An object's fit needs MIN_VALUES channel values; a term takes part where TERM_VALUES of
# them are at least SIGNAL (a term under a level everywhere cannot be told from rounding; a
# small sphere's highlight covers a few pixels).
MIN_VALUES = 12
TERM_VALUES = 6
SIGNAL = 1.0 / 255.0
# Pixels an object needs in the image for a fit of its own.
MIN_PIXELS = 8
# A coefficient is "far from 1" when it is off by more than this and its 99.9% interval
# excludes 1 (two correct renderers fit within a few percent: their bytes differ by rounding).
TERM_TOLERANCE = 0.2
Z999 = 3.29
# Under this a term counts as missing rather than scaled.
MISSING = 0.25
# A fit with a coefficient outside this range explains nothing: no real program weighs a
# term negatively or by more than a few lights' worth (a failed fit gave 68428x where the
# program's Transform offset its rays), so its object gets no shading finding.
PLAUSIBLE = (-0.1, 8.0)
# An ambient coefficient this close to the number of lights (two or more) is the ambient term
# added once per light.
LIGHT_COUNT_TOLERANCE = 0.1
# 8-bit rounding: a byte b stands for (b + 0.5)/255 +- 0.5/255; the residual's floor
QUANTUM = 1.0 / 255.0 / np.sqrt(12.0)
# Shininess fit: exponents from a sixteenth to 16x the material's, geometric steps, outside
# SHININESS_RANGE of it (closer is the linear fit's rounding).
SHININESS_STEPS = 41
SHININESS_SPAN = 16.0
SHININESS_RANGE = (0.8, 1.25)
# An alternative model wins where its RMS residual is this many times smaller.
MODEL_GAIN = 2.0
# The best model must leave at most this RMS residual in levels (8-bit rounding alone is
# 0.29; silhouette pixels shared with another object add a little).
GOOD_FIT_LEVELS = 3.0

HINTS = {
    ("term_missing", "ambient"): "is ambient ⊙ kd added to every hit?",
    ("term_scaled", "ambient"): "is the ambient term added once per light instead of once?",
    ("term_missing", "diffuse"): "is max(N·L, 0)·I ⊙ kd added for every light?",
    ("term_scaled", "diffuse"): "light intensity, falloff or kd scaled?",
    ("term_missing", "specular"): "is the specular term rl^shininess·I ⊙ ks added?",
    ("term_scaled", "specular"): "ks or the light intensity scaled in the specular term?",
    ("term_missing", "specular_behind"):
        "the course does not gate the specular term by N·L > 0: is yours gated?",
    ("term_scaled", "specular_behind"): "is the specular term gated or scaled by N·L?",
    ("term_missing", "reflection"): "is ks ⊙ trace(reflected ray) added on mirrors?",
    ("term_scaled", "reflection"): "is the reflected color weighted by ks once?",
}


@dataclass(frozen=True)
class TermFit:
    """One object's best explanation: the model ("linear", "ambient_per_light" or
    "shininess"), its coefficient and standard error per term taking part, the exponent it
    used, and its residual RMS in levels."""

    object: int
    pixels: int
    model: str
    coefficients: dict[str, tuple[float, float]]
    rms_levels: float
    shininess: float | None = None


def term_columns(parts: Parts, where: np.ndarray, shininess: float | None = None,
                 ambient_per_light: bool = False) -> dict[str, np.ndarray]:
    """term -> (n, 3) float64 values of the pixels `where` is set on. `shininess`: the
    specular terms recomputed with that exponent (the clamped R·L raised to it, as spec §6
    has it); `ambient_per_light`: the ambient term once per light whose shadow ray is not
    blocked."""
    im = {name: v[where] for name, v in parts.images.items()}
    unblocked = ~im["shadow"].astype(bool)
    front = im["cos_nl"] > 0
    specular = im["specular"].astype(np.float64)
    if shininess is not None:
        ks = np.array([m.specular for m in parts.scene.materials], np.float64)
        ks_hit = ks[np.maximum(im["material"], 0)][:, None, :]
        power = im["cos_rl"].astype(np.float64) ** shininess
        specular = power[..., None] * im["intensity"] * ks_hit

    def lit(on: np.ndarray) -> np.ndarray:
        return np.where((unblocked & on)[..., None], specular, 0).sum(axis=1)

    ambient = im["ambient"].astype(np.float64)
    if ambient_per_light:
        ambient = ambient * unblocked.sum(axis=1)[:, None]
    return {"ambient": ambient,
            "diffuse": np.where(unblocked[..., None], im["diffuse"], 0).sum(
                axis=1, dtype=np.float64),
            "specular": lit(front), "specular_behind": lit(~front),
            "reflection": im["reflection"].astype(np.float64)}


def _samples(got: np.ndarray, columns: dict[str, np.ndarray]
             ) -> tuple[np.ndarray, np.ndarray, list[str]] | None:
    """Design matrix, targets and the terms taking part for one object's channel values
    (`got`: the candidate's (n, 3) bytes there) that neither image clips (the model below 1,
    the candidate below 255)."""
    model = sum(columns.values())
    use = (model >= 0) & (model < 1) & (got < 255)
    if len(got) < MIN_PIXELS or use.sum() < MIN_VALUES:
        return None
    terms = [t for t in TERMS if (columns[t][use] >= SIGNAL).sum() >= TERM_VALUES]
    if not terms:
        return None
    x = np.stack([columns[t][use] for t in terms], axis=1)
    y = (got[use] + 0.5) / 255.0
    return x, y, terms


def _least_squares(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Coefficients, their standard errors, and the residual sum of squares."""
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    residual = y - x @ coef
    rss = float(residual @ residual)
    dof = max(len(y) - x.shape[1], 1)
    sigma2 = max(rss / dof, QUANTUM ** 2)
    cov = sigma2 * np.linalg.pinv(x.T @ x)
    return coef, np.sqrt(np.maximum(np.diag(cov), 0.0)), rss


def _fit(parts: Parts, got: np.ndarray, index: int, model: str, shininess: float | None = None
         ) -> TermFit | None:
    where = parts.images["object"] == index
    columns = term_columns(parts, where, shininess, model == "ambient_per_light")
    found = _samples(got[where], columns)
    if found is None:
        return None
    x, y, terms = found
    coef, se, rss = _least_squares(x, y)
    return TermFit(index, int(where.sum()), model,
                   {t: (float(c), float(e)) for t, c, e in zip(terms, coef, se)},
                   float(np.sqrt(rss / len(y)) * 255.0), shininess)


def fit_object(parts: Parts, got: np.ndarray, index: int) -> TermFit | None:
    """The object's best explanation: the reference's terms scaled (linear), or with the
    ambient term once per unshadowed light, or with another shininess; an alternative wins
    where its RMS residual is MODEL_GAIN times smaller. None where too few
    values, or where even the best leaves more than GOOD_FIT_LEVELS of residual (the
    candidate's values are not made of the reference's terms there)."""
    linear = _fit(parts, got, index, "linear")
    if linear is None:
        return None
    best = linear
    if parts.images["shadow"].shape[2] > 1 or parts.images["shadow"].any():
        per_light = _fit(parts, got, index, "ambient_per_light")
        if per_light and "ambient" in per_light.coefficients and \
                per_light.rms_levels * MODEL_GAIN < best.rms_levels:
            best = per_light
    own = float(parts.scene.materials[parts.objects[index].material].shininess)
    if "specular" in linear.coefficients and own > 0:
        lo, hi = SHININESS_RANGE
        grid = own * SHININESS_SPAN ** np.linspace(-1, 1, SHININESS_STEPS)
        fits = [f for e in grid if not lo <= e / own <= hi
                and (f := _fit(parts, got, index, "shininess", float(e)))
                and "specular" in f.coefficients]
        shiny = min(fits, key=lambda f: f.rms_levels, default=None)
        if shiny and shiny.rms_levels * MODEL_GAIN < best.rms_levels:
            best = shiny
    return best if best.rms_levels <= GOOD_FIT_LEVELS else None


def _far(coef: float, se: float) -> bool:
    return abs(coef - 1) > TERM_TOLERANCE and abs(coef - 1) > Z999 * se


def shading_findings(parts: Parts, got: np.ndarray) -> list[Finding]:
    """One finding per code over all objects (the objects and their coefficients in the
    message), the one weighing most (pixels x how far off) first; an object explained by
    the ambient term per light (or scaled by the number of lights) or another shininess names
    that. Findings of those models, and of the specular term missing behind the surface, are
    `specific`: they name one bug, where a scaled term has many causes."""
    entries: dict[str, list[tuple[TermFit, float]]] = {}
    lights = parts.images["shadow"].shape[2]
    for info in parts.objects:
        fit = fit_object(parts, got, info.index)
        if fit is None or not all(PLAUSIBLE[0] <= c <= PLAUSIBLE[1]
                                  for c, _ in fit.coefficients.values()):
            continue
        if fit.model == "ambient_per_light":
            entries.setdefault("ambient_per_light", []).append((fit, np.inf))
        elif fit.model == "shininess":
            assert fit.shininess is not None  # the shininess model fits one
            entries.setdefault("shininess", []).append((fit, fit.shininess))
        for term, (coef, se) in fit.coefficients.items():
            if term == "ambient" and lights > 1 and abs(coef - lights) < LIGHT_COUNT_TOLERANCE:
                entries.setdefault("ambient_per_light", []).append((fit, coef))
            elif _far(coef, se):
                kind = "term_missing" if coef < MISSING else "term_scaled"
                entries.setdefault(f"{kind}:{term}", []).append((fit, coef))
    found = []
    for code, fits in entries.items():
        objects = [f.object for f, _ in fits]
        weight = sum(f.pixels for f, _ in fits) * (
            2.0 if code in ("ambient_per_light", "shininess") else
            max(min(abs(c - 1), 1.0) for _, c in fits))
        found.append((weight, _finding(parts, code, fits, _objects_mask(parts, objects))))
    ordered = [f for _, f in sorted(found, key=lambda wf: -wf[0])]
    # another shininess explains the specular terms scaled or missing on other objects too
    shiny = [f for f in ordered if f.code == "shininess"]
    ordered = shiny + [f for f in ordered if f.code != "shininess"] if shiny and any(
        f.code.endswith(("specular", "specular_behind")) for f in ordered) else ordered
    unique: dict[str, Finding] = {}
    for f in ordered:
        unique.setdefault(f.code, f)
    return list(unique.values())


def _finding(parts: Parts, code: str, fits: list[tuple[TermFit, float]],
             evidence: np.ndarray) -> Finding:
    describe = parts.objects
    if code == "ambient_per_light":
        # the linear fit's coefficient where it found the light count
        where = ", ".join(describe[f.object].describe() + (f" {c:.2f}x" if np.isfinite(c) else "")
                          for f, c in fits)
        return Finding("term_scaled:ambient",
                       f"your ambient term is added once per unshadowed light, not once "
                       f"({where}): is ambient ⊙ kd inside the loop over lights?", evidence,
                       specific=True)
    if code == "shininess":
        where = "; ".join(
            f"{describe[f.object].describe()}: {s:.3g} where the material says "
            f"{parts.scene.materials[describe[f.object].material].shininess:g}"
            for f, s in fits)
        return Finding("shininess",
                       f"your highlights fit another shininess ({where}): is the specular "
                       "term (R·L)^shininess with R the mirrored view ray? (Blinn's half vector "
                       "fits about a quarter of it)", evidence,
                       tuple(s for _, s in fits), specific=True)
    kind, term = code.split(":")
    coefs = ", ".join(f"{describe[f.object].describe()} {c:.2f}x" for f, c in fits)
    what = "missing" if kind == "term_missing" else "scaled"
    return Finding(code, f"your {term.replace('_', ' ')} term is {what} against the "
                   f"reference's ({coefs}): {HINTS[(kind, term)]}", evidence,
                   tuple(c for _, c in fits), specific=code == "term_missing:specular_behind")


def _objects_mask(parts: Parts, objects: list[int]) -> np.ndarray:
    return mask_image(np.isin(parts.images["object"], objects))
