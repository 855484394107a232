"""The `raycheck` command: one entry point for rendering, scene analysis and reports."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

USAGE = """usage: raycheck COMMAND ...

commands:
  render <course flags>     render with raycheck's tracer (same flags as the course program)
  info SCENE                what the scene uses and which flags can change its image
  gallery [--out DIR]       render the bundled course scenes with the tracer
  report [--out DIR]        the comparison report (not yet available: renders the gallery)
  bench [--size N]          time the bundled course scenes (cold and warm) and print a table
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

    from .gallery import render_gallery

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
        from .bench import main as bench_main

        return bench_main(rest)
    if cmd == "report":
        print("raycheck report: the comparison report is not yet available; "
              "rendering the bundled scenes with the tracer instead")
        return _gallery(rest, "raycheck report")
    print(f"raycheck: error: unknown command '{cmd}'\n{USAGE}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
