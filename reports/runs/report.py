"""`raycheck report`: the comparison suite, the tracer against the Mitsuba reference over every
scene x feature it can exercise, as a static HTML report with error-against-time plots,
provenance and a JSON file holding every number."""
from __future__ import annotations

from html import escape
from pathlib import Path
from typing import Callable

from raycheck.tracer.render_limits import LimitError
from raycheck.tracer.scene.limits import Budget

from ..catalog import BundledScene
from ..judge.verdict import ENGINES_JITTER_TEST, ENGINES_TOLERANCE
from ..pages.svgplot import loglog
from ..provenance import provenance
from ..records import CaseRecord, to_json
from ..renderers import Renderer
from .bench_records import BenchRun
from .case_settings import CaseSettings
from .convergence import SIZE_SWEEP_SAMPLES, SWEEP_SIZE, Point, sweep, sweep_problem
from .distribution import DEFAULT_REALISATIONS
from .matrix import Matrix, Runner, run_matrix, summary, write_index, write_json, write_junit

REPORT_SIZE = 128  # square size of report renders unless a scene asks for its own size
SWEEP_SCENES = ("spheres_mirror", "cubemap_mesh")


def _plots(points: list[Point], labels: list[str]) -> list[str]:
    """Per sweep scene and error metric: each renderer's sample-count sweep (solid) and
    resolution sweep (dashed) against warm run time."""
    plots = []
    for scene in sorted({p.scene for p in points}):
        pts = [p for p in points if p.scene == scene]
        for metric, label in (("one_minus_ssim", "1 - SSIM"), ("rmse", "RMSE")):
            series = {}
            for r in labels:
                series[f"{r} spp"] = sorted(
                    (p.warm_s, getattr(p, metric), f"{p.samples} spp at {p.size} px")
                    for p in pts if p.renderer == r and p.size == SWEEP_SIZE)
                series[f"{r} size"] = sorted(
                    (p.warm_s, getattr(p, metric), f"{p.size} px at {p.samples} spp")
                    for p in pts if p.renderer == r and p.samples == SIZE_SWEEP_SAMPLES)
            plots.append(loglog(f"{scene}: {label} against warm run time", "warm run time (s)",
                                label, series, dashed=[n for n in series if n.endswith("size")]))
    return plots


def _sweep_section(points: list[Point], labels: list[str]) -> str:
    if not points:
        return ""
    from ..pages.html import _num

    trs = "".join(
        f"<tr><td>{escape(t.scene)}</td><td>{escape(t.renderer)}</td>"
        f"<td class=num>{t.size}</td><td class=num>{t.samples}</td>"
        + _num(t.cold_s, "{:.3f}") + _num(t.warm_s, "{:.3f}")
        + _num(t.rmse, "{:.3e}") + _num(t.one_minus_ssim, "{:.3e}") + "</tr>"
        for t in points)
    return ("<h2>Error against run time</h2>" + "".join(_plots(points, labels))
            + "<h3>Times and errors of the sweeps</h3><table><thead><tr><th>scene</th>"
              "<th>renderer</th><th>size</th><th>spp</th><th>cold s</th><th>warm s</th>"
              "<th>RMSE</th><th>1-SSIM</th></tr></thead><tbody>" + trs + "</tbody></table>")


def _jitter_section(rows: list[CaseRecord], realisations: int) -> str:
    """Every jittered image's statistics against the reference's distribution."""
    from ..pages.html import _num

    trs = ""
    for row in rows:
        for k in row.kinds:
            if not k.jitter:
                continue
            stats = {s["name"]: s for s in k.jitter["statistics"]}
            trs += (f'<tr><td><a href="{escape(row.page)}">{escape(row.case)}</a></td>'
                    f"<td>{escape(k.kind)}</td><td>{escape(k.verdict)}</td>"
                    f"<td class=num>{k.jitter['failing_pixels']}</td>"
                    + "".join(_num(stats[n]["value"], "{:.3g}")
                              for n in ("mean z", "mean z^2", "correlation")) + "</tr>")
    if not trs:
        return ""
    return ("<h2>Jittered images: the statistical test</h2>"
            f"<p>Each 16-sample image against {realisations} realisations of the reference "
            f"({escape(ENGINES_JITTER_TEST.describe())}): per-pixel z with a 1/12 level^2 "
            "quantisation floor, Sidak-corrected; mean z (bias), mean z^2 (noise level) and "
            "the correlation of z between neighbours (one shared jitter pattern), each against "
            "its null distribution from the realisations. The false-alarm rate and the power "
            "for injected defects, measured by tools/bench_jitter.py, are in docs/statistics.md."
            "</p>"
            "<table><thead><tr><th>case</th><th>kind</th><th>verdict</th>"
            "<th>failing pixels</th><th>mean z</th><th>mean z^2</th><th>correlation</th>"
            "</tr></thead><tbody>" + trs + "</tbody></table>")


