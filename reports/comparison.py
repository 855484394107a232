"""One case compared: both renderers, every metric per image kind, a verdict, and its images.

Deterministic cases compare the tracer's images with Mitsuba's directly. Jittered cases cannot:
the two draw different random samples. Both 16-sample images are compared with one converged
Mitsuba render instead, and their errors must be of the same size (thresholds.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tracer.scene import load_scene

from . import metrics, thresholds
from .cases import Case
from .runners import Rendered, render_case


@dataclass
class KindResult:
    kind: str
    metrics: dict[str, float]  # tracer against Mitsuba (its converged render when jittered)
    passed: bool
    failures: list[str]
    jitter: dict[str, float] = field(default_factory=dict)  # see judge_jitter


@dataclass
class CaseResult:
    case: Case
    size: tuple[int, int]
    kinds: list[KindResult]
    times: dict[str, dict[str, float | None]]  # renderer -> cold_s / warm_s
    images: dict[str, dict[str, np.ndarray]]  # renderer -> kind -> float image

    @property
    def passed(self) -> bool:
        return all(k.passed for k in self.kinds)


def _judge(kind: str, m: metrics.Comparison) -> list[str]:
    """Deterministic cases: SSIM and the 8-bit level test."""
    failures = []
    if m.ssim < thresholds.SSIM_MIN:
        failures.append(f"{kind}: SSIM {m.ssim:.4f} < {thresholds.SSIM_MIN}")
    within = 1.0 - m.off_by_more_than_one
    if within < thresholds.WITHIN_ONE_LEVEL_MIN:
        failures.append(f"{kind}: {within:.2%} of pixels within one 8-bit level "
                        f"< {thresholds.WITHIN_ONE_LEVEL_MIN:.1%}")
    return failures


def poisoned(image: np.ndarray) -> np.ndarray:
    """Pixels whose mean holds an inf, NaN or FLT_MAX-sized sample: one such sample decides the
    pixel (it quantises to black, spec §8-9)."""
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(image) < 1e30)
    return bad.any(axis=2) if bad.ndim == 3 else bad


def mean_level_error(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    """Mean absolute difference in 8-bit levels over the pixels in mask (all channels)."""
    d = np.abs(metrics.bytes8(a).astype(np.float64) - metrics.bytes8(b).astype(np.float64))[mask]
    return float(np.mean(d)) if d.size else 0.0


def errors_same_size(e_t: float, e_m: float) -> bool:
    return (abs(e_m - e_t) <= thresholds.JITTER_ABS_LEVELS
            or 1 / thresholds.JITTER_ERROR_RATIO_MAX <= e_m / max(e_t, 1e-9)
            <= thresholds.JITTER_ERROR_RATIO_MAX)


def judge_jitter(kind: str, tracer: np.ndarray, mitsuba: np.ndarray,
                 converged: np.ndarray) -> tuple[list[str], dict[str, float]]:
    """Both 16-sample images against the converged one (see thresholds.py)."""
    failures = []
    n_t, n_m = int(poisoned(tracer).sum()), int(poisoned(mitsuba).sum())
    if abs(n_t - n_m) > thresholds.POISONED_SIGMAS * np.sqrt(n_t + n_m) + thresholds.POISONED_SLACK:
        failures.append(f"{kind}: {n_t} (tracer) vs {n_m} (Mitsuba) pixels with an "
                        f"inf/NaN/missed sample")
    mask = ~(poisoned(converged) | poisoned(tracer) | poisoned(mitsuba))
    e_t = mean_level_error(tracer, converged, mask)
    e_m = mean_level_error(mitsuba, converged, mask)
    if not errors_same_size(e_t, e_m):
        failures.append(f"{kind}: mean error against the converged render {e_t:.3f} (tracer) "
                        f"and {e_m:.3f} (Mitsuba) levels are not of the same size")
    return failures, {"error_tracer": e_t, "error_mitsuba": e_m, "poisoned_tracer": n_t,
                      "poisoned_mitsuba": n_m}


def run_case(case: Case, size: tuple[int, int], seed: int = 0) -> CaseResult:
    scene = load_scene(case.scene.path)
    runs: dict[str, Rendered] = {r: render_case(r, scene, case, size, seed=seed)
                                 for r in ("tracer", "mitsuba")}
    images = {r: run.images for r, run in runs.items()}
    times = {r: {"cold_s": run.cold_s, "warm_s": run.warm_s} for r, run in runs.items()}
    if case.jittered:
        run = render_case("mitsuba", scene, case, size, samples=thresholds.CONVERGED_SAMPLES,
                          seed=seed + 1, warm=False)
        images["converged"] = run.images
        times["converged"] = {"cold_s": run.cold_s, "warm_s": None}
    kinds = []
    for kind in case.kinds:
        if case.jittered:
            # the table's metrics: the tracer's 16 samples against the converged render
            m = metrics.compare(images["converged"][kind], images["tracer"][kind])
            failures, extra = judge_jitter(kind, images["tracer"][kind],
                                           images["mitsuba"][kind], images["converged"][kind])
        else:
            m = metrics.compare(images["mitsuba"][kind], images["tracer"][kind])
            failures, extra = _judge(kind, m), {}
        kinds.append(KindResult(kind, m.as_dict(), not failures, failures, extra))
    return CaseResult(case, size, kinds, times, images)


def write_case_images(result: CaseResult, folder: Path) -> dict[str, dict[str, str]]:
    """PNG files of a case (both renders, difference heatmap, SSIM map) per kind; returns
    kind -> role -> file name relative to folder."""
    from .imaging import diff_heatmap, save_gray_map, save_png

    folder.mkdir(parents=True, exist_ok=True)
    files: dict[str, dict[str, str]] = {}
    a_key, b_key = ("converged", "tracer") if result.case.jittered else ("mitsuba", "tracer")
    for k in result.kinds:
        kind = k.kind
        names = {}
        for role in ("tracer", "mitsuba") + (("converged",) if result.case.jittered else ()):
            name = f"{kind}_{role}.png"
            save_png(folder / name, result.images[role][kind])
            names[role] = name
        ref, got = result.images[a_key][kind], result.images[b_key][kind]
        scale = diff_heatmap(folder / f"{kind}_diff.png", ref, got)
        _, ssim_full = metrics.ssim_map(ref, got)
        save_gray_map(folder / f"{kind}_ssim.png", ssim_full)
        names["diff"] = f"{kind}_diff.png"
        names["ssim"] = f"{kind}_ssim.png"
        names["diff_scale"] = f"{scale:.6g}"
        files[kind] = names
    return files
