"""One case compared: both renderers, every metric per image kind, a verdict, and its images.

Deterministic cases compare the tracer's images with Mitsuba's directly. Jittered cases cannot:
the two draw different random samples. Each renderer's 16-sample image is compared with its own
converged render instead, and the two converged renders with each other.
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
    metrics: dict[str, float]  # tracer against Mitsuba (converged renders for jittered cases)
    passed: bool
    failures: list[str]
    jitter: dict[str, float] = field(default_factory=dict)  # rmse_tracer, rmse_mitsuba, ratio


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


def _judge(kind: str, m: metrics.Comparison, converged: bool = False) -> list[str]:
    """Deterministic cases: SSIM and the 8-bit level test. Converged jittered renders keep a
    little Monte Carlo noise, which flips bytes at edges: their own SSIM bound, no level test."""
    failures = []
    ssim_min = thresholds.CONVERGED_SSIM_MIN if converged else thresholds.SSIM_MIN
    if m.ssim < ssim_min:
        failures.append(f"{kind}: SSIM {m.ssim:.4f} < {ssim_min}")
    within = 1.0 - m.off_by_more_than_one
    if not converged and within < thresholds.WITHIN_ONE_LEVEL_MIN:
        failures.append(f"{kind}: {within:.2%} of pixels within one 8-bit level "
                        f"< {thresholds.WITHIN_ONE_LEVEL_MIN:.1%}")
    return failures


def _judge_jitter(kind: str, e_t: float, e_m: float) -> tuple[list[str], float]:
    lo, hi = sorted((e_t, e_m))
    ratio = hi / lo if lo > 0 else (1.0 if hi == 0 else float("inf"))
    if hi < thresholds.JITTER_RMSE_FLOOR or ratio <= thresholds.JITTER_RMSE_RATIO_MAX:
        return [], ratio
    return [f"{kind}: 16-sample RMSE against converged: tracer {e_t:.4g}, Mitsuba {e_m:.4g} "
            f"(ratio {ratio:.2f} > {thresholds.JITTER_RMSE_RATIO_MAX})"], ratio


def run_case(case: Case, size: tuple[int, int], seed: int = 0) -> CaseResult:
    scene = load_scene(case.scene.path)
    runs: dict[str, Rendered] = {r: render_case(r, scene, case, size, seed=seed)
                                 for r in ("tracer", "mitsuba")}
    images = {r: run.images for r, run in runs.items()}
    times = {r: {"cold_s": run.cold_s, "warm_s": run.warm_s} for r, run in runs.items()}
    converged = {}
    if case.jittered:
        for r in ("tracer", "mitsuba"):
            run = render_case(r, scene, case, size, samples=thresholds.CONVERGED_SAMPLES,
                              seed=seed + 1, warm=False)
            converged[r] = run.images
            images[f"{r}_converged"] = run.images
            times[f"{r}_converged"] = {"cold_s": run.cold_s, "warm_s": None}
    kinds = []
    for kind in case.kinds:
        if case.jittered:
            m = metrics.compare(converged["mitsuba"][kind], converged["tracer"][kind])
            e_t = metrics.rmse(converged["tracer"][kind], images["tracer"][kind])
            e_m = metrics.rmse(converged["mitsuba"][kind], images["mitsuba"][kind])
            jitter_failures, ratio = _judge_jitter(kind, e_t, e_m)
            judged = kind != "depth" or thresholds.JUDGE_CONVERGED_DEPTH
            failures = jitter_failures + (
                [f"converged {f}" for f in _judge(kind, m, converged=True)] if judged else [])
            extra = {"rmse_tracer": e_t, "rmse_mitsuba": e_m, "ratio": ratio}
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
    a_key, b_key = ("mitsuba_converged", "tracer_converged") if result.case.jittered else \
        ("mitsuba", "tracer")
    for k in result.kinds:
        kind = k.kind
        names = {}
        for role in ("tracer", "mitsuba") + ((a_key, b_key) if result.case.jittered else ()):
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
