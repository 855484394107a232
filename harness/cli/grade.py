"""`raycheck grade SUBMISSION ... --out DIR`: the full check of every submission of a class,
a class table and a gradebook file (harness/commands/grade.py)."""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from ..check_options import FEATURES_HELP
from ..renderers import BUILTIN, CommandRenderer, Limits
from .common import (
    UsageError,
    add_case_size_option,
    add_run_options,
    add_sandbox_options,
    case_runner,
    out_folder,
    positive_float,
    run,
)
from .common import (
    parser as command_parser,
)

PROG = "raycheck grade"


def parser() -> argparse.ArgumentParser:
    from ..commands.grade import DEFAULT_POINTS

    keys = {f: f if f.isalpha() else f'"{f}"' for f in DEFAULT_POINTS}  # TOML quotes "a+b"
    points = "\n  ".join(f"{keys[f]} = {p}" for f, p in DEFAULT_POINTS.items())
    ap = command_parser(
        PROG, "Check every submission of a class against the reference, each on every case "
        "of the scenes, through one pool of workers. Writes DIR/<name>/ (each submission's "
        "report, as raycheck check writes it), DIR/index.html (the class table, sortable), "
        "DIR/grades.csv and DIR/grades.json.",
        epilog="A weights file is TOML with one table, points per feature family (a family "
               f"not listed gets 0); the default:\n  [points]\n  {points}\n"
               "Exit status: 0 every submission was graded (whatever its grade), 2 bad usage.")
    ap.add_argument("submissions", nargs="+", metavar="SUBMISSION",
                    help="sources (a folder, a .zip or .tar.gz, a git repository or bundle: "
                         "built with CMake), an executable, a folder holding an executable "
                         "a2, or a command string (\"python3 alice/tracer.py\"); "
                         "NAME=SUBMISSION names its row")
    ap.add_argument("--scenes", nargs="+", type=Path, metavar="SCENE", default=[],
                    help="scene files, or bundled scenes by name (course/arch); default: every "
                         "bundled course and feature scene")
    ap.add_argument("--out", type=out_folder, required=True, metavar="DIR",
                    help="where the reports, index.html and grades.csv/json go")
    add_case_size_option(ap)
    ap.add_argument("--weights", type=Path, metavar="FILE",
                    help="points per feature family (TOML; default below)")
    ap.add_argument("--features", metavar="LIST",
                    help=f"comma-separated features to run (of {FEATURES_HELP}; default: "
                         "all)")
    ap.add_argument("--reference", default="tracer", choices=sorted(BUILTIN),
                    help="what submissions are judged against (default: tracer)")
    ap.add_argument("--timeout", type=positive_float, default=Limits.timeout_s, metavar="S",
                    help=f"wall-clock limit per render in seconds (default {Limits.timeout_s:g})")
    ap.add_argument("--quiet", action="store_true", help="no progress")
    ap.add_argument("--strict", action="store_true",
                    help="count the course program's quirks too (by default a submission is "
                         "scored on what the handouts require; its row lists the quirks it "
                         "differs on)")
    add_sandbox_options(ap, "auto")
    add_run_options(ap)
    return ap


def main(argv: list[str]) -> int:
    args = parser().parse_args(argv)

    def grade() -> int:
        from ..commands.check_config import CheckConfig
        from ..commands.grade import GradeInputError, read_points, run_grade, submissions
        from ..storage.results import cache_folder
        from ..storage.staging import ReplacedFolder

        limits = Limits(timeout_s=args.timeout)
        try:
            points = read_points(args.weights)
            subs = submissions(args.submissions, limits)
        except GradeInputError as e:
            raise UsageError(str(e)) from None
        config = CheckConfig(reference=args.reference, scenes=tuple(args.scenes),
                             size=tuple(args.size) if args.size else None,
                             features=args.features, timeout=args.timeout, strict=args.strict,
                             sandbox=args.sandbox, sandbox_read=tuple(args.sandbox_read))
        subs = [replace(s, renderer=s.renderer and config.sandboxed(s.renderer))
                for s in subs]
        template = config.matrix(candidate=CommandRenderer(["a2"], limits))
        sandbox = config.box()
        if (warning := config.sandbox_warning()) is not None:
            print(f"{PROG}: {warning}", file=sys.stderr)
        with ReplacedFolder(args.out, finishes_run=True) as staging, \
                case_runner(args, args.out) as runner:
            rows = run_grade(subs, template, staging, runner, cache_folder(args.out), points,
                             sandbox, limits)
        width = max(len(r.name) for r in rows)
        for r in rows:
            what = (f"build failed: {r.build_error}" if r.build_error else
                    f"{r.passed}/{r.cases} cases passed, {r.crashes} crashes, "
                    f"{r.timeouts} timeouts" + (f"; {r.build}" if r.build != "prebuilt"
                                                else ""))
            print(f"{r.name:<{width}}  {r.score:>6g}/{r.max_score:g}  {what}")
        print(f"class page: {(args.out / 'index.html').resolve()}")
        return 0

    return run(PROG, grade)
