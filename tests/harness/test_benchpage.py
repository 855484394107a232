"""The benchmark page: its tables and plots show the numbers they are given, hand-checked."""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import pytest

from raycheck.harness.bench.records import BenchRun
from raycheck.harness.cli.report import main as report_main
from raycheck.harness.pages.benchpage import bench_page, write_bench_page
from raycheck.harness.pages.svgplot import W, bars

HOSTILE = "<b>&x"


def _run(data: dict) -> BenchRun:
    """A bench run from its JSON, as `raycheck report --bench FILE` reads one."""
    return BenchRun.from_json(data)


def _course(scene: str, tracer_warm: float, mitsuba_warm: float) -> list[dict]:
    common = {"scene": scene, "size": 800, "flags": "-bounces 4 -shadows"}
    return [{**common, "renderer": "tracer", "cold_s": 0.5, "warm_s": tracer_warm},
            {**common, "renderer": "mitsuba", "cold_s": 0.25, "warm_s": mitsuba_warm}]


def _throughput_row(triangles: int, ours: float) -> dict:
    """A bench run's throughput row as bench.json holds it (176 device bytes per triangle)."""
    from raycheck.harness.bench.records import JitCounts, ThroughputRow

    jit = JitCounts(kernels=1, cache_hits=0)
    return ThroughputRow(
        triangles=triangles, vertices=triangles // 2, rays=4096, threads=2,
        build_s=triangles * 1e-6, build_cpu_s=triangles * 1e-6, upload_s=0.01, nodes=3,
        leaves=2, depth=1, node_bytes=32 * triangles, triangle_bytes=136 * triangles,
        order_bytes=8 * triangles, ours_cold_s=0.5, jit_cold=jit, ours_full_cold_s=0.5,
        hit_fraction=0.5, jit_warm=jit, ours_warm_s=4096 / ours / 1e6, ours_mrays=ours,
        ours_full_warm_s=4096 / (0.75 * ours) / 1e6, ours_full_mrays=0.75 * ours,
        peak_rss_mb=100.0, mi_prelim_mrays=2 * ours, mi_full_mrays=1.5 * ours,
        vs_mitsuba_prelim=0.5, vs_mitsuba_full=0.5, render_warm_s=0.1).to_json()


def test_course_table_ratios_and_status():
    data = {"course": _course("fast", 0.010, 0.020) + _course(HOSTILE, 0.030, 0.020)}
    page = bench_page(_run(data))
    rows = re.findall(r'<tr class="(pass|fail)"><td>([^<]*)</td>(.*?)</tr>', page)
    assert [(status, scene) for status, scene, _ in rows] == [
        ("pass", "fast"), ("fail", "&lt;b&gt;&amp;x")]
    # the last cell is tracer warm / Mitsuba warm: 0.010 / 0.020 and 0.030 / 0.020
    ratios = [re.findall(r'data-v="([^"]+)"', cells)[-1] for _, _, cells in rows]
    assert [float(r) for r in ratios] == [0.5, 1.5]
    assert HOSTILE not in page
    assert "BVH against Mitsuba/Embree" not in page  # no throughput rows: no section
    assert "raycheck bench --throughput" in page


def test_course_table_names_its_warm_run_count_where_the_run_kept_it():
    from raycheck.harness.bench.records import Timing, format_table

    unkept = _course("a", 1.0, 1.0)
    kept = [dict(r, warm_runs=7) for r in unkept]
    assert "warm = the median of the next 7 renders." in bench_page(_run({"course": kept}))
    assert "warm = the median of the renders after it." in bench_page(_run({"course": unkept}))
    assert format_table([Timing(**r) for r in kept]).splitlines()[-1] == (
        "(800x800, -bounces 4 -shadows; seconds; warm: median of 7 renders;"
        " ratio = tracer/mitsuba)")


def test_throughput_section_bytes_per_triangle():
    data = {"course": _course("a", 1.0, 1.0),
            "throughput": [_throughput_row(1000, 30.0), _throughput_row(10000, 20.0)]}
    page = bench_page(_run(data))
    assert "BVH against Mitsuba/Embree" in page
    # (32 + 136 + 8) bytes per triangle, in both rows
    assert page.count('data-v="176.0"') == 2
    assert page.count("<svg") == 1 + 3  # the bars, throughput, build and render plots


