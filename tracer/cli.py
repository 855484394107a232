"""`python -m raycheck.tracer <course flags>` and `raycheck render`: the course program's
command line.

Bad input of any kind ends in one line on stderr and exit status 2, before any output file is
touched; output files are written only after the whole render succeeded, all or nothing (see
scene.outputs.write_all).
Every limit that needs no scene (sizes, bounces, samples) is checked before
the scene is read, the scene's own limits while it is parsed, the rest before the kernel is
built.
"""
from __future__ import annotations

import sys
import time
from typing import Any

from .image import png_writer
from .kernel.backend import BackendError
from .options import OptionError, RenderOptions
from .process import run_command
from .render import Renderer
from .render_limits import LimitError, check_render_limits, check_scene_limits
from .scene import SceneError, load_scene
from .scene.flags import (
    CourseCommand,
    FlagError,
    budget_from_args,
    check_outputs,
    help_text,
    parse_course_flags,
    wants_help,
)
from .scene.outputs import write_images
from .scene.request import request_fields

EXTRA_OPTIONS: dict[str, type] = {"backend": str, "seed": str, "precision": str, "samples": str,
                                  "mode": str, "max-memory": str, "max-rays": str,
                                  "max-kernel-tests": str, "mistake": list,
                                  "float": bool,
                                  "quiet": bool}
USAGE = ("usage: raycheck render -input scene.txt [-output out.png] [-normals n.png] "
         "[-depth min max d.png] [-size w h] [-bounces n] [-shadows] [-jitter] [-filter] "
         "[--backend llvm|cuda] [--precision single|double] [--mode course|robust] [--seed N] "
         "[--samples N] [--mistake CODE[=VALUE]]... [--float] [--quiet] (--help: what each "
         "means)")
OPTIONS_HELP = {
    "--backend llvm|cuda": "Dr.Jit backend (default llvm, the CPU; cuda needs a GPU)",
    "--precision single|double": "float32, the course's arithmetic (default), or float64",
    "--mode course|robust": "course (default): the course program, quirks included; robust: "
                            "its numerical failures fixed",
    "--seed N": "seed of the -jitter samples (default 0: runs are reproducible)",
    "--samples N": "jittered samples per pixel with -jitter (default 16, the course's)",
    "--mistake CODE[=VALUE]": "render with a student's mistake switched on (course mode; "
                              "repeat it, or separate codes by commas, for several); the "
                              "codes: docs/findings.md, or an unknown one's error message",
    "--float": "also write each image's float values as .npy beside it (row 0 = top; depth "
               "(t-min)/(max-min), a missed ray's t being FLT_MAX)",
    "--max-memory SIZE": "refuse renders estimated to need more (default 8G; e.g. 16G, 512M)",
    "--max-rays N": f"refuse renders casting more rays (default 2^36 = {2**36})",
    "--max-kernel-tests N": "refuse scenes whose kernel would hold more sphere and plane "
                            "tests (default 1024; compile time grows with their square)",
    "--quiet": "no progress lines (shown on stderr once a render takes over a second)",
    "-h, --help": "this help",
}
SUMMARY = "Render a course scene with raycheck's tracer, as the course program does."


def options_from_args(cmd: CourseCommand) -> RenderOptions:
    given = cmd.extra.get("mistake", [])
    spelled = [code for item in (given if isinstance(given, list) else [str(given)])
               for code in item.split(",") if code.strip()]
    # the settings and mistakes as spelled: RenderOptions converts and checks them, in its
    # order (options.choice, mistakes.switches)
    settings: dict[str, Any] = {name: str(cmd.extra[name])
                                for name in ("backend", "precision", "mode")
                                if name in cmd.extra}
    settings["mistakes"] = tuple(spelled)
    try:
        return RenderOptions(**request_fields(cmd.request), **settings)
    except OptionError as e:
        raise FlagError(str(e)) from None


class Progress:
    """Prints progress on stderr once a render has taken more than a second."""

    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, fraction: float) -> None:
        elapsed = time.perf_counter() - self.start
        if self.quiet or elapsed < 1.0:
            return
        end = "\n" if fraction >= 1.0 else ("\r" if sys.stderr.isatty() else "\n")
        print(f"rendering: {fraction:4.0%} after {elapsed:.1f} s", end=end, file=sys.stderr,
              flush=True)
        self.shown = True


def run(argv: list[str]) -> int:
    cmd = parse_course_flags(argv, EXTRA_OPTIONS)
    check_outputs(cmd)
    opts = options_from_args(cmd)
    check_render_limits(opts)  # before the scene is read: no work for a request over a limit
    budget = budget_from_args(cmd)
    assert cmd.input is not None  # parse_course_flags requires -input here
    scene = load_scene(cmd.input, budget)
    check_scene_limits(scene, opts, budget)
    renderer = Renderer(scene, opts)
    progress = Progress(bool(cmd.extra.get("quiet")))
    result = renderer.render(progress)
    images = {kind: getattr(result, kind) for kind in cmd.outputs}
    write_images(cmd.outputs, images, png_writer, bool(cmd.extra.get("float")))
    return 0


def main(argv: list[str] | None = None, prog: str = "python -m raycheck.tracer") -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv:  # a usage error, on stderr
        print(USAGE.replace("raycheck render", prog), file=sys.stderr)
        return 2
    if wants_help(argv):  # asked for: on stdout, status 0 (`--help | head` too: run_command)
        return run_command(prog, lambda: print(help_text(prog, SUMMARY, OPTIONS_HELP)) or 0, (),
                           uses_cache=False)
    return run_command(prog, lambda: run(argv),
                       (FlagError, LimitError, BackendError, SceneError))
