"""The benchmark page of the report (bench.html): `raycheck bench` numbers as tables and plots.

Always the course scenes (both renderers' cold and warm times and their ratio); with
`raycheck bench --throughput` data also primary-ray throughput against triangle count, BVH
build time and memory, and render time against triangle count.
"""
from __future__ import annotations

import json
import textwrap
from html import escape
from pathlib import Path
from typing import Callable

from ..bench.records import (
    BenchRun,
    Machine,
    ThroughputRow,
    Timing,
    Versus,
    format_table,
    format_versus,
)
from .html import num_cell, page, provenance_block
from .svgplot import bars


def _course(rows: tuple[Timing, ...]) -> str:
    """Per scene each renderer's cold and warm times, and the warm ratio of the first renderer
    to the second (green rows: the first is at least as fast)."""
    names = list(dict.fromkeys(r.renderer for r in rows))
    by_scene: dict[str, dict[str, Timing]] = {}
    for r in rows:
        by_scene.setdefault(r.scene, {})[r.renderer] = r
    pair = names[:2] if len(names) >= 2 else None
    trs = []
    for scene, t in by_scene.items():
        cells = "".join(num_cell(t[n].cold_s if n in t else None, "{:.3f}")
                        + num_cell(t[n].warm_s if n in t else None, "{:.3f}") for n in names)
        ratio = None
        if pair and all(n in t for n in pair) and t[pair[1]].warm_s > 0:
            ratio = t[pair[0]].warm_s / t[pair[1]].warm_s
        status = "" if ratio is None else ("pass" if ratio <= 1.0 else "fail")
        trs.append(f'<tr class="{status}"><td>{escape(scene)}</td>{cells}'
                   + (num_cell(ratio, "{:.2f}") if pair else "") + "</tr>")
    first = rows[0]
    setting = f"{first.size}x{first.size}, {first.flags}"
    n = first.warm_runs
    runs = f"the next {n} renders" if n else "the renders after it"
    plot = bars(f"Warm render time (s), {setting}", "seconds (lower is faster)",
                {s: {r: v.warm_s for r, v in t.items()} for s, t in by_scene.items()})
    heads = "".join(f"<th>{escape(n)} cold s</th><th>{escape(n)} warm s</th>" for n in names)
    ratio_head = f"<th>warm ratio {escape(pair[0])}/{escape(pair[1])}</th>" if pair else ""
    green = (f" Green rows: {escape(pair[0])} is at least as fast as {escape(pair[1])} warm."
             if pair else "")
    return (f"<h2>Course scenes</h2><p>{escape(setting)}. Each renderer in a fresh process "
            "with an empty Dr.Jit kernel cache: cold = load, trace, compile and the first "
            f"render; warm = the median of {runs}.{green}</p><table><thead>"
            f"<tr><th>scene</th>{heads}{ratio_head}</tr></thead><tbody>"
            + "".join(trs) + "</tbody></table>" + plot)


def bench_page(data: BenchRun) -> str:
    """The page of a bench run: the course scenes, and the throughput where the run has it."""
    body = ["<h1>raycheck bench</h1><p><a href=\"bench.json\">All numbers as JSON</a>. "
            "<a href=\"index.html\">Comparison report</a>.</p>"]
    if data.course:
        body.append(_course(data.course))
    if data.throughput:
        from .throughput import throughput_section

        body.append(throughput_section(list(data.throughput)))
    else:
        body.append("<p>Throughput, build, memory and scaling: run <code>raycheck bench "
                    "--throughput --json FILE</code> and <code>raycheck report --bench "
                    "FILE</code>.</p>")
    if data.provenance:
        body.append(provenance_block(data.provenance))
    return page("raycheck bench", "".join(body))


# what reading a field of data that is not a bench run's raises
BAD_DATA = (KeyError, TypeError, ValueError, AttributeError, ZeroDivisionError)


class BenchFileError(ValueError):
    """A file that is not a `raycheck bench --json` run (one line: the file and why)."""


