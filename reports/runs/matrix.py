"""The case matrix run for one candidate against one reference: every scene x every feature it
can exercise, each case's pictures and page, and the index (overview matrix + table), the JSON
of every number and a JUnit file. `check` and `report` are this with their own renderers,
tolerance and extra pages."""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path
from xml.sax.saxutils import quoteattr

from raycheck.tracer.analysis import analyze
from raycheck.tracer.limits import LimitError
from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.limits import Budget, scene_request_problem

from ..cases import DEFAULT_CASE_SIZE, Case, case_matrix, kind_skip_reason
from ..catalog import BundledScene, unique_labels, with_depth_range
from ..judge.verdict import Tolerance
from ..pages import html
from ..pages.case_files import write_case_images
from ..renderers import Renderer
from .case import CaseResult, run_case
from .progress import Progress

KINDS = ("color", "normals", "depth")


@dataclass
class Matrix:
    scenes: list[BundledScene]
    candidate: Renderer
    reference: Renderer
    tolerance: Tolerance
    size: tuple[int, int] | None = None  # every case at this size; None: as below
    default_size: tuple[int, int] = DEFAULT_CASE_SIZE  # for scenes without a # size line
    features: frozenset[str] | None = None  # None: every feature a scene can exercise
    warm: bool = False  # time a second, warm render of each case (report's time columns)
    seed: int = 0  # of the jittered cases
    budget: Budget = Budget()  # every case's memory and rays, checked before any runs

    def cases(self) -> tuple[list[Case], list[dict]]:
        """The cases to run and the skipped rows (whole features, or kinds of a case)."""
        cases, skips = [], []
        for scene in map(with_depth_range, unique_labels(self.scenes)):
            model = load_scene(scene.path, self.budget)
            scene_cases, skipped = case_matrix(scene, self.size or scene.size or self.default_size,
                                               analyze(model))
            skips += [{"scene": scene_id(scene), "feature": s.feature, "kind": "all",
                       "reason": s.reason} for s in skipped if self._wanted(s.feature)]
            for case in scene_cases:
                if not self._wanted(case.feature):
                    continue
                problem = case.request.limit_problem() or \
                    scene_request_problem(model, case.request, self.budget)
                if problem:  # refused before any case runs
                    raise LimitError(f"{scene.path}: {case.feature}: {problem}")
                cases.append(replace(case, request=replace(case.request, seed=self.seed)))
                skips += [{"scene": scene_id(scene), "feature": case.feature, "kind": k,
                           "reason": kind_skip_reason(case.feature, k)}
                          for k in KINDS if k not in case.request.kinds]
        return cases, skips

    def _wanted(self, feature: str) -> bool:
        if self.features is None:
            return True
        # "bounces" names the mirror feature whatever N a scene uses (bounces3, bounces4)
        generic = "+".join("bounces" if p.startswith("bounces") else p
                           for p in feature.split("+"))
        return feature in self.features or generic in self.features


def scene_id(scene: BundledScene) -> str:
    """folder/name, longer where two scenes of a run share it (catalog.unique_labels)."""
    return scene.id


def slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def case_row(result: CaseResult) -> dict:
    case = result.case
    return {
        "case": case.id, "scene": scene_id(case.scene), "feature": case.feature,
        "description": case.scene.description, "flags": case.request.feature_flags,
        "size": list(case.request.size), "jittered": case.jittered, "passed": result.passed,
        "verdict": result.verdict, "labels": result.labels, "times": result.times,
        "log": result.log, "error": result.error,
        "depth_range": list(case.request.depth_range), "depth_origin": case.scene.depth_origin,
        "kinds": [k.as_dict() for k in result.kinds],
    }


def write_case(result: CaseResult, folder: Path, prov: dict[str, str],
               index_href: str | None = None) -> dict:
    """The case's images and page under folder; returns its JSON row with the file names."""
    files = write_case_images(result, folder)
    row = case_row(result)
    row["files"] = files
    command = result.case.request.to_argv(result.case.scene.path.name)
    (folder / "index.html").write_text(
        html.case_page(row, files, command, prov, index_href), encoding="utf-8")
    return row


def write_case_under(out: Path, result: CaseResult, prov: dict[str, str]) -> dict:
    """The case's folder out/cases/SCENE/FEATURE, linked to out/index.html; returns its row
    with the page relative to out."""
    case = result.case
    rel = Path("cases") / slug(scene_id(case.scene)) / slug(case.feature)
    row = write_case(result, out / rel, prov, "../../../index.html")
    row["page"] = f"{rel.as_posix()}/index.html"
    return row


