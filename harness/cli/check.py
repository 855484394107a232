"""`raycheck check --renderer CMD [SCENE ...] --out DIR`: any course renderer against the
reference, case by case."""
from __future__ import annotations

import argparse
import sys
from dataclasses import fields
from pathlib import Path

from ..check_options import FEATURES_HELP
from ..commands.check_config import CheckConfig
from ..judge.verdict import Tolerance
from ..pages.diagnosis import diagnosis_text
from ..records import CheckEntry, CheckReport, Verdict
from ..renderers import BUILTIN, Limits
from ..storage.distribution import DEFAULT_REALISATIONS
from .common import (
    UsageError,
    add_budget_options,
    add_case_size_option,
    add_run_options,
    add_sandbox_options,
    at_least_4,
    case_runner,
    out_folder,
    positive_float,
    run,
)
from .common import (
    parser as command_parser,
)

PROG = "raycheck check"


def parser() -> argparse.ArgumentParser:
    ap = command_parser(
        PROG, "Run a course renderer on every scene x feature case its scenes exercise and "
        "judge each image against the reference. Writes DIR/index.html (an overview matrix, "
        "then every comparison), DIR/check.json and DIR/junit.xml.",
        epilog="Exit status: 0 every case passes, 1 a case failed or erred, 2 bad usage.")
    ap.add_argument("scenes", nargs="*", type=Path,
                    help="scene files, or bundled scenes by name (course/arch); default: every "
                         "bundled course and feature scene")
    ap.add_argument("--renderer", required=True, metavar="CMD",
                    help="the candidate: a command taking the course's flags, split like a "
                         "shell would (\"python3 my_tracer.py\"), or tracer / mitsuba")
    ap.add_argument("--reference", default="tracer", choices=sorted(BUILTIN),
                    help="what the candidate is judged against (default: tracer, the exact "
                         "course reference; mitsuba: the independent engine)")
    ap.add_argument("--out", type=out_folder, required=True, metavar="DIR",
                    help="where index.html, check.json, junit.xml and cases/ go")
    add_case_size_option(ap)
    ap.add_argument("--features", metavar="LIST",
                    help=f"comma-separated features to run (of {FEATURES_HELP}; "
                         "default: all)")
    ap.add_argument("--timeout", type=positive_float, default=Limits.timeout_s, metavar="S",
                    help=f"wall-clock limit per render in seconds (default {Limits.timeout_s:g})")
    ap.add_argument("--tolerance", type=int, default=Tolerance.levels, metavar="LEVELS",
                    help="per-pixel tolerance in 8-bit levels (default %(default)s)")
    ap.add_argument("--fail-share", type=float, default=Tolerance.share, metavar="SHARE",
                    help="share of pixels allowed beyond the tolerance (default %(default)s)")
    ap.add_argument("--hard-limit", type=int, default=Tolerance.hard, metavar="LEVELS",
                    help="fail a case where any pixel differs by more levels (default: off)")
    add_budget_options(ap)
    ap.add_argument("--realisations", type=at_least_4, default=DEFAULT_REALISATIONS,
                    metavar="K", help="realisations of the reference's distribution that "
                    "jittered images are tested against (default %(default)s; cached)")
    ap.add_argument("--no-causes", dest="causes", action="store_false",
                    help="do not search the mistake that reproduces a failing image (faster; "
                         "the other findings stay)")
    ap.add_argument("--strict", action="store_true",
                    help="judge byte for byte with the course program, its quirks included: "
                         "an image that differs only where the course program has a quirk "
                         "no handout asks for (docs/course-format.md) fails instead of "
                         "passing with a note")
    add_sandbox_options(ap, "off")
    ap.add_argument("--gradescope", type=Path, metavar="FILE",
                    help="also write the results in Gradescope's autograder format (score, "
                         "a test per feature family with its failing cases' top findings)")
    ap.add_argument("--weights", type=Path, metavar="FILE",
                    help="points per feature family for --gradescope (TOML, as raycheck "
                         "grade reads it; default: grade's)")
    ap.add_argument("--quiet", action="store_true",
                    help="no progress (a bar with count and ETA on a terminal, else a line "
                         "per case)")
    add_run_options(ap)
    return ap


def config_of(args: argparse.Namespace) -> CheckConfig:
    """The check the parsed arguments ask for."""
    return CheckConfig(**{f.name: getattr(args, f.name) for f in fields(CheckConfig)} |
                       {"scenes": tuple(args.scenes), "sandbox_read": tuple(args.sandbox_read),
                        "size": tuple(args.size) if args.size else None})


