"""`python -m tracer <course flags>` and `raycheck render`: the course program's command line.

Bad input of any kind ends in one line on stderr and exit status 2, before any output file is
touched; output files are written only after the whole render succeeded, each atomically.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from .backend import BackendError
from .image import write_npy, write_png
from .limits import LimitError
from .render import DEFAULT_SEED, JITTER_SAMPLES, RenderOptions, RenderResult, Renderer
from .scene import SceneError, load_scene
from .scene.flags import CourseArgs, FlagError, parse_course_flags

EXTRA_OPTIONS: dict[str, type] = {"backend": str, "seed": str, "precision": str, "samples": str,
                                  "float": bool,
                                  "quiet": bool}
USAGE = ("usage: raycheck render -input scene.txt [-output out.png] [-normals n.png] "
         "[-depth min max d.png] [-size w h] [-bounces n] [-shadows] [-jitter] [-filter] "
         "[--backend llvm|cuda] [--precision single|double] [--seed N] [--samples N] [--float] "
         "[--quiet]")


class UsageError(Exception):
    pass


def options_from_args(args: CourseArgs) -> RenderOptions:
    seed_text = str(args.extra.get("seed", DEFAULT_SEED))
    if not seed_text.isdigit():
        raise FlagError(f"--seed: expected a non-negative integer, found '{seed_text}'")
    samples_text = str(args.extra.get("samples", JITTER_SAMPLES))
    if not samples_text.isdigit():
        raise FlagError(f"--samples: expected a positive integer, found '{samples_text}'")
    return RenderOptions(
        width=args.width, height=args.height, bounces=args.bounces, shadows=args.shadows,
        jitter=args.jitter, filter=args.filter,
        want_color=args.output is not None, want_normals=args.normals is not None,
        want_depth=args.depth_file is not None,
        depth_min=args.depth_min, depth_max=args.depth_max, seed=int(seed_text),
        backend=str(args.extra.get("backend", "llvm")),
        precision=str(args.extra.get("precision", "single")),
        samples=int(samples_text),
    )


def check_outputs(args: CourseArgs) -> None:
    outs = args.outputs()
    if not outs:
        raise FlagError("nothing to write: give -output, -normals or -depth")
    for p in outs:
        if p.suffix.lower() != ".png":
            raise FlagError(f"output file names must end in .png, found '{p}'")
        parent = p.parent if str(p.parent) else Path(".")
        if not parent.is_dir():
            raise FlagError(f"folder of output file '{p}' does not exist")


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


def write_outputs(args: CourseArgs, result: RenderResult, floats: bool) -> None:
    for path, image in ((args.output, result.color), (args.normals, result.normals),
                        (args.depth_file, result.depth)):
        if path is None or image is None:
            continue
        write_png(path, image)
        if floats:
            write_npy(path.with_suffix(".npy"), image)


def run(argv: list[str]) -> int:
    args = parse_course_flags(argv, EXTRA_OPTIONS)
    check_outputs(args)
    opts = options_from_args(args)
    scene = load_scene(args.input)
    renderer = Renderer(scene, opts)
    progress = Progress(bool(args.extra.get("quiet")))
    result = renderer.render(progress)
    write_outputs(args, result, bool(args.extra.get("float")))
    return 0


def main(argv: list[str] | None = None, prog: str = "python -m tracer") -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print(USAGE.replace("raycheck render", prog))
        return 0 if argv else 2
    try:
        return run(argv)
    except (FlagError, LimitError, BackendError) as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
    except SceneError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
    except OSError as e:
        print(f"{prog}: error: {e.filename or ''}: {e.strerror}", file=sys.stderr)
    return 2
