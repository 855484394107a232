"""How often the top finding names the bug: every defect of tests/wrappers/corrupt.py, on the
bundled scenes, in the cases it breaks; and the tracer itself ("none"), which must get no
finding (and no failure) anywhere.

    .venv/bin/python tools/bench_findings.py [--size N] [--defects a,b,...] [-j N] [--json F]
                                             [SCENE ...]

Prints a markdown table: per defect, its failing kinds, how many of them have a top finding
that names the defect, and the top findings seen (a sparse confusion table); then the share
over all defects. Exit status 1 when that share is under TARGET or the tracer got a finding.
The defects run in parallel, one per worker process (-j, default: the number of cores).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "tests" / "wrappers"))

from corrupt import Corrupted  # noqa: E402

from raycheck.harness.case_settings import CaseSettings  # noqa: E402
from raycheck.harness.catalog import scenes_named  # noqa: E402
from raycheck.harness.judge.verdict import Tolerance  # noqa: E402
from raycheck.harness.pipeline.case import run_case  # noqa: E402
from raycheck.harness.pipeline.executor import use_threads, workers  # noqa: E402
from raycheck.harness.pipeline.matrix import Matrix  # noqa: E402
from raycheck.harness.records import FindingRecord  # noqa: E402
from raycheck.harness.renderers import renderer_from_spec  # noqa: E402

TARGET = 0.9  # the issue's bar: 90% of the failing kinds' top findings name their bug
EVERY = frozenset({"plain", "shadows", "bounces", "shadows+bounces", "jitter", "filter",
                   "jitter+filter"})
# defect -> (the features whose cases it breaks, the finding codes that name it)
DEFECTS: dict[str, tuple[frozenset[str], frozenset[str]]] = {
    "no_shadows": (frozenset({"shadows", "shadows+bounces"}),
                   frozenset({"cause:shadow_missing", "no_effect", "shadow_missing"})),
    "no_bounces": (frozenset({"bounces"}), frozenset({"cause:reflection_depth", "no_effect"})),
    # at -bounces 1 one fewer is none: the flag has no effect
    "one_bounce_fewer": (frozenset({"bounces"}),
                         frozenset({"cause:reflection_depth", "reflection_depth", "no_effect"})),
    "no_filter": (frozenset({"filter"}), frozenset({"cause:filter_ignored", "no_effect"})),
    # every sample at the (sub-)pixel's corner: jitter_fixed with offset 0
    "no_jitter": (frozenset({"jitter"}), frozenset({"cause:jitter_fixed", "jitter_no_noise"})),
    "samples4": (frozenset({"jitter", "jitter+filter"}), frozenset({"cause:jitter_samples"})),
    # one jitter pattern for every pixel: no catalogue mistake, no finding names it (the
    # correlation statistic fails it); a cause named here is a wrong one
    "shared_pattern": (frozenset({"jitter", "jitter+filter"}), frozenset({"cause:unexplained"})),
    "filter_2x": (frozenset({"filter", "jitter+filter"}),
                  frozenset({"filter_kernel", "filter_weights", "brightness_scale"})),
    "flip": (frozenset({"plain"}), frozenset({"flipped_vertical"})),
    "flip_h": (frozenset({"plain"}), frozenset({"flipped_horizontal"})),
    "transpose": (frozenset({"plain"}), frozenset({"transposed"})),
    "swap_rb": (frozenset({"plain"}), frozenset({"channel_order"})),
    "gamma": (frozenset({"plain"}), frozenset({"gamma_encoded"})),
    "offset": (frozenset({"plain"}), frozenset({"constant_offset"})),
    "rounding": (frozenset({"plain"}), frozenset({"quantisation"})),
    "normals_clip": (frozenset({"plain"}), frozenset({"normals_mapping"})),
    "normals_abs": (frozenset({"plain"}), frozenset({"normals_mapping"})),
    "depth_inverted": (frozenset({"plain"}), frozenset({"depth_mapping"})),
    "acne": (frozenset({"shadows"}), frozenset({"shadow_acne"})),
    # where no kept row crosses a shadow, the candidate has none: no_effect names that
    "few_shadows": (frozenset({"shadows"}), frozenset({"cause:shadow_missing", "shadow_missing",
                                                       "no_effect"})),
    # the shading bugs of tests/wrappers/patched.py
    "specular_gated": (EVERY - {"jitter", "jitter+filter", "filter"},
                       frozenset({"cause:specular_gated", "term_missing:specular_behind"})),
    # the wrapper adds it after each light's shadow test: without shadows, once per light
    "ambient_per_light": (EVERY - {"jitter", "jitter+filter", "filter"},
                          frozenset({"cause:ambient_per_lit_light", "cause:ambient_per_light",
                                     "term_scaled:ambient", "term_missing:ambient"})),
    "half_vector": (EVERY - {"jitter", "jitter+filter", "filter"},
                    frozenset({"cause:specular_half_vector", "shininess",
                               "term_scaled:specular"})),
    "no_offset": (frozenset({"shadows", "bounces", "shadows+bounces"}),
                  frozenset({"cause:shadow_offset", "cause:reflection_offset", "shadow_acne",
                             "reflection_acne"})),
    # --- geometry level (harness/judge/geometry.py); object:<index> is named by its prefix
    "unnormalised_normals": (frozenset({"plain"}),
                             frozenset({"cause:transform_normal_unnormalised", "normal_length",
                                        "object", "transformed_objects"})),
    "one_material": (frozenset({"plain"}), frozenset({"object"})),
    "pixel_centre": (frozenset({"plain"}), frozenset({"cause:ndc_pixel_centre", "edges_only"})),
    "half_shift": (frozenset({"plain"}), frozenset({"cause:ndc_half_shift", "shifted"})),
    "depth_unclamped": (frozenset({"plain"}), frozenset({"depth_mapping"})),
    # ---
    "none": (EVERY, frozenset()),
}
# rounding moves bytes by one level: only a zero-level tolerance fails it
TOLERANCES = {"rounding": Tolerance(levels=0)}


def top_findings(defect: str, scenes: list, size: int, threads: int | None = None) -> Counter:
    """Top finding code ("-" for none) of every failing kind of the defect's cases; threads:
    this worker's Dr.Jit threads (executor.use_threads)."""
    use_threads(threads)
    features, _ = DEFECTS[defect]
    # strict: the catalogue's quirk readings (reflection_gate=0) are faults here too
    matrix = Matrix(scenes, Corrupted(defect), renderer_from_spec("tracer"),
                    CaseSettings(TOLERANCES.get(defect, Tolerance()), strict=True),
                    size=(size, size), features=features)
    seen: Counter = Counter()
    for case in matrix.cases()[0]:
        result = run_case(case, matrix.candidate, matrix.reference, matrix.settings)
        for k in result.kinds:
            if k.verdict != "pass" or (defect == "none" and k.findings):
                seen[_top(k.findings)] += 1
    return seen


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--size", type=int, default=24, help="square image size (default 24)")
    ap.add_argument("--defects", help=f"comma-separated, of {', '.join(DEFECTS)}")
    ap.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                    help="worker processes (default: the number of cores; 1: in this process)")
    ap.add_argument("--json", type=Path, metavar="FILE",
                    help="also write the table as JSON (raycheck report --findings FILE)")
    args = ap.parse_args(argv)
    unknown = [d for d in (args.defects.split(",") if args.defects else []) if d not in DEFECTS]
    if unknown:
        ap.error(f"unknown defects {', '.join(unknown)}")
    if args.jobs is not None and args.jobs < 1:
        ap.error(f"-j {args.jobs}: at least 1")
    scenes = scenes_named(args.scenes)
    defects = args.defects.split(",") if args.defects else list(DEFECTS)
    print("| defect | failing kinds | top finding names it | top findings seen |")
    print("|---|---|---|---|")
    right = total = 0
    tracer_findings = 0
    rows = []
    start = time.perf_counter()
    with workers(args.jobs) as w:
        # the tracer's own run ("none": every feature of every scene) is the longest: first,
        # so that it does not finish alone at the end
        order = sorted(defects, key=lambda d: d != "none")
        futures = {d: w.executor.submit(top_findings, d, scenes, args.size, w.threads)
                   for d in order}
        for defect in defects:  # the table in the defects' order, each row when it is done
            seen = futures[defect].result()
            n = sum(seen.values())
            named = sum(c for code, c in seen.items() if names(code, DEFECTS[defect][1]))
            rows.append({"defect": defect, "failing": n, "named": named,
                         "seen": dict(seen.most_common())})
            if defect == "none":
                tracer_findings = n
                print(f"| none (the tracer) | {n} | - | "
                      f"{_seen(seen) or 'no finding, no failure'} |", flush=True)
                continue
            right, total = right + named, total + n
            cell = f"{named}/{n} ({named / n:.0%})" if n else "0/0"
            print(f"| {defect} | {n} | {cell} | {_seen(seen)} |", flush=True)
    share = right / total if total else 0.0
    seconds = time.perf_counter() - start
    print(f"\n{right}/{total} top findings name their defect ({share:.1%}); the tracer: "
          f"{tracer_findings} findings; {seconds:.0f} s")
    precision = precision_table(rows)
    print("\n| top finding | shown | names the defect | precision |\n|---|---|---|---|")
    for code, (shown, good) in precision.items():
        print(f"| `{code}` | {shown} | {good} | {good / shown:.0%} |")
    if args.json:
        args.json.write_text(json.dumps({
            "rows": rows, "named": right, "total": total, "target": TARGET,
            "precision": {c: {"shown": n, "right": g} for c, (n, g) in precision.items()},
            "tracer_findings": tracer_findings, "size": args.size, "seconds": seconds,
            "date": time.strftime("%Y-%m-%d")}, indent=1), encoding="utf-8")
    return 0 if share >= TARGET and tracer_findings == 0 else 1


