"""How often a failing image's top finding names the mistake that made it: every entry of the
mistake catalogue (tracer/mistakes.py), alone and in pairs, as a candidate program (the tracer
with that mistake on, as `python -m raycheck.tracer --mistake CODE=VALUE` renders), on every
bundled scene at the default check size; and the tracer itself, which must get no finding.

    .venv/bin/python tools/bench_causes.py [--size N] [--programs a,b+c,...] [-j N] [--json F]
                                           [SCENE ...]

Prints a markdown table: per program, its failing images, how many have a top finding naming
one of its mistakes with the right parameter (within the search's resolution), how many name a
wrong cause, how many say no known mistake reproduces them, and of the failing images the
jittered ones (judged by the distribution the mistaken reference draws: jitter_causes.py) and
how many of those name the right cause; then the shares over all programs,
and the cost of the search (seconds per program). Exit status 1 when the right share is under
TARGET, any top finding names a wrong cause, or the tracer got a finding.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

from raycheck.harness.case_settings import CaseSettings  # noqa: E402
from raycheck.harness.catalog import scenes_named  # noqa: E402
from raycheck.harness.pipeline.case import run_case  # noqa: E402
from raycheck.harness.pipeline.executor import use_threads, workers  # noqa: E402
from raycheck.harness.pipeline.matrix import Matrix, scene_priors  # noqa: E402
from raycheck.harness.records import FindingRecord  # noqa: E402
from raycheck.harness.renderers.builtin import TracerRenderer  # noqa: E402
from raycheck.tracer.mistakes import CATALOGUE, MISTAKES, Switch, parse_switch  # noqa: E402

TARGET = 0.95
# the value each parameterised mistake is benchmarked at: one a real program might have, off
# the sweep's values where the refinement has to find it
VALUES = {"falloff_power": 1.0, "shininess_scale": 2.0, "shadow_offset": 0.0,
          "shadow_offset_normal": 0.001, "reflection_offset": 0.0,
          "reflection_offset_normal": 0.001, "reflection_gate": 0.0, "reflection_depth": -1.0,
          "jitter_fixed": 0.5, "jitter_centred": 2.0, "jitter_samples": 4.0}
# two mistakes of different functions at once, as real programs have them
PAIRS = (("falloff_power", "specular_half_vector"), ("shadow_offset", "ambient_per_light"),
         ("light_reversed", "shadow_beyond_light"), ("reflection_gate", "falloff_ignored"),
         ("reflection_unweighted", "shadow_missing"), ("plane_normalised", "specular_gated"),
         ("transform_normal_unnormalised", "shadow_offset"),
         ("triangle_flat_normals", "reflection_offset"),
         ("sphere_far_root", "diffuse_unclamped"), ("ndc_pixel_centre", "falloff_power"),
         ("specular_half_vector", "jitter_samples"), ("shadow_offset", "jitter_centred"))
# other values of the same mistakes: a real program's constants
VARIANTS = ("shadow_offset=0.05", "reflection_offset=0.05", "falloff_power=3",
            "falloff_power=1.5", "reflection_depth=1", "shininess_scale=0.5",
            "reflection_gate=0.5")
FEATURES = frozenset({"plain", "shadows", "bounces", "shadows+bounces", "filter", "jitter",
                      "jitter+filter"})


def switch(code: str) -> Switch:
    m = MISTAKES[code]
    return Switch(code, None if m.parameter is None else VALUES[code])


def programs() -> dict[str, tuple[Switch, ...]]:
    out: dict[str, tuple[Switch, ...]] = {"none": ()}
    out.update({m.code: (switch(m.code),) for m in CATALOGUE})
    out.update({v: (parse_switch(v),) for v in VARIANTS})
    out.update({f"{a}+{b}": (switch(a), switch(b)) for a, b in PAIRS})
    return out


def right_value(found: float | None, true: float | None, code: str) -> bool:
    """Whether a found parameter is the program's within the search's resolution: offsets
    within a factor of 2 (or both under 1e-4), counts exactly, others within 0.25."""
    if true is None or found is None:
        return true is None and found is None
    p = MISTAKES[code].parameter
    assert p is not None
    if code == "jitter_samples":  # the test tells a count from its neighbours only roughly
        return abs(found - true) <= 1
    if p.integer:
        return found == true
    if p.geometric:
        if max(found, true) < 1e-4:
            return True
        return min(found, true) > 0 and abs(math.log(found / true)) <= math.log(2.0)
    return abs(found - true) <= 0.25


@dataclass
class Row:
    program: str
    failing: int = 0
    right: int = 0
    wrong: int = 0
    unexplained: int = 0
    other: int = 0  # a finding that is no cause (flag-level, where the images differ)
    jittered: int = 0  # of the failing images, those of jittered cases
    jittered_right: int = 0
    seen: Counter = field(default_factory=Counter)
    scenes: Counter = field(default_factory=Counter)  # failing images per scene
    seconds: float = 0.0


def run_program(name: str, switches: tuple[Switch, ...], scenes: list, size: int | None,
                threads: int | None = None) -> Row:
    use_threads(threads)
    candidate = TracerRenderer(f"tracer --mistake {name}",
                               {"mistakes": tuple(str(s) for s in switches)})
    # strict: the catalogue's quirk readings (reflection_gate=0) are faults here too
    matrix = Matrix(scenes, candidate, TracerRenderer(), CaseSettings(strict=True),
                    size=None if size is None else (size, size), features=FEATURES)
    row = Row(name)
    start = time.perf_counter()
    cases = matrix.cases()[0]
    # as a check runs them: a scene's unjittered cases first, whose causes its jittered cases
    # try first (pipeline/matrix.py's program_priors)
    found: dict[Path, list[tuple[Switch, ...]]] = {}
    for case in [c for c in cases if not c.jittered] + [c for c in cases if c.jittered]:
        priors = scene_priors(found.get(case.scene.path, [])) if case.jittered else ()
        result = run_case(case, matrix.candidate, matrix.reference, matrix.settings, priors)
        if not case.jittered:
            found.setdefault(case.scene.path, []).extend(result.explanations)
        for k in result.kinds:
            if k.verdict == "pass" and not (name == "none" and k.findings):
                continue
            row.failing += 1
            row.jittered += case.jittered
            row.scenes[case.scene.name] += 1
            # strict: a quirk's own finding (the course program does this too) comes first,
            # the search's cause after it
            named = [f for f in k.findings if not f.code.startswith("quirk:")]
            top = named[0] if named else FindingRecord("-", "")
            code = top.code
            row.seen[code] += 1
            if code == "cause:unexplained":
                row.unexplained += 1
            elif code.startswith("cause:"):
                if _named(top.message, switches):
                    row.right += 1
                    row.jittered_right += case.jittered
                else:
                    row.wrong += 1
            else:
                row.other += 1
    row.seconds = time.perf_counter() - start
    return row


def _named(message: str, switches: tuple[Switch, ...]) -> bool:
    """Whether a cause finding names one of the program's mistakes with its parameter: the
    finding's `--mistake` lists (the cause's, and those the images cannot tell from it)."""
    for listed in message.split("--mistake ")[1:]:
        spelled = listed.split(")")[0].split()[0].rstrip(".").split(",")
        for s in map(parse_switch, spelled):
            true = next((t for t in switches if t.code == s.code), None)
            if true is not None and right_value(s.value, true.value, s.code):
                return True
    return False


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--size", type=int, default=None,
                    help="square image size (default: each scene's, else 128)")
    ap.add_argument("--programs", help="comma-separated names: catalogue codes, pairs as a+b, "
                                       "none (the tracer)")
    ap.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                    help="worker processes (default: the number of cores; 1: in this process)")
    ap.add_argument("--json", type=Path, metavar="FILE", help="also write the rows as JSON")
    ap.add_argument("--tables", type=Path, metavar="JSON",
                    help="no run: write the tables of a --json run into docs/findings.md "
                         "(every cause) and README.md (per starter-code function)")
    args = ap.parse_args(argv)
    if args.tables:
        return write_tables(json.loads(args.tables.read_text(encoding="utf-8")))
    known = programs()
    names = args.programs.split(",") if args.programs else list(known)
    chosen: dict[str, tuple[Switch, ...]] = {}
    for name in names:
        if name in known:
            chosen[name] = known[name]
        else:
            try:
                chosen[name] = tuple(parse_switch(s) for s in name.split("+"))
            except ValueError as e:
                ap.error(str(e))
    scenes = scenes_named(args.scenes)
    start = time.perf_counter()
    rows: list[Row] = []
    print("| program | failing images | top finding: right cause | wrong cause | "
          "unexplained | other | jittered: right/failing | s |")
    print("|---|---|---|---|---|---|---|---|")
    with workers(args.jobs) as w:
        futures = {n: w.executor.submit(run_program, n, s, scenes, args.size, w.threads)
                   for n, s in chosen.items()}
        for name in chosen:
            row = futures[name].result()
            rows.append(row)
            share = f"{row.right}/{row.failing}" if row.failing else "0/0"
            print(f"| {name} | {row.failing} | {share} | {row.wrong} | {row.unexplained} | "
                  f"{row.other} | {row.jittered_right}/{row.jittered} | {row.seconds:.0f} |",
                  flush=True)
    mistaken = [r for r in rows if r.program != "none"]
    failing = sum(r.failing for r in mistaken)
    right = sum(r.right for r in mistaken)
    wrong = sum(r.wrong for r in mistaken)
    tracer = sum(r.failing for r in rows if r.program == "none")
    seconds = time.perf_counter() - start
    print(f"\n{right}/{failing} failing images name the right cause first "
          f"({right / max(failing, 1):.1%}), {wrong} a wrong cause "
          f"({wrong / max(failing, 1):.1%}); the tracer: {tracer} findings; {seconds:.0f} s")
    for r in mistaken:
        if r.wrong or r.other:
            print(f"  {r.program}: {dict(r.seen.most_common())}")
    if args.json:
        args.json.write_text(json.dumps({
            "rows": [{**{k: v for k, v in vars(r).items() if k not in ("seen", "scenes")},
                      "seen": dict(r.seen), "scenes": dict(r.scenes)} for r in rows],
            "right": right, "wrong": wrong, "failing": failing, "tracer_findings": tracer,
            "seconds": seconds, "date": time.strftime("%Y-%m-%d")}, indent=1),
            encoding="utf-8")
    ok = right >= TARGET * failing and wrong == 0 and tracer == 0
    return 0 if ok else 1


def write_tables(data: dict) -> int:
    """The catalogue with each cause's measured share, between the markers of
    docs/findings.md, and the share per starter-code function between README.md's."""
    rows = {r["program"]: r for r in data["rows"]}
    lines = ["| code | function | your program ... | parameter: sweep | right first |",
             "|---|---|---|---|---|"]
    per_function: dict[str, list[int]] = {}
    for m in CATALOGUE:
        r = rows.get(m.code, {"right": 0, "failing": 0, "wrong": 0})
        p = m.parameter
        sweep = "-" if p is None else (f"{p.name} (course {p.course:g}): "
                                       if p.course is not None else f"{p.name}: ") + \
            ", ".join(f"{v:g}" for v in p.sweep)
        shown = m.describe(VALUES.get(m.code)).replace("|", "\\|")
        share = f"{r['right']}/{r['failing']}" if r["failing"] else "not shown"
        lines.append(f"| `{m.code}` | `{m.function}` | {shown} | {sweep} | {share} |")
        f = per_function.setdefault(m.function, [0, 0, 0, 0])
        f[0], f[1], f[2], f[3] = f[0] + 1, f[1] + r["right"], f[2] + r["failing"], \
            f[3] + r["wrong"]
    note = (f"\nMeasured {data['date']} by `tools/bench_causes.py` (each mistake alone at the "
            "value in its row, on every bundled scene at the default size): right first / "
            "failing images, jittered ones included.")
    readme = ["| starter-code function | mistakes | failing images | right cause first | "
              "wrong cause first |", "|---|---|---|---|---|"]
    readme += [f"| `{fn}` | {n} | {failing} | {right / max(failing, 1):.1%} | "
               f"{wrong / max(failing, 1):.1%} |"
               for fn, (n, right, failing, wrong) in per_function.items()]
    _between(REPO / "docs" / "findings.md", "\n".join(lines) + "\n" + note)
    _between(REPO / "README.md", "\n".join(readme))
    exposed: dict[str, list[str]] = {}
    for m in CATALOGUE:
        for scene, n in rows.get(m.code, {}).get("scenes", {}).items():
            if n:
                exposed.setdefault(scene, []).append(f"`{m.code}`")
    scenes = ["| bundled scene | the mistakes that fail one of its cases |", "|---|---|"]
    scenes += [f"| {name} | {', '.join(codes)} |" for name, codes in sorted(exposed.items())]
    _between(REPO / "docs" / "findings.md", "\n".join(scenes), "exposes")
    return 0


def _between(path: Path, body: str, marker: str = "causes") -> None:
    """The text between a file's <!-- marker:begin --> and <!-- marker:end --> replaced."""
    text = path.read_text(encoding="utf-8")
    begin, end = f"<!-- {marker}:begin -->", f"<!-- {marker}:end -->"
    head, _, rest = text.partition(begin)
    _, _, tail = rest.partition(end)
    path.write_text(f"{head}{begin}\n{body}\n{end}{tail}", encoding="utf-8")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