def run_matrix(matrix: Matrix, out: Path, prov: dict[str, str],
               quiet: bool = False) -> tuple[list[dict], list[dict], float]:
    """Runs every case, writing each one's folder under out/cases/ and showing progress;
    returns (case rows, skipped rows, seconds)."""
    out.mkdir(parents=True, exist_ok=True)
    cases, skips = matrix.cases()
    rows = []
    start = time.perf_counter()
    progress = Progress(len(cases), quiet=quiet)
    for case in cases:
        result = run_case(case, matrix.candidate, matrix.reference, matrix.tolerance,
                          matrix.warm)
        rows.append(write_case_under(out, result, prov))
        worst = next((f for k in result.kinds for f in k.failures), "")
        progress.step(f"{case.id} {result.verdict}{': ' + worst if worst else ''}",
                      failed=result.verdict != "pass")
    return rows, skips, time.perf_counter() - start


def index_rows(rows: list[dict]) -> list[dict]:
    """One table row per case and kind."""
    out = []
    for row in rows:
        for k in row["kinds"]:
            out.append({"scene": row["scene"], "feature": row["feature"], "kind": k["kind"],
                        "status": k["verdict"], "metrics": k["metrics"], "times": row["times"],
                        "failures": k["failures"], "page": row["page"],
                        "note": "16 samples against the converged reference"
                                if row["jittered"] else ""})
    return out


def overview_cells(rows: list[dict]) -> dict[tuple[str, str], dict]:
    cells = {}
    for row in rows:
        folder = row["page"].rsplit("/", 1)[0]
        files = row["files"].get("color") or next(iter(row["files"].values()), {})
        thumbs = [(f"{folder}/{files[r]}", r) for r in ("candidate", "diff") if r in files]
        title = next((f for k in row["kinds"] for f in k["failures"]), row["verdict"])
        finding = top_finding(row)
        if finding:
            title += f"; finding {finding['code']}: {finding['message']}"
        cells[(row["scene"], row["feature"])] = {"verdict": row["verdict"], "page": row["page"],
                                                 "thumbs": thumbs, "title": title}
    return cells


def top_finding(row: dict) -> dict | None:
    """The first finding of the case's first failing kind (judge.findings), if any."""
    return next((k["findings"][0] for k in row["kinds"]
                 if k["verdict"] == "fail" and k["findings"]), None)


def features_in_order(rows: list[dict]) -> list[str]:
    order = ["plain", "shadows", "bounces", "shadows+bounces", "jitter", "filter",
             "jitter+filter"]

    def key(f: str) -> tuple[int, str]:
        generic = "+".join("bounces" if p.startswith("bounces") else p for p in f.split("+"))
        return (order.index(generic) if generic in order else len(order), f)

    return sorted({r["feature"] for r in rows}, key=key)


def write_index(out: Path, rows: list[dict], skips: list[dict], labels: dict[str, str],
                intro: str, prov: dict[str, str], title: str, extra: str = "") -> None:
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    matrix = html.overview(overview_cells(rows), scenes, features_in_order(rows)) if rows else ""
    (out / "index.html").write_text(
        html.index_page(index_rows(rows), skips, labels, intro, prov, title, matrix, extra),
        encoding="utf-8")


def summary(rows: list[dict]) -> dict[str, int]:
    """Counts of kind verdicts."""
    counts = {"pass": 0, "fail": 0, "error": 0}
    for row in rows:
        for k in row["kinds"]:
            counts[k["verdict"]] += 1
    return counts


def write_junit(path: Path, rows: list[dict], suite: str) -> None:
    """One testcase per case and kind (classname scene, name feature/kind), failures and errors
    with their messages, skipped kinds left out."""
    counts = summary(rows)
    cases = []
    for row in rows:
        for k in row["kinds"]:
            seconds = (row["times"].get("candidate") or {}).get("cold_s") or 0.0
            attrs = (f'classname={quoteattr(row["scene"])} '
                     f'name={quoteattr(row["feature"] + "/" + k["kind"])} time="{seconds:.3f}"')
            message = "; ".join(k["failures"])
            if k["verdict"] == "pass":
                cases.append(f"  <testcase {attrs}/>")
            else:
                tag = "failure" if k["verdict"] == "fail" else "error"
                code = k["findings"][0]["code"] if k["findings"] else k["verdict"]
                cases.append(f"  <testcase {attrs}>\n    <{tag} message={quoteattr(message)} "
                             f"type={quoteattr(code)}/>\n  </testcase>")
    total = sum(counts.values())
    path.write_text(
        '<?xml version="1.0" encoding="utf-8"?>\n'
        f'<testsuite name={quoteattr(suite)} tests="{total}" failures="{counts["fail"]}" '
        f'errors="{counts["error"]}" skipped="0">\n' + "\n".join(cases) + "\n</testsuite>\n",
        encoding="utf-8")


def finite_json(x):
    """Strict JSON: non-finite floats (PSNR of identical images is inf) become strings."""
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if isinstance(x, dict):
        return {k: finite_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite_json(v) for v in x]
    return x


def write_json(path: Path, data: dict) -> None:
    path.write_text(json.dumps(finite_json(data), indent=1, allow_nan=False), encoding="utf-8")