def precision_table(rows: list[dict]) -> dict[str, tuple[int, int]]:
    """Per finding code (object:<index> as one, the hint after "unexplained" as itself; not
    "unexplained", which names nothing): how often it was a failing kind's top finding over
    the defects, and how often it named the defect: its precision on this synthetic set. Most
    shown first."""
    counts: dict[str, list[int]] = {}
    for row in rows:
        if row["defect"] == "none":
            continue
        for code, n in row["seen"].items():
            plain = code.removeprefix("unexplained, then ")
            if plain in ("-", "cause:unexplained"):  # names nothing
                continue
            key = "object:<index>" if plain.startswith("object:") else plain
            c = counts.setdefault(key, [0, 0])
            c[0] += n
            c[1] += n if names(code, DEFECTS[row["defect"]][1]) else 0
    return {k: (v[0], v[1]) for k, v in sorted(counts.items(), key=lambda kv: -kv[1][0])}


def _top(findings: list[FindingRecord]) -> str:
    """The top finding's code; where it says no known mistake reproduces the image, the hint
    after it (these defects are mostly outside the mistake catalogue: the hint is what names
    them), marked as following it."""
    if not findings:
        return "-"
    if findings[0].code == "cause:unexplained" and len(findings) > 1:
        return "unexplained, then " + findings[1].code
    return findings[0].code


def names(code: str, codes: frozenset[str]) -> bool:
    """Whether a finding code is one of the defect's: exactly, or object:<index> as object."""
    code = code.removeprefix("unexplained, then ")
    return code in codes or (code.startswith("object:") and "object" in codes)


def _seen(seen: Counter) -> str:
    return ", ".join(f"{code} {n}" for code, n in seen.most_common())


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
