"""`raycheck compare <course flags> --out DIR`: one case, both renderers, one HTML page."""
from __future__ import annotations

import sys
from pathlib import Path

from tracer.scene import SceneError, load_scene
from tracer.scene.flags import FlagError, parse_course_flags

from .cases import KINDS, Case
from .catalog import BundledScene, read_header
from .comparison import run_case
from .provenance import provenance
from .report import write_case

PROG = "raycheck compare"


def case_from_args(argv: list[str]) -> tuple[Case, tuple[int, int], Path, int]:
    args = parse_course_flags(argv, {"out": str, "seed": str})
    if "out" not in args.extra:
        raise FlagError("--out DIR is required")
    seed_text = str(args.extra.get("seed", "0"))
    if not seed_text.isdigit():
        raise FlagError(f"--seed: expected a non-negative integer, found '{seed_text}'")
    load_scene(args.input)  # bad scenes fail here, with file and line, before any work
    header = read_header(args.input)
    flags: list[str] = []
    if args.bounces:
        flags += ["-bounces", str(args.bounces)]
    flags += [f for f, on in (("-shadows", args.shadows), ("-jitter", args.jitter),
                              ("-filter", args.filter)) if on]
    named = [k for k, p in (("color", args.output), ("normals", args.normals),
                            ("depth", args.depth_file)) if p is not None]
    scene = BundledScene(args.input, tuple(flags), None, (args.depth_min, args.depth_max),
                         header.description)
    case = Case(scene, " ".join(flags) or "plain", tuple(flags), tuple(named) or KINDS)
    return case, (args.width, args.height), Path(str(args.extra["out"])), int(seed_text)


def main(argv: list[str]) -> int:
    try:
        case, size, out, seed = case_from_args(argv)
    except (FlagError, SceneError) as e:
        print(f"{PROG}: error: {e}", file=sys.stderr)
        return 2
    result = run_case(case, size, seed)
    write_case(result, out, provenance(seed))
    for k in result.kinds:
        m = k.metrics
        print(f"{k.kind:<8} {'pass' if k.passed else 'FAIL'}  SSIM {m['ssim']:.5f}  "
              f"within 1 level {1 - m['off_by_more_than_one']:.3%}  max abs {m['max_abs']:.4g}")
        for f in k.failures:
            print(f"         {f}")
    t, mi = result.times["tracer"], result.times["mitsuba"]
    print(f"times    tracer {t['cold_s']:.3f} s cold, {t['warm_s']:.3f} s warm; "
          f"Mitsuba {mi['cold_s']:.3f} s cold, {mi['warm_s']:.3f} s warm")
    print(f"page     {(out / 'index.html').resolve()}")
    return 0 if result.passed else 1
