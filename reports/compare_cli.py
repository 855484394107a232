"""`raycheck compare <course flags> --out DIR`: one case, both renderers, one HTML page."""
from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

from tracer.scene import SceneError, load_scene
from tracer.scene.flags import FlagError, parse_course_flags

from .cases import Case, feature_name
from .catalog import read_header, with_depth_range
from .judge.verdict import ENGINES_TOLERANCE
from .provenance import provenance
from .renderers import MitsubaRenderer, TracerRenderer
from .runs.case import run_case
from .runs.matrix import write_case

PROG = "raycheck compare"


def case_from_args(argv: list[str]) -> tuple[Case, Path]:
    cmd = parse_course_flags(argv, {"out": str, "seed": str})
    if "out" not in cmd.extra:
        raise FlagError("--out DIR is required")
    load_scene(cmd.input)  # bad scenes fail here, with file and line, before any work
    header = read_header(cmd.input)
    request = cmd.request if cmd.outputs else cmd.request.with_kinds(("color", "normals", "depth"))
    if "depth" in cmd.outputs:
        header = replace(header, depth_range=request.depth_range, depth_origin="-depth")
    else:
        header = with_depth_range(header)
        request = replace(request, depth_min=header.depth_range[0],
                          depth_max=header.depth_range[1])
    return Case(header, feature_name(request), request), Path(str(cmd.extra["out"]))


def main(argv: list[str]) -> int:
    try:
        case, out = case_from_args(argv)
    except (FlagError, SceneError) as e:
        print(f"{PROG}: error: {e}", file=sys.stderr)
        return 2
    result = run_case(case, TracerRenderer(), MitsubaRenderer(), ENGINES_TOLERANCE, warm=True)
    write_case(result, out, provenance(case.request.seed))
    for k in result.kinds:
        m = k.metrics
        print(f"{k.kind:<8} {k.verdict:<5} SSIM {m['ssim']:.5f}  "
              f"within 1 level {1 - m['off_by_more_than_one']:.3%}  max abs {m['max_abs']:.4g}")
        for f in k.failures:
            print(f"         {f}")
    t, r = result.times["candidate"], result.times["reference"]
    c_name, r_name = result.labels["candidate"], result.labels["reference"]
    print(f"times    {c_name} {t['cold_s']:.3f} s cold, {t['warm_s']:.3f} s warm; "
          f"{r_name} {r['cold_s']:.3f} s cold, {r['warm_s']:.3f} s warm")
    print(f"page     {(out / 'index.html').resolve()}")
    return 0 if result.passed else 1
