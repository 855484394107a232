"""`raycheck check --renderer CMD [SCENE ...] --out DIR`: any course renderer against the
reference, case by case."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..judge.verdict import Tolerance
from ..renderers import BUILTIN, Limits, renderer_from_spec
from ..runs.distribution import DEFAULT_REALISATIONS
from ..check_options import FEATURES_HELP, feature_family
from ..runs.matrix import Matrix
from .common import (
    UsageError, add_budget_options, add_case_size_option, add_run_options, at_least_4,
    budget_of, case_runner, out_folder, parser as command_parser, positive_float,
    run, scene_headers,
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
    ap.add_argument("--quiet", action="store_true",
                    help="no progress (a bar with count and ETA on a terminal, else a line "
                         "per case)")
    add_run_options(ap)
    return ap


def parse_features(text: str | None) -> frozenset[str] | None:
    """--features LIST as a set of families (None: every feature)."""
    if not text:
        return None
    names = [f.strip() for f in text.split(",") if f.strip()]
    unknown = [n for n in names if feature_family(n) is None]
    if unknown:
        raise UsageError(f"--features: unknown {', '.join(unknown)} "
                         f"(expected some of {FEATURES_HELP})")
    return frozenset(feature_family(n) for n in names) or None


def matrix_from_args(args: argparse.Namespace) -> Matrix:
    """The validated matrix of parsed arguments (args.out may be None: no output folder);
    the pytest plugin builds its matrix here too, so both check options alike."""
    features = parse_features(args.features)
    if args.tolerance < 0 or not 0 <= args.fail_share <= 1 or (
            args.hard_limit is not None and args.hard_limit < 0):
        raise UsageError("--tolerance and --hard-limit must be >= 0, --fail-share in 0..1")
    from ..runs.report import all_bundled

    scenes = scene_headers(args.scenes) or all_bundled()
    try:
        candidate = renderer_from_spec(args.renderer, Limits(timeout_s=args.timeout),
                                       budget_of(args))
    except ValueError as e:
        raise UsageError(f"--renderer: {e}") from None
    reference = renderer_from_spec(args.reference, budget=budget_of(args))
    tolerance = Tolerance(args.tolerance, args.fail_share, args.hard_limit)
    return Matrix(scenes, candidate, reference, tolerance,
                  tuple(args.size) if args.size else None, features=features,
                  budget=budget_of(args), realisations=args.realisations)


def format_summary(data: dict) -> str:
    """The terminal table: scene x feature, the case's verdict and its worst number."""
    by_case: dict[tuple[str, str], list[dict]] = {}
    for c in data["cases"]:
        by_case.setdefault((c["scene"], c["feature"]), []).append(c)
    lines = [f"{'scene':<34} {'feature':<20} {'verdict':<7} worst"]
    rank = {"error": 0, "fail": 1, "pass": 2}
    for (scene, feature), kinds in by_case.items():
        worst = min(kinds, key=lambda k: (rank[k["verdict"]],
                                          -(k["metrics"].get("beyond_tolerance") or 0)))
        if worst["verdict"] == "error":
            detail = f"{worst['kind']}: {worst['findings'][0]['code']}: " \
                     f"{worst['findings'][0]['message']}"
        elif worst["jitter"]:
            detail = (worst["failures"][0] if worst["failures"] else
                      f"{worst['kind']}: {worst['jitter']['failing_pixels']} pixels beyond "
                      f"|z| {worst['jitter']['pixel_threshold']:.3g}")
        else:
            m = worst["metrics"]
            detail = (f"{worst['kind']}: {m['beyond_tolerance']:.2%} beyond tolerance, "
                      f"max {m['max_levels']} levels")
        lines.append(f"{scene:<34} {feature:<20} {worst['verdict']:<7} {detail}")
        failing = next((k for k in kinds if k["verdict"] == "fail" and k["findings"]), None)
        if failing:  # what is wrong (judge.findings), under its case's row
            top = failing["findings"][0]
            lines.append(f"{'':<64}{failing['kind']}: {top['code']}: {top['message']}")
    s = data["summary"]
    lines.append(f"{sum(s.values())} comparisons: {s['pass']} passed, {s['fail']} failed, "
                 f"{s['error']} errors; {len(data['skipped'])} skipped")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    args = parser().parse_args(argv)

    def check() -> int:
        from ..runs.check import run_check
        from ..runs.staging import replaced_folder

        matrix = matrix_from_args(args)
        with replaced_folder(args.out) as staging, case_runner(args, args.out) as runner:
            data = run_check(matrix, staging, runner)
        print(format_summary(data))
        print(f"report: {(args.out / 'index.html').resolve()}")
        s = data["summary"]
        return 0 if s["fail"] == 0 and s["error"] == 0 else 1

    return run(PROG, check)
