"""`raycheck grade`: the full check of every submission of a class, and a class table.

A submission given as sources (a folder, an archive, a git repository: submission/sources.py) is
built first, in the same pool of workers as the cases and in the sandbox (submission/cmake.py); one
that does not build is a row of its own ("build failed", the compiler's first error, its log).

All submissions' cases go through one executor, interleaved (case 1 of every submission,
then case 2, ...), so a submission that hangs holds at most its share of the workers for its
timeouts instead of stalling the class. The reference of each case is rendered once, before
the submissions run, into a render cache that every submission's cases then read
(results.CachedRenderer): with 200 submissions the reference costs 1/200 of what rendering it
per submission would.

Writes DIR/<name>/ (each submission's report, as `raycheck check` writes it, its build.log
and its Gradescope results.json), DIR/index.html (the class table), DIR/grades.csv and
DIR/grades.json.
"""
from __future__ import annotations

import math
import os
import re
import shutil
import time
import tomllib
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path

from ..check_options import FAMILIES, FEATURES_HELP, case_family, feature_family
from ..pipeline.matrix import Job, Matrix, Runner, place_case_under, write_json
from ..provenance import provenance
from ..records import CheckEntry, CheckReport, FamilyCount, GradeRow, Verdict
from ..renderers import CommandRenderer, Limits
from ..renderers.command import program_file, split_command
from ..renderers.sandbox import Sandbox
from ..storage.results import CachedRenderer
from ..submission.cmake import BuildResult, build_sources
from ..submission.sources import ARCHIVES, is_sources
from .check import write_check
from .class_files import CLASS_FILES, ClassGrades, write_class_files
from .gradescope import gradescope_results

# points per feature family out of 100: the course's basic image first, then each feature by
# how much of the assignment it is
DEFAULT_POINTS = {"plain": 20, "shadows": 15, "bounces": 15, "shadows+bounces": 10,
                  "jitter": 15, "filter": 15, "jitter+filter": 10}
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")


class GradeInputError(ValueError):
    """A submission or weights file that cannot be used (one line, exit status 2)."""


@dataclass(frozen=True)
class Submission:
    name: str  # its folder under DIR and its row in the table
    renderer: CommandRenderer | None  # None: sources, not built yet
    sources: Path | None = None  # a submission given as sources
    build: BuildResult | None = None  # what building its sources gave


def submission(spec: str, limits: Limits) -> Submission:
    """NAME=SPEC or SPEC: sources (a folder holding C++ sources or a CMakeLists.txt, a .zip
    or .tar.gz, a git repository or bundle: built before the cases), an executable file, a
    folder holding an executable `a2`, or a command string; the name is NAME, else the
    folder's or file's name."""
    name, sep, rest = spec.partition("=")
    if sep and NAME.fullmatch(name) and rest:
        spec = rest
    else:
        name = ""
    path = Path(spec)
    if is_sources(path):  # built, even beside an a2 of its own: the sources are what count
        stem = path.resolve().name
        for suffix in (*ARCHIVES, ".bundle"):
            stem = stem.removesuffix(suffix)
        return Submission(_slug(name or stem), None, sources=path)
    if path.is_dir():
        path = path / "a2"
        if not (path.is_file() and os.access(path, os.X_OK)):
            raise GradeInputError(f"{spec}: a folder without an executable a2")
        argv, name = [str(path)], name or Path(spec).resolve().name
    elif path.is_file():
        if not os.access(path, os.X_OK):
            raise GradeInputError(f"{spec}: not executable (chmod +x, or name its interpreter: "
                                  f"'python3 {spec}')")
        argv, name = [spec], name or path.stem
    else:
        try:
            argv = split_command(spec)
        except ValueError as e:
            raise GradeInputError(f"{spec!r}: {e}") from None
        program = program_file(argv)
        if program is None:
            raise GradeInputError(f"{spec!r}: no such file or command {argv[0]!r}")
        name = name or (program.parent.name if program.name == "a2" else program.stem)
    slug = _slug(name)
    return Submission(slug, CommandRenderer(argv, limits, name=slug))


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name).lstrip(".") or "a2"


