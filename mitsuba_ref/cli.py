"""`python -m raycheck.mitsuba_ref <course flags>` and `raycheck reference`:
the course command line,
rendered by Mitsuba 3.

Same contract as the tracer's command: the course's single-dash flags (spec §10) plus our
double-dash options. Bad input of any kind ends in one line on stderr and exit status 2 before
any output file is touched (every limit that needs no scene is checked before the scene is
read); outputs are written only after the whole render succeeded, all or nothing: a PNG per
named image and, with --float, a .npy of its float values beside it (row 0 = top).
"""
from __future__ import annotations

import sys

from raycheck.tracer.process import run_command
from raycheck.tracer.scene import SceneError, load_scene
from raycheck.tracer.scene.errors import quote
from raycheck.tracer.scene.flags import (
    CourseCommand,
    FlagError,
    budget_from_args,
    check_outputs,
    help_text,
    parse_course_flags,
    wants_help,
)
from raycheck.tracer.scene.limits import scene_request_problem
from raycheck.tracer.scene.outputs import write_images
from raycheck.tracer.scene.request import request_fields

from .image import png_writer
from .variant import VARIANTS, VariantError

EXTRA_OPTIONS: dict[str, type] = {"variant": str, "backend": str, "seed": str, "samples": str,
                                  "offsets": str, "max-memory": str, "max-rays": str,
                                  "max-kernel-tests": str,
                                  "float": bool, "quiet": bool}
USAGE = ("usage: {prog} -input scene.txt [-output out.png] [-normals n.png] "
         "[-depth min max d.png] [-size w h] [-bounces n] [-shadows] [-jitter] [-filter] "
         "[--variant llvm_ad_rgb|cuda_ad_rgb] [--offsets course|mitsuba] [--seed N] "
         "[--samples N] [--float] [--quiet] (--help: what each means)")
OPTIONS_HELP = {
    "--variant llvm_ad_rgb|cuda_ad_rgb": "Mitsuba variant (default llvm_ad_rgb, the CPU)",
    "--offsets course|mitsuba": "shadow and mirror ray offsets: the course's 0.01 along the ray "
                                "(default) or Mitsuba's own",
    "--seed N": "seed of the -jitter samples (default 0)",
    "--samples N": "jittered samples per pixel with -jitter (default 16, the course's)",
    "--float": "also write each image's float values as .npy beside it (row 0 = top)",
    "--max-memory SIZE": "refuse renders estimated to need more (default 8G; e.g. 16G, 512M)",
    "--max-rays N": f"refuse renders casting more rays (default 2^36 = {2**36})",
    "--max-kernel-tests N": "refuse scenes over the tracer's kernel limit (default 1024)",
    "--quiet": "no timing line",
    "-h, --help": "this help",
}
SUMMARY = "Render a course scene with the Mitsuba 3 reference (mitsuba_ref)."
def options_from_args(cmd: CourseCommand):
    from .render import OptionError, ReferenceOptions

    variant = str(cmd.extra.get("variant", cmd.extra.get("backend", "llvm_ad_rgb")))
    if variant not in VARIANTS:
        raise FlagError(f"--variant: expected llvm_ad_rgb or cuda_ad_rgb, found "
                        f"{quote(variant)}")
    offsets = str(cmd.extra.get("offsets", "course"))
    if offsets not in ("course", "mitsuba"):
        raise FlagError(f"--offsets: expected course or mitsuba, found {quote(offsets)}")
    opts = ReferenceOptions(**request_fields(cmd.request), variant=variant, offsets=offsets)
    try:
        opts.check()
    except OptionError as e:
        raise FlagError(str(e)) from None
    return opts


def run(argv: list[str]) -> int:
    from .render import ReferenceRenderer

    cmd = parse_course_flags(argv, EXTRA_OPTIONS)
    check_outputs(cmd)
    opts = options_from_args(cmd)  # limits checked before the scene is read
    budget = budget_from_args(cmd)
    assert cmd.input is not None  # parse_course_flags requires -input unless told otherwise
    scene = load_scene(cmd.input, budget)
    problem = scene_request_problem(scene, opts, budget)  # the same limits as the tracer's
    if problem:
        raise FlagError(problem)
    renderer = ReferenceRenderer(scene, opts)
    try:
        result = renderer.render()
    finally:
        renderer.close()
    if not cmd.extra.get("quiet") and result.seconds + result.load_seconds > 1.0:
        print(f"rendered in {result.seconds:.2f} s (scene load {result.load_seconds:.2f} s)",
              file=sys.stderr)
    images = {kind: getattr(result, kind) for kind in cmd.outputs}
    write_images(cmd.outputs, images, png_writer, bool(cmd.extra.get("float")))
    return 0


def main(argv: list[str] | None = None, prog: str = "python -m raycheck.mitsuba_ref") -> int:
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    if not argv:  # a usage error, on stderr
        print(USAGE.format(prog=prog), file=sys.stderr)
        return 2
    if wants_help(argv):  # asked for: on stdout, status 0
        print(help_text(prog, SUMMARY, OPTIONS_HELP))
        return 0
    return run_command(prog, lambda: run(argv), (FlagError, SceneError, VariantError))
