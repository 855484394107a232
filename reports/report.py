"""`raycheck report`: the comparison suite over scenes x relevant features as a static HTML
report, with error-against-time plots, provenance and a JSON file holding every number."""
from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Callable

from . import html
from .cases import KINDS, Case, case_matrix, kind_skip_reason
from .catalog import BundledScene, bundled
from .comparison import CaseResult, run_case, write_case_images
from .convergence import SIZE_SWEEP_SAMPLES, SWEEP_SIZE, as_rows, sweep
from .provenance import provenance
from .svgplot import loglog

REPORT_SIZE = 128  # square size of report renders unless a scene asks for its own size
SWEEP_SCENES = ("spheres_mirror", "cubemap_mesh")


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def course_command(case: Case, size: tuple[int, int]) -> list[str]:
    cmd = ["-size", str(size[0]), str(size[1]), "-input", str(case.scene.path), *case.flags,
           "-output", "out.png"]
    if "normals" in case.kinds:
        cmd += ["-normals", "normals.png"]
    if "depth" in case.kinds:
        lo, hi = case.scene.depth_range
        cmd += ["-depth", f"{lo:g}", f"{hi:g}", "depth.png"]
    return cmd


def case_row(result: CaseResult) -> dict:
    case = result.case
    return {
        "case": case.id, "scene": case.scene.name, "feature": case.feature,
        "description": case.scene.description, "flags": list(case.flags),
        "size": list(result.size), "jittered": case.jittered, "passed": result.passed,
        "times": result.times,
        "kinds": [{"kind": k.kind, "metrics": k.metrics, "passed": k.passed,
                   "failures": k.failures, "jitter": k.jitter} for k in result.kinds],
    }


def write_case(result: CaseResult, folder: Path, prov: dict[str, str],
               index_href: str | None = None) -> dict:
    """The case's images and page under folder; returns its JSON row."""
    files = write_case_images(result, folder)
    row = case_row(result)
    row["files"] = files
    (folder / "index.html").write_text(
        html.case_page(row, files, ["raycheck", "compare"] + course_command(result.case,
                                                                              result.size), prov,
                       index_href),
        encoding="utf-8")
    return row


def _index_rows(row: dict, page: str) -> list[dict]:
    out = []
    for k in row["kinds"]:
        out.append({"scene": row["scene"], "feature": row["feature"], "kind": k["kind"],
                    "status": "pass" if k["passed"] else "fail", "metrics": k["metrics"],
                    "times": row["times"], "failures": k["failures"], "page": page,
                    "note": "16 samples against converged Mitsuba" if row["jittered"] else ""})
    return out


def _plots(points: list[dict]) -> list[str]:
    """Per sweep scene and error metric: both renderers' sample-count sweep (solid) and
    resolution sweep (dashed) against warm run time."""
    plots = []
    for scene in sorted({p["scene"] for p in points}):
        pts = [p for p in points if p["scene"] == scene]
        for metric, label in (("one_minus_ssim", "1 - SSIM"), ("rmse", "RMSE")):
            series = {}
            for r in ("tracer", "mitsuba"):
                series[f"{r} spp"] = sorted(
                    (p["warm_s"], p[metric], f"{p['samples']} spp at {p['size']} px")
                    for p in pts if p["renderer"] == r and p["size"] == SWEEP_SIZE)
                series[f"{r} size"] = sorted(
                    (p["warm_s"], p[metric], f"{p['size']} px at {p['samples']} spp")
                    for p in pts if p["renderer"] == r and p["samples"] == SIZE_SWEEP_SAMPLES)
            plots.append(loglog(f"{scene}: {label} against warm run time", "warm run time (s)",
                                label, series, dashed=[n for n in series if n.endswith("size")]))
    return plots


def build_report(scenes: list[BundledScene], out: Path, size: int = REPORT_SIZE,
                 sweep_scenes: tuple[str, ...] = SWEEP_SCENES, seed: int = 0,
                 log: Callable[[str], None] = print, stress_link: bool = False,
                 bench_link: bool = False) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    prov = provenance(seed)
    rows, index_rows, skips = [], [], []
    start = time.perf_counter()
    for scene in scenes:
        cases, skipped = case_matrix(scene)
        skips += [{"scene": s.scene.name, "feature": s.feature, "kind": "all", "reason": s.reason}
                  for s in skipped]
        for case in cases:
            dims = scene.size or (size, size)
            result = run_case(case, dims, seed)
            rel = Path("cases") / _slug(scene.name) / _slug(case.feature)
            row = write_case(result, out / rel, prov, "../../../index.html")
            rows.append(row)
            index_rows += _index_rows(row, f"{rel.as_posix()}/index.html")
            skips += [{"scene": scene.name, "feature": case.feature, "kind": k,
                       "reason": kind_skip_reason(case.feature, k)}
                      for k in KINDS if k not in case.kinds]
            log(f"{case.id:<36} {'pass' if result.passed else 'FAIL'}  "
                f"({time.perf_counter() - start:.0f} s)")
    points: list[dict] = []
    for scene in scenes:
        if scene.name in sweep_scenes:
            log(f"error against time: {scene.name}")
            points += as_rows(sweep(scene))
    data = {"provenance": prov, "cases": rows, "skipped": skips, "convergence": points,
            "seconds": time.perf_counter() - start}
    (out / "report.json").write_text(json.dumps(finite_json(data), indent=1, allow_nan=False),
                                     encoding="utf-8")
    (out / "index.html").write_text(
        html.index_page(index_rows, skips, _plots(points), points, prov, stress_link=stress_link,
                        bench_link=bench_link),
        encoding="utf-8")
    return data


def finite_json(x):
    """Strict JSON: non-finite floats (PSNR of identical images is inf) become strings."""
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if isinstance(x, dict):
        return {k: finite_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite_json(v) for v in x]
    return x


def all_bundled() -> list[BundledScene]:
    return bundled("course") + bundled("features")