def test_bars_are_proportional_to_their_values():
    svg = bars("t", "s", {"x": {"tracer": 1.0, "Mitsuba": 2.0}, "y": {"tracer": 0.5}})
    widths = [float(w) for w in re.findall(r'<rect x="\d+" y="\d+" width="([\d.]+)"', svg)]
    # one scale for all: the axis (W - 130 px of labels - 20 px of margin = 370 px) spans
    # 1.15x the largest value: 370 / 2.3 = 160.87 px per unit
    assert W - 130 - 20 == 370
    assert widths == [160.9, 321.7, 80.4]
    assert 'fill="#1f77b4"' in svg and 'fill="#d62728"' in svg  # first renderer blue, second red


def test_report_takes_a_saved_bench_and_links_it(tmp_path: Path):
    saved = tmp_path / "bench.json"
    saved.write_text(json.dumps({"course": _course("fast", 0.010, 0.020)}))
    scene = Path(__file__).resolve().parents[2] / "scenes/features/nonsquare.txt"
    out = tmp_path / "out"
    assert report_main([str(scene), "--out", str(out), "--no-sweeps", "--size", "8",
                        "--bench", str(saved)]) == 0
    assert (out / "report/bench.html").exists()
    assert json.loads((out / "report/bench.json").read_text())["course"][0]["scene"] == "fast"
    assert 'href="bench.html"' in (out / "report/index.html").read_text()


