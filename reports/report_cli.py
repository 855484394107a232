"""`raycheck report [SCENE ...] --out DIR`."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tracer.scene import SceneError, load_scene

from .catalog import read_header
from .renderers import MitsubaRenderer, TracerRenderer
from .runs.report import REPORT_SIZE, all_bundled, build_report


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="raycheck report")
    ap.add_argument("scenes", nargs="*", type=Path, help="scene files (default: all bundled)")
    ap.add_argument("--out", type=Path, default=Path("out"),
                    help="the report goes to OUT/report (default out/report)")
    ap.add_argument("--size", type=int, default=REPORT_SIZE,
                    help="image side for scenes without a # size line")
    ap.add_argument("--no-sweeps", action="store_true", help="skip the error-against-time sweeps")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-stress", action="store_true",
                    help="skip the extreme scenes' stress page (out/report/stress.html)")
    ap.add_argument("--bench", type=Path, metavar="FILE",
                    help="the benchmark page (out/report/bench.html) from this `raycheck bench "
                         "--json` file instead of timing the course scenes now")
    ap.add_argument("--no-bench", action="store_true", help="skip the benchmark page")
    args = ap.parse_args(argv)
    bench_data = None
    if args.bench:
        try:
            bench_data = json.loads(args.bench.read_text(encoding="utf-8"))
            if not isinstance(bench_data, dict) or not isinstance(bench_data.get("course"), list):
                raise ValueError("no course table")
        except (OSError, ValueError) as e:
            print(f"raycheck report: error: {args.bench}: not a raycheck bench JSON file ({e})",
                  file=sys.stderr)
            return 2
    try:
        for p in args.scenes:
            load_scene(p)
    except SceneError as e:
        print(f"raycheck report: error: {e}", file=sys.stderr)
        return 2
    scenes = [read_header(p) for p in args.scenes] or all_bundled()
    out = args.out / "report"
    kw = {"sweep_scenes": ()} if args.no_sweeps else {}
    stress = not args.no_stress and not args.scenes
    if stress:
        from .runs.stress import run_stress

        run_stress(out=args.out)
    bench = not args.no_bench and (bench_data is not None or not args.scenes)
    if bench:
        from .pages.benchpage import write_bench_page
        from .runs.bench import run_bench

        if bench_data is None:
            print("bench: the course scenes in both renderers")
            bench_data = run_bench(["tracer", "mitsuba"])
        write_bench_page(bench_data, out)
    data = build_report(scenes, out, TracerRenderer(), MitsubaRenderer(), args.size,
                        seed=args.seed, stress_link=stress, bench_link=bench, **kw)
    counts = data["summary"]
    print(f"{sum(counts.values())} comparisons, {counts['fail']} failed, {counts['error']} "
          f"errors, {len(data['skipped'])} skipped, {data['seconds']:.0f} s")
    print(f"report: {(out / 'index.html').resolve()}")
    if stress:
        print(f"stress: {(out / 'stress.html').resolve()}")
    if bench:
        print(f"bench: {(out / 'bench.html').resolve()}")
    return 0