def read_bench(path: Path) -> BenchRun:
    """A saved `raycheck bench --json` run, checked by making its page before a report
    starts."""
    try:
        data = BenchRun.from_json(json.loads(path.read_text(encoding="utf-8")))
        bench_page(data)
    except OSError as e:
        raise BenchFileError(f"{path}: not a raycheck bench JSON file ({e})") from None
    except BAD_DATA as e:
        raise BenchFileError(f"{path}: not a raycheck bench JSON file ({type(e).__name__}: "
                             f"{e})") from None
    return data


def write_bench_page(data: BenchRun, folder: Path) -> Path:
    """Writes folder/bench.html and folder/bench.json; returns the page's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "bench.json").write_text(json.dumps(data.to_json(), indent=2), encoding="utf-8")
    path = folder / "bench.html"
    path.write_text(bench_page(data), encoding="utf-8")
    return path


# --- the generated performance tables (docs/performance.md) ----------------------------------
README_BEGIN = "<!-- bench:begin -->"
README_END = "<!-- bench:end -->"
README_NOTE = ("<!-- generated from one run by raycheck bench --readme or tools/bench_readme.py: "
               "edit the prose around it, not this -->")
README_PARTS = ("course", "throughput", "versus", "machine", "provenance")
SHORT_BEGIN = "<!-- bench-short:begin -->"
SHORT_END = "<!-- bench-short:end -->"


class ReadmeError(ValueError):
    """The bench data or the README cannot make the README's tables (the message says why)."""


def machine_line(data: BenchRun) -> str:
    """Which machine, when, how loaded and which versions the numbers are from."""
    m, p = data.machine, data.provenance
    if m is None or p is None:
        raise ReadmeError("the bench data has no machine or provenance")
    gpu = "no GPU (the CUDA backend was not run)" if m.gpu == "none" else f"GPU: {m.gpu}"
    return (f"One run on {m.date}: {m.cpu}, {m.cores} cores, {gpu}; 1-minute load "
            f"average {m.load_average.min:g}-{m.load_average.max:g} during the run (other jobs "
            f"shared the machine: ratios in one table are paired, absolute seconds are not "
            f"comparable across runs). raycheck {p['raycheck']} (commit "
            f"{p['git commit'][:12]}), Dr.Jit {p.get('drjit', '?')}, Mitsuba "
            f"{p.get('mitsuba', '?')}, {p['llvm'].split(' (')[0]}, Python {p['python']}.")


def throughput_table(rows: list[ThroughputRow]) -> str:
    """Primary-ray throughput against Mitsuba/Embree (ours: t and triangle against the
    preliminary intersection; with the shading normal against the full surface interaction),
    BVH build time and memory per triangle."""
    lines = [f"{'triangles':>10}   {'ours M rays/s (+normal)':>23}   "
             f"{'Mitsuba (Embree) prelim / full':>30}   {'ours/prelim':>11}   {'/full':>5}"
             f"  {'BVH build s':>11}  {'B/tri':>5}"]
    for r in rows:
        if r.mi_prelim_mrays is None or r.mi_full_mrays is None:
            raise ReadmeError("the throughput rows have no Mitsuba numbers (run without "
                              "--no-mitsuba)")
        ours = f"{r.ours_mrays:.2f} ({r.ours_full_mrays:.2f})"
        mitsuba = f"{r.mi_prelim_mrays:.2f} / {r.mi_full_mrays:.2f}"
        lines.append(f"{r.triangles:>10}   {ours:>23}   {mitsuba:>30}   "
                     f"{r.vs_mitsuba_prelim:11.2f}   {r.vs_mitsuba_full:5.2f}  "
                     f"{r.build_s:11.3f}  {r.bytes_per_triangle:5.0f}")
    return "\n".join(lines)


def _whole(data: BenchRun) -> tuple[tuple[Versus, ...], tuple[ThroughputRow, ...], Machine]:
    """The parts only a whole run has (ReadmeError naming those missing)."""
    missing = [k for k in README_PARTS if not getattr(data, k)]
    if missing or data.versus is None or data.throughput is None or data.machine is None:
        raise ReadmeError(f"the bench data has no {', '.join(missing)}: the performance tables "
                          "come from one `raycheck bench --throughput --versus CMD` run")
    return data.versus, data.throughput, data.machine