def _matrix(scenes: list[BundledScene], candidate: Renderer, reference: Renderer, size: int,
            seed: int, budget: Budget, realisations: int) -> Matrix:
    settings = CaseSettings(ENGINES_TOLERANCE, warm=True, realisations=realisations,
                            jitter_test=ENGINES_JITTER_TEST)
    return Matrix(scenes, candidate, reference, settings, default_size=(size, size), seed=seed,
                  budget=budget)


def check_report_limits(scenes: list[BundledScene], candidate: Renderer, reference: Renderer,
                        size: int, budget: Budget, realisations: int,
                        sweep_scenes: tuple[str, ...] = SWEEP_SCENES) -> None:
    """LimitError for the first case or sweep of build_report's that is over a limit: for the
    command to call before any work (the stress and bench pages come before the cases)."""
    _matrix(scenes, candidate, reference, size, 0, budget, realisations).cases()
    for scene in scenes:
        problem = sweep_problem(scene, budget) if scene.name in sweep_scenes else None
        if problem:
            raise LimitError(f"the error-against-time sweep of {scene.name}, {problem} (or "
                             "leave the sweeps out: --no-sweeps)")


def build_report(scenes: list[BundledScene], out: Path, candidate: Renderer,
                 reference: Renderer, size: int = REPORT_SIZE,
                 sweep_scenes: tuple[str, ...] = SWEEP_SCENES, seed: int = 0,
                 log: Callable[[str], None] = print, quiet: bool = False,
                 stress_link: bool = False, budget: Budget = Budget(),
                 runner: Runner | None = None, bench_link: bool = False,
                 findings_link: bool = False,
                 realisations: int = DEFAULT_REALISATIONS) -> dict:
    prov = provenance(seed)
    matrix = _matrix(scenes, candidate, reference, size, seed, budget, realisations)
    rows, skips, seconds = run_matrix(matrix, out, prov, quiet, runner)
    points: list[Point] = []
    for scene in scenes:
        if scene.name in sweep_scenes:
            log(f"error against time: {scene.name}")
            points += sweep(scene, [candidate, reference], reference)
    labels = {"candidate": candidate.name, "reference": reference.name}
    data = {"provenance": prov, "labels": labels, "cases": [to_json(r) for r in rows],
            "skipped": to_json(skips), "summary": to_json(summary(rows)),
            "convergence": to_json(points), "seconds": seconds}
    write_json(out / "report.json", data)
    write_junit(out / "junit.xml", rows, "raycheck report")
    intro = (f"Metrics compare {escape(candidate.name)} with {escape(reference.name)} on the "
             f"values as shown (clipped to [0, 1]) within "
             f"{escape(matrix.settings.tolerance.describe())}; jittered rows judge each "
             f"16-sample image by a statistical test against {realisations} realisations of "
             f"{escape(reference.name)} ({escape(ENGINES_JITTER_TEST.describe())}). "
             '<a href="report.json">All numbers as JSON</a>.'
             + (' The extreme scenes in every mode: <a href="stress.html">stress tests</a>.'
                if stress_link else "")
             + (' Render times and BVH throughput: <a href="bench.html">benchmarks</a>.'
                if bench_link else "")
             + (' Which bug the top finding names: <a href="findings.html">findings</a>.'
                if findings_link else ""))
    write_index(out, rows, skips, labels, intro, prov, "raycheck report",
                _jitter_section(rows, realisations)
                + _sweep_section(points, [candidate.name, reference.name]))
    return data


def course_bench(log: Callable[[str], None] = print) -> BenchRun:
    """The benchmark page's numbers: `raycheck bench` of the course scenes in both renderers,
    timed once per engine source and machine and then reused from the disk cache
    (disk_cache.py): 14 fresh processes would otherwise be timed again on every report, for
    numbers that only a change of the engines or the machine changes. The page's provenance
    is that of the run that timed them."""
    import hashlib
    import json
    import platform

    from .bench import run_bench
    from .disk_cache import cache_folder, engine_digest, load_bytes, save_bytes

    machine = f"{platform.node()} {platform.machine()} {platform.platform()}"
    key = hashlib.sha256(f"{engine_digest()} {machine}".encode()).hexdigest()
    path = cache_folder() / "bench" / f"{key}.json"
    try:
        saved = BenchRun.from_json(json.loads(load_bytes(path) or b"null"))
        log(f"bench: the saved run of these engines on this machine ({path})")
        return saved
    except ValueError:  # none, or a damaged entry: timed again
        pass
    log("bench: the course scenes in both renderers")
    data = run_bench(["tracer", "mitsuba"], log=log)
    save_bytes(path, json.dumps(data.to_json()).encode())
    return data


