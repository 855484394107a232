"""`raycheck info SCENE`: what a scene uses and which of -shadows, -bounces, -jitter, -filter
can change its image."""
from __future__ import annotations

from pathlib import Path

from .common import parser, run

PROG = "raycheck info"


def main(argv: list[str]) -> int:
    ap = parser(PROG, "Print what a scene uses (primitives, lights, reflective materials, cube "
                "map) and which of -shadows, -bounces, -jitter, -filter can change its image.")
    ap.add_argument("scene", type=Path, help="a course scene file (.txt)")
    args = ap.parse_args(argv)

    def info() -> int:
        from raycheck.tracer.analysis import analyze, format_info
        from raycheck.tracer.scene import load_scene

        scene = load_scene(args.scene)
        print(format_info(scene, analyze(scene)))
        return 0

    return run(PROG, info)
