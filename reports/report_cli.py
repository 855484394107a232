"""`raycheck report [SCENE ...] --out DIR`."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tracer.scene import SceneError, load_scene

from .catalog import read_header
from .report import REPORT_SIZE, all_bundled, build_report


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
    args = ap.parse_args(argv)
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
        from .stress import run_stress

        run_stress(out=args.out)
    data = build_report(scenes, out, args.size, seed=args.seed, stress_link=stress, **kw)
    n = sum(len(c["kinds"]) for c in data["cases"])
    failed = sum(not k["passed"] for c in data["cases"] for k in c["kinds"])
    print(f"{n} comparisons, {failed} failed, {len(data['skipped'])} skipped, "
          f"{data['seconds']:.0f} s")
    print(f"report: {(out / 'index.html').resolve()}")
    if stress:
        print(f"stress: {(out / 'stress.html').resolve()}")
    return 0
