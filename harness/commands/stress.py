"""`raycheck stress`: the extreme scenes (scenes/extreme) in course mode, robust mode, course
mode in float64 and Mitsuba, each against the float64 robust render as the reference.

Per scene and variant: pixels with a NaN or inf channel in the float color image, the share of
8-bit pixels differing by more than one level from the reference (acne, leaks, missed hits),
SSIM against it, cold and warm run time. The page lists the rows worst first (share differing,
then NaN/inf count) with reference | variant | difference images for each failing row.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..cases import Case
from ..catalog import BundledScene, bundled
from ..judge.metrics import displayed, share_off_by_more_than_one_level, ssim
from ..pages.imaging import diff_heatmap, save_png
from ..pages.stresspage import stress_page
from ..pipeline.case import render_role
from ..pipeline.matrix import write_json
from ..records import StressRow
from ..renderers import Renderer, RenderError, stress_reference, stress_variants

DEFAULT_SIZE = (64, 64)
SSIM_GOAL = 0.99


def nonfinite_pixels(image: np.ndarray) -> int:
    """Pixels with at least one NaN or ±inf channel."""
    bad = ~np.isfinite(image)
    return int(bad.any(axis=-1).sum() if bad.ndim == 3 else bad.sum())


def _render(renderer: Renderer, bs: BundledScene, size: tuple[int, int]):
    return render_role(renderer, Case(bs, "stress", bs.typical_request(size)), True)


def run_stress(scenes: list[BundledScene] | None = None, folder: Path = Path("out/report"),
               variants: dict[str, Renderer] | None = None,
               size: tuple[int, int] | None = None, progress=None,
               reference: Renderer | None = None) -> list[StressRow]:
    """Render, measure and write folder/stress.html, stress.json and stress_img/; the rows,
    worst first. Default variants and reference: renderers.stress_variants / stress_reference."""
    scenes = bundled("extreme") if scenes is None else scenes
    variants = stress_variants() if variants is None else variants
    reference = reference or stress_reference()
    folder = Path(folder)
    img_dir = folder / "stress_img"
    img_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for bs in scenes:
        sz = size or bs.size or DEFAULT_SIZE
        ref = _render(reference, bs, sz)
        ref_img = ref.images["color"]
        ref_png = f"stress_img/{bs.name}.reference.png"
        save_png(folder / ref_png, ref_img)
        for name, which in variants.items():
            try:
                r = _render(which, bs, sz)
            except RenderError as e:  # a renderer failing on a scene is a result too
                rows.append(StressRow(scene=bs.name, variant=name, size=sz, error=str(e),
                                      nonfinite=None, differing=1.0, ssim=0.0, cold_s=None,
                                      warm_s=None, passed=False, description=bs.description))
                continue
            img = r.images["color"]
            stem = f"stress_img/{bs.name}.{name}"
            np.save(folder / f"{stem}.npy", img)
            save_png(folder / f"{stem}.png", img)
            differing = share_off_by_more_than_one_level(ref_img, img)
            s = ssim(ref_img, img)
            if min(img.shape[:2]) < 7:
                # below SSIM's 3x3 window metrics.ssim falls back to exact float equality; on
                # the 8-bit values as shown that fallback is what the course output compares
                s = ssim(displayed(ref_img), displayed(img))
            nf = nonfinite_pixels(img)
            passed = nf == 0 and s >= SSIM_GOAL
            row = StressRow(scene=bs.name, variant=name, size=sz, nonfinite=nf,
                            differing=differing, ssim=s, cold_s=r.cold_s, warm_s=r.warm_s,
                            passed=passed, description=bs.description, image=f"{stem}.png",
                            floats=f"{stem}.npy", reference=ref_png,
                            reference_nonfinite=nonfinite_pixels(ref_img))
            if not passed:
                row = replace(row, diff=f"{stem}.diff.png",
                              diff_scale=diff_heatmap(folder / f"{stem}.diff.png", ref_img, img))
            rows.append(row)
            if progress:
                progress(row)
    rows.sort(key=sort_key)
    write_json(folder / "stress.json", rows)
    (folder / "stress.html").write_text(stress_page(rows, SSIM_GOAL), encoding="utf-8")
    return rows


def sort_key(row: StressRow):
    """Worst first: largest share differing, then most NaN/inf pixels, then lowest SSIM."""
    nf = row.nonfinite if row.nonfinite is not None else float("inf")
    return (-row.differing, -nf, row.ssim, row.scene, row.variant)


def format_table(rows: list[StressRow]) -> str:
    lines = [f"{'scene':<24} {'variant':<15} {'NaN/inf':>7} {'differ':>8} {'SSIM':>7} "
             f"{'cold s':>7} {'warm s':>7}  status"]
    for r in rows:
        nf = "-" if r.nonfinite is None else str(r.nonfinite)
        cold = "-" if r.cold_s is None else f"{r.cold_s:.2f}"
        warm = "-" if r.warm_s is None else f"{r.warm_s:.3f}"
        lines.append(f"{r.scene:<24} {r.variant:<15} {nf:>7} {r.differing:>8.2%} "
                     f"{r.ssim:>7.4f} {cold:>7} {warm:>7}  "
                     f"{r.error or ('pass' if r.passed else 'FAIL')}")
    return "\n".join(lines)