@pytest.mark.parametrize("course", [None, [1, 2], "no warm time", "no cold time"])
def test_report_refuses_a_file_that_is_not_a_bench(course, tmp_path: Path, capsys):
    """Before any work, with one line: not JSON of a run, or rows that the page cannot show
    (each of these ended the report in a traceback once the cases had run)."""
    rows = _course("a", 1.0, 1.0)
    if course == "no warm time":
        course = [dict(r, warm_s=None) for r in rows]
    elif course == "no cold time":
        course = [{k: v for k, v in r.items() if k != "cold_s"} for r in rows]
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2]" if course is None else json.dumps({"course": course}))
    assert report_main(["--out", str(tmp_path / "out"), "--bench", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("raycheck report: error: ") and err.count("\n") == 1
    assert "bad.json: not a raycheck bench JSON file" in err
    assert not (tmp_path / "out").exists()


def test_write_bench_page_writes_page_and_json(tmp_path: Path):
    data = {"course": _course("s", 0.1, 0.1), "provenance": {"cpu": "test cpu"}}
    path = write_bench_page(_run(data), tmp_path / "r")
    assert path == tmp_path / "r" / "bench.html"
    assert json.loads((tmp_path / "r" / "bench.json").read_text()) == data
    assert "test cpu" in path.read_text()


def test_versus_times_both_programs_in_pairs_and_keeps_every_run():
    """bench --versus on one small scene, the tracer's own command line as the other program:
    each run's seconds kept, the table has the medians and the speed-up."""
    import sys

    from raycheck.harness.bench.records import format_versus
    from raycheck.harness.bench.timing import versus_table
    from raycheck.harness.catalog import bundled

    scene = [s for s in bundled("course") if s.path.stem == "ellipsoid"]
    rows = versus_table(f"{sys.executable} -m raycheck.tracer", sizes=(8,), runs=2,
                        scenes=scene, log=lambda *_: None)
    assert [(r.scene, r.size, len(r.tracer_s), len(r.other_s)) for r in rows] == \
        [("ellipsoid", 8, 2, 2)]
    assert all(t > 0 for t in rows[0].tracer_s + rows[0].other_s)
    table = format_versus(rows, "python")
    assert "ellipsoid" in table and "speed-up" in table


def _bench_run() -> dict:
    """One synthetic run of `raycheck bench --throughput --versus a2` (made-up numbers)."""
    flags = "-bounces 4 -shadows"
    return {
        "course": _course("fast", 0.010, 0.020) + _course("slow", 0.030, 0.020),
        "throughput": [_throughput_row(1000, 10.0), _throughput_row(1000000, 2.5)],
        "versus_program": {"command": ["/x/a2"], "sha256": None, "file": "/x/a2", "name": "a2"},
        "versus": [  # medians 0.25 / 1.5: 6x, met; 0.2 / 0.25: a2 under 0.3 s, no goal;
                     # 0.4 / 0.35: 0.875x, missed
            {"scene": "fast", "size": 800, "flags": flags, "tracer_s": [0.2, 0.3, 0.25],
             "other_s": [1.5, 1.4, 1.6]},
            {"scene": "fast", "size": 200, "flags": flags, "tracer_s": [0.2, 0.2, 0.2],
             "other_s": [0.25, 0.25, 0.25]},
            {"scene": "slow", "size": 200, "flags": flags, "tracer_s": [0.4, 0.4, 0.4],
             "other_s": [0.35, 0.35, 0.35]}],
        "machine": {"cpu": "Test CPU 9000", "cores": 2, "date": "2026-12-01", "gpu": "none",
                    "load_average": {"min": 0.5, "max": 3.25, "every_s": 5.0,
                                     "samples": [0.5, 3.25]}},
        "provenance": {"raycheck": "0.1.0", "git commit": "0123456789abcdef0123",
                       "mitsuba": "3.9.1", "drjit": "1.5.0", "python": "3.11.7",
                       "llvm": "LLVM 19.1.7 (/usr/lib/libLLVM.so.19.1)"},
    }


README_BEFORE = "# T\n\nprose\n<!-- bench:begin -->\nold tables\n<!-- bench:end -->\nmore prose\n"
README_AFTER = """# T

prose
<!-- bench:begin -->
<!-- generated from one run by raycheck bench --readme or tools/bench_readme.py:\
 edit the prose around it, not this -->
One run on 2026-12-01: Test CPU 9000, 2 cores, no GPU (the CUDA backend was not run); 1-minute
load average 0.5-3.25 during the run (other jobs shared the machine: ratios in one table are
paired, absolute seconds are not comparable across runs). raycheck 0.1.0 (commit 0123456789ab),
Dr.Jit 1.5.0, Mitsuba 3.9.1, LLVM 19.1.7, Python 3.11.7.

```
scene                 tracer cold    warm   mitsuba cold    warm warm ratio
fast                        0.500   0.010          0.250   0.020       0.50
slow                        0.500   0.030          0.250   0.020       1.50
(800x800, -bounces 4 -shadows; seconds; ratio = tracer/mitsuba)
```

```
 triangles   ours M rays/s (+normal)   Mitsuba (Embree) prelim / full\
   ours/prelim   /full  BVH build s  B/tri
      1000              10.00 (7.50)                    20.00 / 15.00\
          0.50    0.50        0.001    176
   1000000               2.50 (1.88)                      5.00 / 3.75\
          0.50    0.50        1.000    176
```

```
scene              size  tracer s             a2 s speed-up   goal
fast                800     0.250            1.500     6.00    met
fast                200     0.200            0.250     1.25      -
slow                200     0.400            0.350     0.87 missed
(-bounces 4 -shadows, color+normals+depth; whole processes, the tracer's kernel cache warm;\
 medians of 3 paired runs;
 speed-up = a2 s / tracer s; goal 800: 5x; 200: 1x where a2 takes over 0.3 s)
```
<!-- bench:end -->
more prose
"""


def test_readme_tables_are_regenerated_from_one_run_between_the_markers():
    from raycheck.harness.pages.benchpage import rewrite_readme

    assert rewrite_readme(README_BEFORE, _run(_bench_run())) == README_AFTER
    assert rewrite_readme(README_AFTER, _run(_bench_run())) == README_AFTER  # again: the same


SHORT_BEFORE = "# R\n<!-- bench-short:begin -->\nold\n<!-- bench-short:end -->\n"
# fast: warm 0.010 and 0.020 s (ratio 0.5); at 800x800 whole processes, medians 0.25 and 1.5 s
# (6x); slow has no 800x800 run: not in the short table
SHORT_AFTER = """# R
<!-- bench-short:begin -->
<!-- generated from one run by raycheck bench --readme or tools/bench_readme.py: edit the \
prose around it, not this -->
```
scene              tracer warm  mitsuba warm  ratio   tracer process      a2 s  speed-up
fast                     0.010         0.020   0.50            0.250     1.500      6.00
(800x800, -bounces 4 -shadows; seconds; 2026-12-01, Test CPU 9000, 2 cores)
```
<!-- bench-short:end -->
"""


def test_the_front_doors_short_table_is_made_from_the_same_run():
    from raycheck.harness.pages.benchpage import rewrite_readme

    assert rewrite_readme(SHORT_BEFORE, _run(_bench_run())) == SHORT_AFTER
    both = README_BEFORE + SHORT_BEFORE
    assert rewrite_readme(both, _run(_bench_run())) == README_AFTER + SHORT_AFTER


def test_bench_readme_tool_rewrites_the_file_or_says_why_not(tmp_path: Path, capsys):
    import runpy

    tool = runpy.run_path(str(Path(__file__).resolve().parents[2] / "tools" / "bench_readme.py"))
    bench, readme = tmp_path / "bench.json", tmp_path / "README.md"
    bench.write_text(json.dumps(_bench_run()))
    readme.write_text(README_BEFORE)
    assert tool["main"]([str(bench), str(readme)]) == 0
    assert readme.read_text() == README_AFTER
    capsys.readouterr()

    partial = {k: v for k, v in _bench_run().items() if k != "versus"}
    bench.write_text(json.dumps(partial))
    assert tool["main"]([str(bench), str(readme)]) == 2
    assert capsys.readouterr().err == (
        f"bench_readme: {bench}: the bench data has no versus: the performance tables come from "
        "one `raycheck bench --throughput --versus CMD` run\n")
    bench.write_text(json.dumps(_bench_run()))
    readme.write_text("no markers\n")
    assert tool["main"]([str(bench), str(readme)]) == 2
    assert capsys.readouterr().err == (
        f"bench_readme: {readme}: expected one <!-- bench:begin --> and, after it, one "
        "<!-- bench:end --> (or <!-- bench-short:begin --> ... <!-- bench-short:end -->) around "
        "the generated tables\n")
    assert readme.read_text() == "no markers\n"
    assert tool["main"]([str(tmp_path / "none.json"), str(readme)]) == 2
    assert capsys.readouterr().err == (f"bench_readme: {tmp_path / 'none.json'}: No such file "
                                       "or directory\n")


def test_bench_readme_needs_one_full_run_and_markers_before_it_starts(tmp_path: Path, capsys):
    from raycheck.harness.cli import main as raycheck_main

    readme = tmp_path / "README.md"
    readme.write_text("no markers\n")
    assert raycheck_main(["bench", "--readme", str(readme), "--throughput"]) == 2
    assert "--readme: the performance tables are those of one full run" in capsys.readouterr().err
    argv = ["bench", "--readme", str(readme), "--throughput", "--versus", sys.executable]
    assert raycheck_main(argv) == 2
    assert capsys.readouterr().err == (
        f"raycheck bench: error: --readme: {readme}: expected one <!-- bench:begin --> and, "
        "after it, one <!-- bench:end --> (or <!-- bench-short:begin --> ... "
        "<!-- bench-short:end -->) around the generated tables (see raycheck bench --help)\n")
    assert raycheck_main(["bench", "--versus", str(tmp_path / "no_a2")]) == 2
    assert "--versus: cannot run" in capsys.readouterr().err


def test_the_shipped_tables_are_those_of_the_shipped_run():
    """README.md's short table and docs/performance.md's tables are what docs/bench.json (the
    run behind them) makes: regenerating them changes nothing."""
    from raycheck.harness.pages.benchpage import rewrite_readme

    repo = Path(__file__).resolve().parents[2]
    data = json.loads((repo / "docs" / "bench.json").read_text(encoding="utf-8"))
    for name in ("README.md", "docs/performance.md"):
        text = (repo / name).read_text(encoding="utf-8")
        assert rewrite_readme(text, _run(data)) == text, name