def submissions(specs: list[str], limits: Limits) -> list[Submission]:
    """The submissions, with names made unique (alice, alice-2, ...)."""
    out: list[Submission] = []
    seen: set[str] = set()
    for spec in specs:
        sub = submission(spec, limits)
        name, n = sub.name, 1
        while name in seen or name in CLASS_FILES:
            n += 1
            name = f"{sub.name}-{n}"
        seen.add(name)
        out.append(replace(sub, name=name, renderer=sub.renderer and
                           replace(sub.renderer, name=name)))
    return out


def read_points(path: Path | None) -> dict[str, float]:
    """Points per feature family from a TOML file's [points] table (a family not listed
    gets 0), or DEFAULT_POINTS."""
    if path is None:
        return dict(DEFAULT_POINTS)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise GradeInputError(f"{path}: cannot read the weights ({e})") from None
    table = data.get("points")
    if not isinstance(table, dict) or set(data) != {"points"}:
        raise GradeInputError(f"{path}: expected one [points] table (family = points)")
    unknown = sorted(name for name in table if feature_family(name) is None)
    if unknown:
        raise GradeInputError(f"{path}: unknown feature families {', '.join(unknown)} "
                              f"(expected some of {FEATURES_HELP})")
    points: dict[str, float] = {}
    for name, value in table.items():
        if not _finite_points(value):
            raise GradeInputError(f"{path}: points of {name} must be a finite number >= 0, "
                                  f"found {value!r}")
        family = feature_family(name)
        assert family is not None  # names of none were refused above
        if family in points:
            raise GradeInputError(f"{path}: {name} and another key both name the family "
                                  f"{family}")
        points[family] = float(value)
    return {f: points.get(f, 0.0) for f in FAMILIES}


