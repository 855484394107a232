"""The pictures of one case: each role's render as the 8-bit course output, the difference
heatmap and the SSIM map of the candidate against what it is judged by."""
from __future__ import annotations

from pathlib import Path

from ..judge import metrics
from ..judge.verdict import as_values, comparable
from .imaging import diff_heatmap, save_gray_map, save_png


def write_case_images(result, folder: Path) -> dict[str, dict[str, str]]:
    """PNG files of a CaseResult per kind; returns kind -> role (candidate, reference,
    mean, diff, ssim, diff_scale, evidence) -> file name relative to folder. Kinds the
    candidate did not deliver get no pictures."""
    folder.mkdir(parents=True, exist_ok=True)
    files: dict[str, dict[str, str]] = {}
    against = "mean" if result.case.jittered else "reference"
    for k in result.kinds:
        kind = k.kind
        if any(kind not in result.images.get(role, {}) for role in ("candidate", against)):
            continue
        names = {}
        for role, images in result.images.items():
            name = f"{kind}_{role}.png"
            save_png(folder / name, as_values(images[kind]))
            names[role] = name
        ref, got = comparable(result.images[against][kind], result.images["candidate"][kind])
        names["diff_scale"] = f"{diff_heatmap(folder / f'{kind}_diff.png', ref, got):.6g}"
        _, ssim_full = metrics.ssim_map(ref, got)
        save_gray_map(folder / f"{kind}_ssim.png", ssim_full)
        names["diff"] = f"{kind}_diff.png"
        names["ssim"] = f"{kind}_ssim.png"
        if kind in result.evidence:  # the top finding's picture (judge.findings)
            save_png(folder / f"{kind}_evidence.png", as_values(result.evidence[kind]))
            names["evidence"] = f"{kind}_evidence.png"
        files[kind] = names
    return files
