"""`raycheck bench`: benchmarks that print tables (reports/runs/bench.py)."""
from __future__ import annotations

import json

from ..renderers import BUILTIN
from .common import out_file, out_folder, parser, positive_int, run

PROG = "raycheck bench"


def main(argv: list[str]) -> int:
    ap = parser(PROG, "Time the bundled course scenes in each renderer, each in a fresh process "
                "with an empty Dr.Jit kernel cache (cold: load, trace, compile, first render; "
                "warm: the median of the next three renders).")
    ap.add_argument("--size", type=positive_int, default=800, metavar="N",
                    help="square image side (default %(default)s)")
    ap.add_argument("--renderer", action="append", choices=sorted(BUILTIN),
                    help="time only these (repeatable; default: tracer and mitsuba)")
    ap.add_argument("--json", type=out_file, metavar="FILE", help="also write every number as JSON")
    ap.add_argument("--html", type=out_folder, metavar="DIR",
                    help="also write the tables and plots as DIR/bench.html (and bench.json)")
    ap.add_argument("--versus", metavar="CMD",
                    help="instead: time the tracer's command line beside this course program "
                         "(e.g. ./a2), whole processes, warm kernel cache, on the course scenes "
                         "at 800x800 and 200x200 with -bounces 4 -shadows and all three images")
    ap.add_argument("--runs", type=positive_int, default=5, metavar="N",
                    help="paired runs per scene and size with --versus (default %(default)s)")
    ap.add_argument("--throughput", action="store_true",
                    help="also measure BVH and Mitsuba/Embree primary-ray throughput on meshes "
                         "of 1k-1M triangles, build time, memory, scaling and JIT (minutes)")
    ap.add_argument("--quiet", action="store_true",
                    help="no tables (the numbers go to --json or --html only)")
    args = ap.parse_args(argv)
    if args.versus is not None and (args.html or args.throughput or args.renderer):
        ap.error("--versus times whole processes on its own: no --html, --throughput or "
                 "--renderer with it")
    if args.versus is not None and not args.versus.split():
        ap.error("--versus: expected a command, found ''")

    def bench() -> int:
        from ..runs.bench import run_bench, run_versus

        log = (lambda text: None) if args.quiet else print
        if args.versus is not None:
            data = run_versus(args.versus, args.runs)
        else:
            data = run_bench(args.renderer or ["tracer", "mitsuba"], args.size, args.throughput,
                             log=log)
        if args.json:
            args.json.write_text(json.dumps(data, indent=2), encoding="utf-8")
        if args.html:
            from ..pages.benchpage import write_bench_page

            print(f"page: {write_bench_page(data, args.html).resolve()}")
        return 0

    return run(PROG, bench)