def _finite_points(value) -> bool:
    """A TOML number that is a weight: not a boolean, finite as a float (1e400 reads as inf,
    and an integer of 400 digits overflows), not negative, not NaN."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return 0.0 <= float(value) < math.inf
    except OverflowError:
        return False


def grade_row(name: str, report: CheckReport, points: dict[str, float],
              build: BuildResult | None = None) -> GradeRow:
    """A submission's line of the class table from its check.json: cases passed per feature
    family (a case passes when every image kind of it does), the score, the cases that
    crashed, timed out or erred otherwise, and per failing family its most common top
    finding."""
    cases: dict[tuple[str, str], list[CheckEntry]] = {}
    for entry in report.cases:
        cases.setdefault((entry.scene, entry.feature), []).append(entry)
    passed = {f: 0 for f in FAMILIES}
    total = {f: 0 for f in FAMILIES}
    codes: dict[str, int] = {}
    tops: dict[str, Counter[str]] = {}
    for (_, feature), kinds in cases.items():
        family = case_family(feature)
        total[family] += 1
        passed[family] += all(k.verdict == Verdict.PASS for k in kinds)
        errors = [k.findings[0].code for k in kinds
                  if k.verdict == Verdict.ERROR and k.findings]
        if errors:
            codes[errors[0]] = codes.get(errors[0], 0) + 1
        top = next((k.findings[0].code for k in kinds
                    if k.verdict != Verdict.PASS and k.findings), None)
        if top is not None:
            tops.setdefault(family, Counter())[top] += 1
    counted = [f for f in FAMILIES if total[f]]
    score = sum(points[f] * passed[f] / total[f] for f in counted)
    return GradeRow(name=name, score=round(score, 2),
                    max_score=round(sum(points[f] for f in counted), 2),
                    families={f: FamilyCount(passed[f], total[f]) for f in FAMILIES},
                    cases=len(cases), passed=sum(passed.values()),
                    crashes=codes.get("crash", 0), timeouts=codes.get("timeout", 0),
                    errors=sum(codes.values()), report=f"{name}/index.html",
                    quirks=tuple(sorted({f.code.removeprefix("quirk:") for k in report.cases
                                         for f in k.findings if f.code.startswith("quirk:")})),
                    sha256=build.sha256 if build else report.renderer.get("sha256"),
                    build=build.summary if build else "prebuilt", build_error="",
                    build_log=f"{name}/build.log" if build else None,
                    causes={f: c.most_common(1)[0][0] for f, c in tops.items()},
                    mistakes=tuple(m.mistake for m in report.diagnosis.mistakes
                                   if not m.quirk))


def failed_build_row(name: str, build: BuildResult, families: list[str],
                     points: dict[str, float], cases: dict[str, int]) -> GradeRow:
    """The row of a submission that did not build: no case ran, no point."""
    return GradeRow(name=name, score=0.0, max_score=round(sum(points[f] for f in families), 2),
                    families={f: FamilyCount(0, cases.get(f, 0)) for f in FAMILIES},
                    cases=sum(cases.values()), passed=0, crashes=0, timeouts=0, errors=0,
                    report=f"{name}/build.log", quirks=(), sha256=build.sha256,
                    build=build.summary,
                    build_error=build.first_error, build_log=f"{name}/build.log", causes={})


def build_all(subs: list[Submission], runner: Runner, cache: Path, sandbox: Sandbox | None,
              limits: Limits) -> list[Submission]:
    """The submissions, those given as sources built (in the runner's pool, each build in the
    sandbox) and given their program, or the build that failed."""
    todo = {s.name: s.sources for s in subs if s.sources is not None}
    if not todo:
        return subs
    executor = runner.workers.executor
    futures = {name: executor.submit(build_sources, sources, cache, sandbox,
                                     runner.workers.threads or 1)
               for name, sources in todo.items()}
    built = []
    for sub in subs:
        if sub.sources is None:
            built.append(sub)
            continue
        result = futures[sub.name].result()
        if not runner.quiet:
            took = "cached" if result.cached else f"{result.seconds:.1f} s"
            print(f"{sub.name}: {result.summary} ({took})"
                  + (f": {result.first_error}" if result.first_error else ""), flush=True)
        renderer = None if result.program is None else CommandRenderer(
            [result.program], limits, name=sub.name, sandbox=sandbox)
        built.append(replace(sub, renderer=renderer, build=result))
    return built


def run_grade(subs: list[Submission], template: Matrix, out: Path, runner: Runner,
              cache: Path, points: dict[str, float], sandbox: Sandbox | None = None,
              limits: Limits = Limits()) -> list[GradeRow]:
    """Grades every submission into out (see the module's docstring); returns the rows.
    `cache` holds the reference's renders and the builds."""
    prov = provenance()
    start = time.perf_counter()
    reference = CachedRenderer(template.reference, cache / "renders")
    template = replace(template, reference=reference)
    cases, skips = template.cases()
    subs = build_all(subs, runner, cache / "builds", sandbox, limits)
    runnable = [s for s in subs if s.renderer is not None]
    # the references first, each case once: a case judged against itself renders the
    # reference (and for jittered cases the converged one) and reads it back from the cache
    Runner(runner.workers, quiet=runner.quiet).run(
        [Job(c, reference, reference, template.settings, label="reference ") for c in cases])
    jobs = [Job(c, s.renderer, reference, template.settings, label=f"{s.name}: ")
            for c in cases for s in runnable if s.renderer is not None]
    outputs = runner.run(jobs)
    seconds = time.perf_counter() - start
    case_counts = Counter(case_family(c.feature) for c in cases)
    families = [f for f in FAMILIES if case_counts[f]]
    rows = []
    for sub in subs:
        folder = out / sub.name
        if sub.renderer is None:
            assert sub.build is not None
            row = failed_build_row(sub.name, sub.build, families, points, dict(case_counts))
            report = None
        else:
            k = runnable.index(sub)
            mine = [place_case_under(folder, o, prov) for o in outputs[k::len(runnable)]]
            report = write_check(replace(template, candidate=sub.renderer), folder, mine,
                                 skips, seconds, prov)
            row = grade_row(sub.name, report, points, sub.build)
        folder.mkdir(parents=True, exist_ok=True)
        if sub.build is not None and sub.build.log is not None:
            shutil.copyfile(sub.build.log, folder / "build.log")
        write_json(folder / "results.json", gradescope_results(
            report, points, families, build=row.build if sub.build else "",
            build_error=row.build_error))
        rows.append(row)
    write_class_files(out, ClassGrades(tuple(rows), points, seconds, prov))
    return rows