def readme_block(data: BenchRun) -> str:
    """The generated tables, markers included: the machine, then the course-scene,
    throughput and versus tables as `raycheck bench` prints them."""
    versus, throughput, _ = _whole(data)
    program = data.versus_program or {}
    try:
        tables = [format_table(list(data.course)), throughput_table(list(throughput)),
                  format_versus(list(versus), program["name"])]
        machine = textwrap.fill(machine_line(data), 95)
    except BAD_DATA as e:
        raise ReadmeError(f"not the data of a raycheck bench run ({type(e).__name__}: "
                          f"{e})") from None
    body = "\n\n".join(f"```\n{t}\n```" for t in tables)
    return f"{README_BEGIN}\n{README_NOTE}\n{machine}\n\n{body}\n{README_END}"


def short_block(data: BenchRun) -> str:
    """The front door's one table, markers included: per course scene the tracer's and
    Mitsuba's warm renders and their ratio, and the tracer's whole process against the other
    program's at the largest size."""
    readme_block(data)  # the same data checks
    versus, _, m = _whole(data)
    other = (data.versus_program or {})["name"][:10]
    names = list(dict.fromkeys(t.renderer for t in data.course))[:2]
    size = max(v.size for v in versus)
    warm = {(t.scene, t.renderer): t.warm_s for t in data.course}
    lines = [f"{'scene':<17} {names[0] + ' warm':>12} {names[-1] + ' warm':>13} "
             f"{'ratio':>6} {names[0] + ' process':>16} {other + ' s':>9} {'speed-up':>9}"]
    try:
        for v in (v for v in versus if v.size == size):
            a, b = warm[(v.scene, names[0])], warm[(v.scene, names[-1])]
            lines.append(f"{v.scene:<17} {a:12.3f} {b:13.3f} {a / b:6.2f} "
                         f"{v.tracer_median_s:16.3f} {v.other_median_s:9.3f} "
                         f"{v.other_median_s / v.tracer_median_s:9.2f}")
    except BAD_DATA as e:
        raise ReadmeError(f"not the data of a raycheck bench run ({type(e).__name__}: "
                          f"{e})") from None
    lines.append(f"({size}x{size}, {data.course[0].flags}; seconds; {m.date}, {m.cpu}, "
                 f"{m.cores} cores)")
    return f"{SHORT_BEGIN}\n{README_NOTE}\n```\n" + "\n".join(lines) + f"\n```\n{SHORT_END}"


# a file's generated blocks: the whole tables (docs/performance.md), the short one (README.md)
BLOCKS = ((README_BEGIN, README_END, readme_block), (SHORT_BEGIN, SHORT_END, short_block))


def generated_spans(text: str) -> list[tuple[int, int, Callable[[BenchRun], str]]]:
    """Where the generated blocks of a file's text begin and end, with what makes each
    (ReadmeError: none, or markers not in pairs)."""
    spans = []
    for begin_marker, end_marker, make in BLOCKS:
        begin, end = text.find(begin_marker), text.find(end_marker)
        if begin < 0 and end < 0:
            continue
        if begin < 0 or end < begin or text.count(begin_marker) != 1 \
                or text.count(end_marker) != 1:
            raise ReadmeError(f"expected one {begin_marker} and, after it, one {end_marker} "
                              "around the generated tables")
        spans.append((begin, end + len(end_marker), make))
    if not spans:
        raise ReadmeError(f"expected one {README_BEGIN} and, after it, one {README_END} (or "
                          f"{SHORT_BEGIN} ... {SHORT_END}) around the generated tables")
    return sorted(spans, key=lambda span: span[0])


def rewrite_readme(text: str, data: BenchRun) -> str:
    """text with each generated block (BLOCKS) made again from data."""
    for begin, end, make in reversed(generated_spans(text)):
        text = text[:begin] + make(data) + text[end:]
    return text


def write_readme(path: Path, data: BenchRun) -> None:
    """Rewrites the README file's generated tables in place (ReadmeError, OSError: unchanged)."""
    from raycheck.tracer.scene.outputs import write_all

    text = rewrite_readme(path.read_text(encoding="utf-8"), data)

    def save(tmp: str) -> None:
        Path(tmp).write_text(text, encoding="utf-8")

    write_all([(path, save)])
