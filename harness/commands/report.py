"""`raycheck report`: the comparison suite, the tracer against the Mitsuba reference over every
scene x feature it can exercise, as a static HTML report with error-against-time plots,
provenance and a JSON file holding every number."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from raycheck.tracer.render_limits import LimitError
from raycheck.tracer.scene.limits import Budget

from ..bench.convergence import sweep, sweep_problem
from ..bench.records import BenchRun, Point
from ..case_settings import CaseSettings
from ..catalog import BundledScene
from ..judge.verdict import ENGINES_JITTER_TEST, ENGINES_TOLERANCE
from ..pages.reportpage import jitter_section, report_intro, sweep_section
from ..pipeline.matrix import (
    Matrix,
    Runner,
    run_matrix,
    summary,
    write_index,
    write_json,
    write_junit,
)
from ..provenance import provenance
from ..records import CaseRecord, Role, SkipRecord, to_json
from ..renderers import Renderer
from ..storage.distribution import DEFAULT_REALISATIONS

REPORT_SIZE = 128  # square size of report renders unless a scene asks for its own size
SWEEP_SCENES = ("spheres_mirror", "cubemap_mesh")
# the report's other pages, linked from its index where they were made: (file, what it holds,
# link text, how to make it where it was not)
OTHER_PAGES = (("stress.html", "The extreme scenes in every mode", "stress tests",
                "raycheck stress"),
               ("bench.html", "Render times and BVH throughput", "benchmarks", "make bench"),
               ("findings.html", "Which bug the top finding names", "findings",
                "make findings"))


@dataclass(frozen=True)
class ReportPlan:
    """What a report compares: the scenes, the two renderers, the cases' size, seed, budget
    and realisations, and the scenes swept for error against time."""

    scenes: tuple[BundledScene, ...]
    candidate: Renderer
    reference: Renderer
    size: int = REPORT_SIZE
    sweep_scenes: tuple[str, ...] = SWEEP_SCENES
    seed: int = 0
    budget: Budget = Budget()
    realisations: int = DEFAULT_REALISATIONS

    def matrix(self) -> Matrix:
        settings = CaseSettings(ENGINES_TOLERANCE, warm=True, realisations=self.realisations,
                                jitter_test=ENGINES_JITTER_TEST)
        return Matrix(list(self.scenes), self.candidate, self.reference, settings,
                      default_size=(self.size, self.size), seed=self.seed, budget=self.budget)

    def swept(self) -> list[BundledScene]:
        return [s for s in self.scenes if s.name in self.sweep_scenes]

    def check_limits(self) -> None:
        """LimitError for the first case or sweep that is over a limit: for the command to
        call before any work."""
        self.matrix().cases()
        for scene in self.swept():
            problem = sweep_problem(scene, self.budget)
            if problem:
                raise LimitError(f"the error-against-time sweep of {scene.name}, {problem} (or "
                                 "leave the sweeps out: --no-sweeps)")


@dataclass(frozen=True)
class Comparisons:
    """The report's cases, run: what its index, report.json and junit.xml are made of."""

    rows: list[CaseRecord]
    skips: list[SkipRecord]
    seconds: float
    provenance: dict[str, str]


def run_comparisons(plan: ReportPlan, out: Path, quiet: bool = False,
                    runner: Runner | None = None) -> Comparisons:
    """Every case of the plan, its pictures and pages written under out/cases."""
    prov = provenance(plan.seed)
    rows, skips, seconds = run_matrix(plan.matrix(), out, prov, quiet, runner)
    return Comparisons(rows, skips, seconds, prov)


def run_sweeps(plan: ReportPlan, log: Callable[[str], None] = print) -> list[Point]:
    points: list[Point] = []
    for scene in plan.swept():
        log(f"error against time: {scene.name}")
        points += sweep(scene, [plan.candidate, plan.reference], plan.reference)
    return points


def write_report(plan: ReportPlan, out: Path, done: Comparisons, points: list[Point],
                 pages: frozenset[str]) -> dict:
    """report.json, junit.xml and the index of the comparisons, with the sweeps' points and
    links to the other pages made (OTHER_PAGES' files in `pages`); returns report.json's
    data."""
    names = [plan.candidate.name, plan.reference.name]
    labels = {Role.CANDIDATE: names[0], Role.REFERENCE: names[1]}
    data = {"provenance": done.provenance, "labels": labels,
            "cases": [to_json(r) for r in done.rows], "skipped": to_json(done.skips),
            "summary": to_json(summary(done.rows)), "convergence": to_json(points),
            "seconds": done.seconds}
    write_json(out / "report.json", data)
    write_junit(out / "junit.xml", done.rows, "raycheck report")
    jitter_test = ENGINES_JITTER_TEST.describe()
    intro = report_intro(names[0], names[1], ENGINES_TOLERANCE.describe(), plan.realisations,
                         jitter_test, [(what, href, text) for href, what, text, _ in OTHER_PAGES
                                       if href in pages],
                         [(what, how) for href, what, _, how in OTHER_PAGES
                          if href not in pages])
    write_index(out, done.rows, done.skips, labels, intro, done.provenance, "raycheck report",
                jitter_section(done.rows, plan.realisations, jitter_test)
                + sweep_section(points, names))
    return data


def build_report(plan: ReportPlan, out: Path, log: Callable[[str], None] = print,
                 quiet: bool = False, runner: Runner | None = None,
                 pages: frozenset[str] = frozenset()) -> dict:
    """The comparisons and the sweeps, and the report's files, in one go."""
    done = run_comparisons(plan, out, quiet, runner)
    return write_report(plan, out, done, run_sweeps(plan, log), pages)


def course_bench(log: Callable[[str], None] = print) -> BenchRun:
    """The benchmark page's numbers: `raycheck bench` of the course scenes in both renderers,
    timed once per engine source and machine and then reused from the disk cache
    (disk_cache.py): 14 fresh processes would otherwise be timed again on every report, for
    numbers that only a change of the engines or the machine changes. The page's provenance
    is that of the run that timed them."""
    import hashlib
    import json
    import platform

    from ..bench.timing import run_bench
    from ..storage.disk_cache import cache_folder, engine_digest, load_bytes, save_bytes

    machine = f"{platform.node()} {platform.machine()} {platform.platform()}"
    key = hashlib.sha256(f"{engine_digest()} {machine}".encode()).hexdigest()
    path = cache_folder() / "bench" / f"{key}.json"
    try:
        saved = BenchRun.from_json(json.loads(load_bytes(path) or b"null"))
        log(f"bench: the saved run of these engines on this machine ({path})")
        return saved
    except ValueError:  # none, or a damaged entry: timed again
        pass
    log("bench: the course scenes in both renderers")
    data = run_bench(["tracer", "mitsuba"], log=log)
    save_bytes(path, json.dumps(data.to_json()).encode())
    return data


