"""The primary-ray throughput benchmark on its own (harness/bench/throughput.py), with sizes,
ray count and parts to choose: `python -m raycheck.harness.cli.throughput`. `raycheck bench
--throughput` runs it at its defaults beside the other benchmarks."""
from __future__ import annotations

import json
import sys

from ..bench.throughput import RAYS, SIZES, WARM_RUNS, run_throughput
from ..pages.throughput import format_throughput
from .common import out_file, parser, positive_int, run

PROG = "python -m raycheck.harness.cli.throughput"


def main(argv: list[str] | None = None) -> int:
    ap = parser(PROG, "Primary-ray throughput of the tracer's BVH against brute force and "
                "Mitsuba/Embree on meshes of growing size, with build time, memory, render "
                "scaling and JIT, as tables.")
    ap.add_argument("--sizes", type=positive_int, nargs="+", default=list(SIZES))
    ap.add_argument("--rays", type=positive_int, default=RAYS)
    ap.add_argument("--warm-runs", type=positive_int, default=WARM_RUNS)
    ap.add_argument("--no-render", action="store_true")
    ap.add_argument("--no-mitsuba", action="store_true")
    ap.add_argument("--fresh-cache", action="store_true",
                    help="run in a child process with an empty Dr.Jit kernel cache")
    ap.add_argument("--json", type=out_file, help="also write the rows as JSON")
    args = ap.parse_args(argv)

    def throughput() -> int:
        rows = run_throughput(args.sizes, args.rays, args.warm_runs, render=not args.no_render,
                              mitsuba=not args.no_mitsuba, fresh_cache=args.fresh_cache)
        print(format_throughput(rows))
        if args.json:
            args.json.write_text(json.dumps(rows, indent=2))
        return 0

    return run(PROG, throughput)


if __name__ == "__main__":
    sys.exit(main())
