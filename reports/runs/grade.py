"""`raycheck grade`: the full check of every submission of a class, and a class table.

All submissions' cases go through one executor, interleaved (case 1 of every submission,
then case 2, ...), so a submission that hangs holds at most its share of the workers for its
timeouts instead of stalling the class. The reference of each case is rendered once, before
the submissions run, into a render cache that every submission's cases then read
(results.CachedRenderer): with 200 submissions the reference costs 1/200 of what rendering it
per submission would.

Writes DIR/<name>/ (each submission's report, as `raycheck check` writes it), DIR/index.html
(the class table), DIR/grades.csv and DIR/grades.json.
"""
from __future__ import annotations

import csv
import io
import math
import os
import re
import time
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

from ..check_options import FAMILIES, FEATURES_HELP, feature_family
from ..pages.grades import grades_page
from ..provenance import provenance
from ..records import CheckEntry, CheckReport, FamilyCount, GradeRow, Verdict, to_json
from ..renderers import CommandRenderer, Limits
from ..renderers.command import program_file, split_command
from .check import write_check
from .matrix import Job, Matrix, Runner, place_case_under, write_json
from .results import CachedRenderer

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
    renderer: CommandRenderer


def submission(spec: str, limits: Limits) -> Submission:
    """NAME=SPEC or SPEC: an executable file, a folder holding an executable `a2`, or a
    command string; the name is NAME, else the folder's or file's name."""
    name, sep, rest = spec.partition("=")
    if sep and NAME.fullmatch(name) and rest:
        spec = rest
    else:
        name = ""
    path = Path(spec)
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
    slug = "".join(c if c.isalnum() or c in "-_." else "_" for c in name).lstrip(".") or "a2"
    return Submission(slug, CommandRenderer(argv, limits, name=slug))


def submissions(specs: list[str], limits: Limits) -> list[Submission]:
    """The submissions, with names made unique (alice, alice-2, ...)."""
    out: list[Submission] = []
    seen: set[str] = set()
    for spec in specs:
        sub = submission(spec, limits)
        name, n = sub.name, 1
        while name in seen or name in ("index.html", "grades.csv", "grades.json"):
            n += 1
            name = f"{sub.name}-{n}"
        seen.add(name)
        out.append(Submission(name, replace(sub.renderer, name=name)))
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


def grade_row(name: str, report: CheckReport, points: dict[str, float]) -> GradeRow:
    """A submission's line of the class table from its check.json: cases passed per feature
    family (a case passes when every image kind of it does), the score, and the cases that
    crashed, timed out or erred otherwise."""
    cases: dict[tuple[str, str], list[CheckEntry]] = {}
    for entry in report.cases:
        cases.setdefault((entry.scene, entry.feature), []).append(entry)
    passed = {f: 0 for f in FAMILIES}
    total = {f: 0 for f in FAMILIES}
    codes: dict[str, int] = {}
    for (_, feature), kinds in cases.items():
        family = feature_family(feature)
        total[family] += 1
        passed[family] += all(k.verdict == Verdict.PASS for k in kinds)
        errors = [k.findings[0].code for k in kinds
                  if k.verdict == Verdict.ERROR and k.findings]
        if errors:
            codes[errors[0]] = codes.get(errors[0], 0) + 1
    counted = [f for f in FAMILIES if total[f]]
    score = sum(points[f] * passed[f] / total[f] for f in counted)
    return GradeRow(name=name, score=round(score, 2),
                    max_score=round(sum(points[f] for f in counted), 2),
                    families={f: FamilyCount(passed[f], total[f]) for f in FAMILIES},
                    cases=len(cases), passed=sum(passed.values()),
                    crashes=codes.get("crash", 0), timeouts=codes.get("timeout", 0),
                    errors=sum(codes.values()), report=f"{name}/index.html",
                    sha256=report.renderer.get("sha256"))


def run_grade(subs: list[Submission], template: Matrix, out: Path, runner: Runner,
              render_cache: Path, points: dict[str, float]) -> list[GradeRow]:
    """Grades every submission into out (see the module's docstring); returns the rows."""
    prov = provenance()
    start = time.perf_counter()
    reference = CachedRenderer(template.reference, render_cache)
    template = replace(template, reference=reference)
    cases, skips = template.cases()
    # the references first, each case once: a case judged against itself renders the
    # reference (and for jittered cases the converged one) and reads it back from the cache
    Runner(runner.workers, quiet=runner.quiet).run(
        [Job(c, reference, reference, template.tolerance, label="reference ",
             realisations=template.realisations) for c in cases])
    jobs = [Job(c, s.renderer, reference, template.tolerance, label=f"{s.name}: ",
                realisations=template.realisations, causes=template.causes)
            for c in cases for s in subs]
    outputs = runner.run(jobs)
    seconds = time.perf_counter() - start
    rows = []
    for i, sub in enumerate(subs):
        folder = out / sub.name
        mine = [place_case_under(folder, o, prov) for o in outputs[i::len(subs)]]
        report = write_check(replace(template, candidate=sub.renderer), folder, mine, skips,
                             seconds, prov)
        rows.append(grade_row(sub.name, report, points))
    write_json(out / "grades.json", {"points": points, "submissions": to_json(rows),
                                     "seconds": seconds, "provenance": prov})
    (out / "grades.csv").write_text(grades_csv(rows), encoding="utf-8")
    (out / "index.html").write_text(grades_page(rows, points, prov), encoding="utf-8")
    return rows


def grades_csv(rows: list[GradeRow]) -> str:
    """One line per submission for a gradebook: name, score, per family passed and total."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["name", "score", "max_score",
                *[f"{f} {c}" for f in FAMILIES for c in ("passed", "total")],
                "cases", "passed", "crashes", "timeouts", "errors", "report"])
    for r in rows:
        w.writerow([r.name, r.score, r.max_score,
                    *[n for f in FAMILIES for n in (r.families[f].passed, r.families[f].total)],
                    r.cases, r.passed, r.crashes, r.timeouts, r.errors, r.report])
    return buf.getvalue()
