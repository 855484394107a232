"""`raycheck report [SCENE ...] --out DIR`: the comparison suite (harness/commands/report.py),
with the stress and benchmark pages."""
from __future__ import annotations

import shutil
import time
from pathlib import Path

from ..bench.records import BenchRun
from ..commands.report import REPORT_SIZE
from ..storage.distribution import DEFAULT_REALISATIONS
from .common import (
    UsageError,
    add_budget_options,
    add_run_options,
    at_least_4,
    budget_of,
    case_runner,
    out_folder,
    parser,
    positive_int,
    run,
    unsigned_int,
)

PROG = "raycheck report"
MAX_SEED = 2**64 - 1


def main(argv: list[str]) -> int:
    ap = parser(PROG, "Run the tracer against the Mitsuba reference on every scene x feature "
                "case the scenes exercise and write an HTML report with error-against-time "
                "plots, provenance, report.json and junit.xml; with the bundled scenes also "
                "the stress and benchmark pages.",
                epilog="Exit status: 0 every comparison passes, 1 one fails or errs, 2 bad "
                       "usage.")
    ap.add_argument("scenes", nargs="*", type=Path, metavar="SCENE",
                    help="scene files, or bundled scenes by name (course/arch); default: every "
                         "bundled course and feature scene")
    ap.add_argument("--out", type=out_folder, default=out_folder("out"), metavar="OUT",
                    help="the report goes to OUT/report (default: out)")
    ap.add_argument("--size", type=positive_int, default=REPORT_SIZE, metavar="N",
                    help="image side for scenes without a # size line (default %(default)s)")
    ap.add_argument("--seed", type=unsigned_int(MAX_SEED), default=0,
                    help="seed of the jittered cases (default 0)")
    ap.add_argument("--realisations", type=at_least_4, default=DEFAULT_REALISATIONS,
                    metavar="K", help="realisations of Mitsuba's distribution that jittered "
                    "images are tested against (default %(default)s; cached)")
    ap.add_argument("--no-sweeps", action="store_true", help="skip the error-against-time sweeps")
    ap.add_argument("--no-stress", action="store_true",
                    help="skip the extreme scenes' stress page (OUT/report/stress.html)")
    ap.add_argument("--bench", type=Path, metavar="FILE",
                    help="the benchmark page (OUT/report/bench.html) from this `raycheck bench "
                         "--json` file instead of timing the course scenes now")
    ap.add_argument("--no-bench", action="store_true", help="skip the benchmark page")
    ap.add_argument("--findings", type=Path, metavar="FILE",
                    help="the findings page (OUT/report/findings.html: which bug the top "
                         "finding names) from this `tools/bench_findings.py --json` file")
    add_budget_options(ap)
    ap.add_argument("--quiet", action="store_true", help="no progress lines")
    add_run_options(ap)
    args = ap.parse_args(argv)
    return run(PROG, lambda: report(args))


def _bench_file(path: Path) -> BenchRun:
    from ..pages.benchpage import BenchFileError, read_bench

    try:
        return read_bench(path)
    except BenchFileError as e:
        raise UsageError(str(e)) from None


def _findings_file(path: Path) -> dict:
    from ..pages.findingspage import FindingsFileError, read_findings

    try:
        return read_findings(path)
    except FindingsFileError as e:
        raise UsageError(str(e)) from None


def report(args) -> int:
    from ..catalog import scenes_named
    from ..commands.report import (
        SWEEP_SCENES,
        ReportPlan,
        run_comparisons,
        run_sweeps,
        write_report,
    )
    from ..renderers import MitsubaRenderer, TracerRenderer
    from ..storage.staging import ReplacedFolder

    bench_data = _bench_file(args.bench) if args.bench else None
    findings_data = _findings_file(args.findings) if args.findings else None
    scenes = scenes_named(args.scenes)
    log = (lambda line: None) if args.quiet else (lambda line: print(line, flush=True))
    out = args.out / "report"
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out: {out} exists and is not a folder")
    sweep_scenes = () if args.no_sweeps else SWEEP_SCENES
    stress = not args.no_stress and not args.scenes
    bench = not args.no_bench and (bench_data is not None or not args.scenes)
    budget = budget_of(args)
    candidate, reference = TracerRenderer(budget=budget), MitsubaRenderer(budget=budget)
    plan = ReportPlan(tuple(scenes), candidate, reference, args.size, sweep_scenes, args.seed,
                      budget, args.realisations)
    plan.check_limits()
    phases: dict[str, float] = {}
    pages = {p for p, made in (("bench.html", bench),
                               ("findings.html", findings_data is not None)) if made}
    # the comparisons first, swapped in whole as soon as they are done (the old report stays
    # whole until then); the stress page and the sweeps, which take as long again, follow in
    # a second swap
    more = stress or plan.swept()
    with ReplacedFolder(out, finishes_run=not more) as staging, \
            case_runner(args, out) as runner:
        start = time.perf_counter()
        if bench:
            from ..commands.report import course_bench
            from ..pages.benchpage import write_bench_page

            write_bench_page(bench_data or course_bench(log), staging)
        if findings_data is not None:
            from ..pages.findingspage import write_findings_page

            write_findings_page(findings_data, staging)
        phases["other pages"] = time.perf_counter() - start
        done = run_comparisons(plan, staging, args.quiet, runner)
        start = time.perf_counter()
        data = write_report(plan, staging, done, [], frozenset(pages))
        phases["comparisons"] = done.seconds + time.perf_counter() - start
    if more:
        log(f"report: {(out / 'index.html').resolve()} (the comparisons); the "
            + " and ".join(["stress page"] * stress + ["error-against-time sweeps"]
                           * bool(plan.swept())) + " follow")
        with ReplacedFolder(out, finishes_run=True) as staging:
            shutil.copytree(out, staging, dirs_exist_ok=True)
            if stress:
                from ..commands.stress import run_stress

                log("stress: the extreme scenes")
                start = time.perf_counter()
                run_stress(folder=staging)
                phases["stress"] = time.perf_counter() - start
                pages.add("stress.html")
            start = time.perf_counter()
            points = run_sweeps(plan, log)
            phases["sweeps"] = time.perf_counter() - start
            data = write_report(plan, staging, done, points, frozenset(pages))
    counts = data["summary"]
    print(f"{sum(counts.values())} comparisons, {counts['fail']} failed, {counts['error']} "
          f"errors, {len(data['skipped'])} skipped, {data['seconds']:.0f} s")
    log("phases: " + ", ".join(f"{name} {seconds:.1f} s" for name, seconds in phases.items()))
    print(f"report: {(out / 'index.html').resolve()}")
    for page in sorted(pages):
        print(f"{page.removesuffix('.html')}: {(out / page).resolve()}")
    return 1 if counts["fail"] or counts["error"] else 0