def format_summary(report: CheckReport) -> str:
    """The diagnosis of the program (the mistakes found, grouped by cause; the failing cases
    none explains), then the table: scene x feature, the case's verdict and its worst number,
    the top finding under a failing case; then the counts."""
    by_case: dict[tuple[str, str], list[CheckEntry]] = {}
    for c in report.cases:
        by_case.setdefault((c.scene, c.feature), []).append(c)
    lines = [f"{'scene':<34} {'feature':<20} {'verdict':<7} worst"]
    rank = {Verdict.ERROR: 0, Verdict.FAIL: 1, Verdict.PASS: 2}
    for (scene, feature), kinds in by_case.items():
        worst = min(kinds, key=lambda k: (rank[k.verdict],
                                          -(k.metrics and k.metrics.beyond_tolerance or 0)))
        if worst.verdict == Verdict.ERROR:
            detail = f"{worst.kind}: {worst.findings[0].code}: {worst.findings[0].message}"
        elif worst.jitter is not None:
            detail = (worst.failures[0] if worst.failures else
                      f"{worst.kind}: {worst.jitter.failing_pixels} pixels beyond "
                      f"|z| {worst.jitter.pixel_threshold:.3g}")
        else:
            m = worst.metrics
            assert m is not None  # a kind that did not err was compared
            detail = (f"{worst.kind}: {m.beyond_tolerance or 0.0:.2%} beyond tolerance, "
                      f"max {m.max_levels} levels")
        quirk = next((k for k in kinds if k.verdict == Verdict.PASS and k.findings
                      and k.findings[0].code.startswith("quirk:")), None)
        verdict = "pass (quirk)" if quirk is not None and worst.verdict == Verdict.PASS \
            else str(worst.verdict)
        lines.append(f"{scene:<34} {feature:<20} {verdict:<7} {detail}")
        failing = next((k for k in kinds if k.verdict == Verdict.FAIL and k.findings), quirk)
        if failing:  # what is wrong (judge.findings), under its case's row
            top = failing.findings[0]
            causes = [f.code.removeprefix("cause:") for f in failing.findings
                      if f.code.startswith("cause:") and f.code != "cause:unexplained"]
            said = (f"explained by {' + '.join(causes)} (above)" if causes
                    else f"{top.code}: {top.message}")
            lines.append(f"{'':<64}{failing.kind}: {said}")
    s = report.summary
    quirks = sum(1 for c in report.cases if c.verdict == Verdict.PASS and c.findings
                 and c.findings[0].code.startswith("quirk:"))
    lines.append(f"{s.passed + s.failed + s.errors} comparisons: {s.passed} passed"
                 + (f" ({quirks} of them where only a quirk of the course program differs)"
                    if quirks else "")
                 + f", {s.failed} failed, {s.errors} errors; {len(report.skipped)} skipped")
    return "\n".join([diagnosis_text(report.diagnosis, len(by_case)), "", *lines])


def write_gradescope(path: Path, report: CheckReport, points: dict[str, float]) -> None:
    """The check's results.json for Gradescope, written whole or not at all."""
    import json
    import os

    from ..commands.gradescope import families_of, gradescope_results

    text = json.dumps(gradescope_results(report, points, families_of(report)), indent=1)
    staged = path.with_name(f".{path.name}.new")
    staged.write_text(text, encoding="utf-8")
    os.replace(staged, path)


def main(argv: list[str]) -> int:
    args = parser().parse_args(argv)

    def check() -> int:
        from ..commands.check import run_check
        from ..commands.grade import GradeInputError, read_points
        from ..storage.staging import ReplacedFolder

        try:
            points = read_points(args.weights)
        except GradeInputError as e:
            raise UsageError(str(e)) from None
        config = config_of(args)
        matrix = config.matrix()
        if (warning := config.sandbox_warning()) is not None:
            print(f"{PROG}: {warning}", file=sys.stderr)
        with ReplacedFolder(args.out, finishes_run=True) as staging, \
                case_runner(args, args.out) as runner:
            report = run_check(matrix, staging, runner)
        if args.gradescope is not None:
            write_gradescope(args.gradescope, report, points)
        print(format_summary(report))
        print(f"report: {(args.out / 'index.html').resolve()}")
        return 0 if report.passed else 1

    return run(PROG, check)
