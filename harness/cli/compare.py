"""`raycheck compare <course flags> --out DIR`: one case, both renderers, one HTML page."""
from __future__ import annotations

import sys
from argparse import ArgumentTypeError
from dataclasses import replace

from raycheck.tracer.scene.flags import (
    budget_from_args,
    check_output_path,
    help_text,
    parse_course_flags,
    wants_help,
)
from raycheck.tracer.scene.request import KINDS

from ..records import Role, Verdict
from .common import UsageError, out_folder, run

PROG = "raycheck compare"
OPTIONS_HELP = {
    "--out DIR": "where the case page, its pictures and maps go (required)",
    "--seed N": "seed of the -jitter samples (default 0)",
    "--quiet": "print only the verdict line per image kind and the page",
    "--max-memory SIZE": "refuse renders estimated to need more memory (default 8G)",
    "--max-rays N": "refuse renders casting more rays (default 2^36)",
    "--max-kernel-tests N": "refuse scenes whose kernel holds more sphere and plane tests "
                            "(default 1024)",
    "-h, --help": "this help",
}
SUMMARY = ("Render one case with the tracer and the Mitsuba reference and compare them: every "
           "metric per image kind, a verdict (exit status 1 when a threshold fails), and "
           "DIR/index.html with both renders, a flip view, difference and SSIM maps. The images "
           "named by -output/-normals/-depth are compared and written as the tracer renders "
           "them; without any, every kind is compared. Without -depth the depth range comes "
           "from the scene's header, else from its visible hits.")


def case_from_args(argv: list[str]):
    from raycheck.tracer.render_limits import check_scene_limits
    from raycheck.tracer.scene import load_scene

    from ..cases import Case, feature_name
    from ..catalog import read_header, with_depth_range

    cmd = parse_course_flags(argv, {"out": str, "seed": str, "max-memory": str,
                                    "max-rays": str, "max-kernel-tests": str, "quiet": bool})
    if "out" not in cmd.extra:
        raise UsageError("--out DIR is required")
    try:
        out = out_folder(str(cmd.extra["out"]))
    except ArgumentTypeError as e:
        raise UsageError(f"--out: {e}") from None
    request = cmd.request if cmd.outputs else cmd.request.with_kinds(KINDS)
    for path in cmd.outputs.values():  # writable, before any work
        check_output_path(path, ".png", ".exr")
    problem = request.limit_problem()  # before the scene is read: no work over a limit
    if problem:
        raise UsageError(problem)
    assert cmd.input is not None  # parse_course_flags requires -input
    budget = budget_from_args(cmd)
    scene = load_scene(cmd.input, budget)  # bad scenes fail here, before any work
    check_scene_limits(scene, request, budget)
    header = read_header(cmd.input)
    if "depth" in cmd.outputs:
        header = replace(header, depth_range=request.depth_range, depth_origin="-depth")
    else:
        header = with_depth_range(header)
        assert header.depth_range is not None  # with_depth_range gives every scene one
        request = replace(request, depth_min=header.depth_range[0],
                          depth_max=header.depth_range[1])
    return Case(header, feature_name(request), request), out, budget, cmd


def main(argv: list[str]) -> int:
    if wants_help(argv):
        print(help_text(PROG, SUMMARY, OPTIONS_HELP))
        return 0
    if not argv:
        print(f"usage: {PROG} -input scene.txt [course flags] --out DIR (--help: more)",
              file=sys.stderr)
        return 2
    return run(PROG, lambda: compare(argv))


def compare(argv: list[str]) -> int:
    from ..case_settings import CaseSettings
    from ..judge.verdict import ENGINES_JITTER_TEST, ENGINES_TOLERANCE
    from ..pipeline.case import run_case
    from ..pipeline.matrix import write_case
    from ..provenance import provenance
    from ..renderers import MitsubaRenderer, TracerRenderer
    from ..storage.staging import ReplacedFolder

    case, out, budget, cmd = case_from_args(argv)
    quiet = bool(cmd.extra.get("quiet"))
    result = run_case(case, TracerRenderer(budget=budget), MitsubaRenderer(budget=budget),
                      CaseSettings(ENGINES_TOLERANCE, warm=True,
                                   jitter_test=ENGINES_JITTER_TEST))
    with ReplacedFolder(out, finishes_run=True) as staging:
        write_case(result, staging, provenance(case.request.seed))
    if cmd.outputs and Role.CANDIDATE in result.images:  # the course flags' own files
        from raycheck.tracer.image import png_writer
        from raycheck.tracer.scene.outputs import write_images

        write_images(cmd.outputs, result.images[Role.CANDIDATE], png_writer, floats=False)
    for k in result.kinds:
        m = k.metrics
        if k.verdict == Verdict.ERROR or m is None:
            print(f"{k.kind:<8} error  {'; '.join(k.failures)}")
            continue
        print(f"{k.kind:<8} {k.verdict:<5} SSIM {m.ssim:.5f}  "
              f"within 1 level {1 - m.off_by_more_than_one:.3%}  max abs {m.max_abs:.4g}")
        for f in k.failures:
            if not quiet:
                print(f"         {f}")
    t, r = result.times.get(Role.CANDIDATE), result.times[Role.REFERENCE]
    c_name, r_name = result.labels[Role.CANDIDATE], result.labels[Role.REFERENCE]
    if t and not quiet:
        print(f"times    {c_name} {t['cold_s']:.3f} s cold, {t['warm_s']:.3f} s warm; "
              f"{r_name} {r['cold_s']:.3f} s cold, {r['warm_s']:.3f} s warm")
    print(f"page     {(out / 'index.html').resolve()}")
    return 0 if result.passed else 1
