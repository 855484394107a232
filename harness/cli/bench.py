"""`raycheck bench`: benchmarks that print tables (harness/bench/timing.py)."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

from ..renderers import BUILTIN
from ..renderers.command import split_command
from .common import UsageError, out_file, out_folder, parser, positive_int, run

PROG = "raycheck bench"


def main(argv: list[str]) -> int:
    ap = parser(PROG, "Time the bundled course scenes in each renderer, each in a fresh process "
                "with an empty Dr.Jit kernel cache (cold: load, trace, compile, first render; "
                "warm: the median of the next seven renders); optionally BVH throughput, the "
                "tracer's whole command line against a course program, and the generated "
                "performance tables (docs/performance.md) from that one run.")
    ap.add_argument("--size", type=positive_int, default=800, metavar="N",
                    help="square image side (default %(default)s)")
    ap.add_argument("--renderer", action="append", choices=sorted(BUILTIN),
                    help="time only these (repeatable; default: tracer and mitsuba)")
    ap.add_argument("--json", type=out_file, metavar="FILE", help="also write every number as JSON")
    ap.add_argument("--html", type=out_folder, metavar="DIR",
                    help="also write the tables and plots as DIR/bench.html (and bench.json)")
    ap.add_argument("--versus", metavar="CMD",
                    help="also time the tracer's command line beside this course program "
                         "(e.g. ./a2), whole processes, warm kernel cache, on the course scenes "
                         "at 800x800 and 200x200 with -bounces 4 -shadows and all three images")
    ap.add_argument("--runs", type=positive_int, default=5, metavar="N",
                    help="paired runs per scene and size with --versus (default %(default)s)")
    ap.add_argument("--throughput", action="store_true",
                    help="also measure BVH and Mitsuba/Embree primary-ray throughput on meshes "
                         "of 1k-1M triangles, build time, memory, scaling and JIT (minutes)")
    ap.add_argument("--readme", type=Path, metavar="FILE", action="append",
                    help="rewrite the tables of FILE (docs/performance.md) between its "
                         "<!-- bench:begin "
                         "--> and <!-- bench:end --> lines, or the short one of README.md "
                         "between <!-- bench-short:begin --> and <!-- bench-short:end -->, "
                         "from this run, naming the machine (needs --throughput and --versus: "
                         "all tables from one run); may be given twice")
    ap.add_argument("--quiet", action="store_true",
                    help="no tables (the numbers go to --json or --html only)")
    args = ap.parse_args(argv)
    if args.versus is not None:
        if not args.versus.split():
            ap.error("--versus: expected a command, found ''")
        try:
            program = split_command(args.versus)[0]  # as the renderer will split it
        except ValueError as e:  # unbalanced quotes
            ap.error(f"--versus: {e}")
        if shutil.which(program) is None:  # said before minutes of other tables
            ap.error(f"--versus: cannot run {program!r} (no such program)")
    if args.readme is not None:
        check_readme(ap, args)

    def bench() -> int:
        from ..bench.timing import run_bench

        log = (lambda text: None) if args.quiet else print
        data = run_bench(args.renderer or ["tracer", "mitsuba"], args.size, args.throughput,
                         args.versus, args.runs, log=log)
        if args.json:
            args.json.write_text(json.dumps(data.to_json(), indent=2), encoding="utf-8")
        if args.html:
            from ..pages.benchpage import write_bench_page

            print(f"page: {write_bench_page(data, args.html).resolve()}")
        for readme in args.readme or ():
            from ..pages.benchpage import ReadmeError, write_readme

            try:
                write_readme(readme, data)
            except (ReadmeError, OSError) as e:  # the run's numbers are in --json, if given
                raise UsageError(f"--readme {readme}: {e}") from None
            print(f"tables rewritten: {readme}")
        return 0

    return run(PROG, bench)


def check_readme(ap, args) -> None:
    """Before the run (minutes): --readme needs the tables of one whole run, and a file
    with the markers."""
    from ..pages.benchpage import ReadmeError, generated_spans

    if args.versus is None or not args.throughput or args.renderer or args.size != 800:
        ap.error("--readme: the performance tables are those of one full run: give --throughput "
                 "and --versus CMD, and neither --renderer nor --size")
    for readme in args.readme:
        try:
            generated_spans(readme.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError) as e:
            ap.error(f"--readme: cannot read {readme}: {getattr(e, 'strerror', None) or e}")
        except ReadmeError as e:
            ap.error(f"--readme: {readme}: {e}")
