"""The `raycheck` command: one entry point for rendering, scene analysis and reports."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

USAGE = """usage: raycheck COMMAND ...

commands:
  render <course flags>          render with raycheck's tracer (the course program's flags)
  reference <course flags>       render the same with Mitsuba 3 (mitsuba_ref)
  check --renderer CMD [SCENE ...] --out DIR
                                 any course renderer against the reference (the tracer in
                                 course mode), every case its scenes exercise; DIR/index.html,
                                 check.json, junit.xml; exit status 1 when a case fails
  compare <course flags> --out DIR
                                 both renderers, metrics, diff images and an HTML page;
                                 exit status 1 when a threshold fails
  report [SCENE ...] [--out DIR] the comparison suite over scenes x relevant features as an
                                 HTML report (default: every bundled scene, into out/report,
                                 with the stress and bench pages; --bench F: a saved bench)
  info SCENE                     what the scene uses and which flags can change its image
  export SCENE -o scene.xml      the scene as a Mitsuba XML file
  gallery [--out DIR]            render the bundled course scenes with the tracer
  bench [--size N] [--throughput] [--json F] [--html DIR]
                                 course scenes cold/warm in both renderers; BVH throughput
                                 (DIR/bench.html: the tables and plots)
  stress [--out DIR]             the extreme scenes in course, robust, float64 and Mitsuba
                                 against the float64 robust render (out/report/stress.html)
"""


def _info(argv: list[str]) -> int:
    from tracer.analysis import analyze, format_info
    from tracer.scene import SceneError, load_scene

    if len(argv) != 1:
        print("usage: raycheck info SCENE.txt", file=sys.stderr)
        return 2
    try:
        scene = load_scene(argv[0])
    except SceneError as e:
        print(f"raycheck info: error: {e}", file=sys.stderr)
        return 2
    print(format_info(scene, analyze(scene)))
    return 0


def _gallery(argv: list[str], prog: str) -> int:
    from tracer.scene import SceneError
    from tracer.scene.flags import FlagError

    from .runs.gallery import render_gallery

    ap = argparse.ArgumentParser(prog=prog)
    ap.add_argument("--out", type=Path, default=Path("out"))
    ap.add_argument("--size", type=int, nargs=2, metavar=("W", "H"))
    args = ap.parse_args(argv)
    out = args.out / "gallery"
    try:
        rows = render_gallery(out, tuple(args.size) if args.size else None)
    except (SceneError, FlagError) as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 2
    for name, seconds, path in rows:
        print(f"{name:<20} {seconds:6.2f} s  {path}")
    print(f"images in {out.resolve()}")
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print(USAGE)
        return 0 if argv else 2
    cmd, rest = argv[0], argv[1:]
    if cmd == "render":
        from tracer.cli import main as tracer_main

        return tracer_main(rest, prog="raycheck render")
    if cmd == "info":
        return _info(rest)
    if cmd == "gallery":
        return _gallery(rest, "raycheck gallery")
    if cmd == "bench":
        from .runs.bench import main as bench_main

        return bench_main(rest)
    if cmd == "stress":
        from .runs.stress import main as stress_main

        return stress_main(rest)
    if cmd == "reference":
        from mitsuba_ref.cli import main as reference_main

        return reference_main(rest, prog="raycheck reference")
    if cmd == "export":
        from mitsuba_ref.export import main_export

        return main_export(rest, prog="raycheck export")
    if cmd == "compare":
        from .compare_cli import main as compare_main

        return compare_main(rest)
    if cmd == "check":
        from .check_cli import main as check_main

        return check_main(rest)
    if cmd == "report":
        from .report_cli import main as report_main

        return report_main(rest)
    print(f"raycheck: error: unknown command '{cmd}'\n{USAGE}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
