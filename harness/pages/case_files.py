"""The pictures of one case: each role's render as the 8-bit course output, the difference
heatmap and the SSIM map of the candidate against what it is judged by."""
from __future__ import annotations

from pathlib import Path

from ..judge import metrics
from ..judge.verdict import as_values, comparable
from ..records import Role
from .imaging import (
    difference,
    save_diff_thumbnail,
    save_gray_map,
    save_heatmap,
    save_png,
    save_thumbnail,
    thumb_shape,
)


def overview_kind(kinds: list[str]) -> str | None:
    """The kind the overview matrix shows a case by: color, else the first it has."""
    return "color" if "color" in kinds else next(iter(kinds), None)


def write_case_images(result, folder: Path) -> dict[str, dict[str, str]]:
    """PNG files of a CaseResult per kind; returns kind -> role (candidate, reference,
    mean, diff, ssim, diff_scale, evidence, and for the overview's kind of an image larger
    than a thumbnail thumb_candidate and thumb_diff) -> file name relative to folder. Kinds
    the candidate did not deliver get no pictures."""
    folder.mkdir(parents=True, exist_ok=True)
    files: dict[str, dict[str, str]] = {}
    against = Role.MEAN if result.case.jittered else Role.REFERENCE
    delivered = [k.kind for k in result.kinds if all(k.kind in result.images.get(role, {})
                                                     for role in (Role.CANDIDATE, against))]
    for kind in delivered:
        names = {}
        for role, images in result.images.items():
            name = f"{kind}_{role}.png"
            save_png(folder / name, as_values(images[kind]))
            names[role] = name
        ref, got = comparable(result.images[against][kind], result.images[Role.CANDIDATE][kind])
        d, scale = difference(ref, got)
        save_heatmap(folder / f"{kind}_diff.png", d, scale)
        names["diff_scale"] = f"{scale:.6g}"
        shape = thumb_shape(got.shape)
        if kind == overview_kind(delivered) and shape is not None:
            save_thumbnail(folder / "thumb_candidate.png", got, shape)
            save_diff_thumbnail(folder / "thumb_diff.png", d, scale, shape)
            names["thumb_candidate"], names["thumb_diff"] = "thumb_candidate.png", "thumb_diff.png"
        _, ssim_full = metrics.ssim_map(ref, got)
        save_gray_map(folder / f"{kind}_ssim.png", ssim_full)
        names["diff"] = f"{kind}_diff.png"
        names["ssim"] = f"{kind}_ssim.png"
        if kind in result.evidence:  # the top finding's picture (judge.findings)
            save_png(folder / f"{kind}_evidence.png", as_values(result.evidence[kind]))
            names["evidence"] = f"{kind}_evidence.png"
        files[kind] = names
    return files
