"""The report's index (`raycheck report`): its introduction, the jittered images' statistics
and the error-against-time sweeps, as HTML sections for html.index_page."""
from __future__ import annotations

from html import escape

from ..bench.records import SIZE_SWEEP_SAMPLES, SWEEP_SIZE, Point
from ..records import CaseRecord
from .html import num_cell
from .svgplot import loglog


def report_intro(candidate: str, reference: str, tolerance: str, realisations: int,
                 jitter_test: str, links: list[tuple[str, str, str]],
                 missing: list[tuple[str, str]]) -> str:
    """The paragraph above the matrix; links: (what it holds, page file, link text) of each
    other page the report has; missing: (what it would hold, the command that makes it) of
    each it has not."""
    return (f"Metrics compare {escape(candidate)} with {escape(reference)} on the values as "
            f"shown (clipped to [0, 1]) within {escape(tolerance)}; jittered rows judge each "
            f"16-sample image by a statistical test against {realisations} realisations of "
            f"{escape(reference)} ({escape(jitter_test)}). "
            '<a href="report.json">All numbers as JSON</a>.'
            + "".join(f' {escape(what)}: <a href="{escape(href)}">{escape(text)}</a>.'
                      for what, href, text in links)
            + "".join(f" {escape(what)}: not in this report (<code>{escape(how)}</code> "
                      "makes it)." for what, how in missing))


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


def sweep_section(points: list[Point], labels: list[str]) -> str:
    if not points:
        return ""
    trs = "".join(
        f"<tr><td>{escape(t.scene)}</td><td>{escape(t.renderer)}</td>"
        f"<td class=num>{t.size}</td><td class=num>{t.samples}</td>"
        + num_cell(t.cold_s, "{:.3f}") + num_cell(t.warm_s, "{:.3f}")
        + num_cell(t.rmse, "{:.3e}") + num_cell(t.one_minus_ssim, "{:.3e}") + "</tr>"
        for t in points)
    return ("<h2>Error against run time</h2>" + "".join(_plots(points, labels))
            + "<h3>Times and errors of the sweeps</h3><table><thead><tr><th>scene</th>"
              "<th>renderer</th><th>size</th><th>spp</th><th>cold s</th><th>warm s</th>"
              "<th>RMSE</th><th>1-SSIM</th></tr></thead><tbody>" + trs + "</tbody></table>")


def jitter_section(rows: list[CaseRecord], realisations: int, jitter_test: str) -> str:
    """Every jittered image's statistics against the reference's distribution."""
    trs = ""
    for row in rows:
        for k in row.kinds:
            if k.jitter is None:
                continue
            stats = {s.name: s for s in k.jitter.statistics}
            trs += (f'<tr><td><a href="{escape(row.page)}">{escape(row.case)}</a></td>'
                    f"<td>{escape(k.kind)}</td><td>{escape(k.verdict)}</td>"
                    f"<td class=num>{k.jitter.failing_pixels}</td>"
                    + "".join(num_cell(stats[n].value, "{:.3g}")
                              for n in ("mean z", "mean z^2", "correlation")) + "</tr>")
    if not trs:
        return ""
    return ("<h2>Jittered images: the statistical test</h2>"
            f"<p>Each 16-sample image against {realisations} realisations of the reference "
            f"({escape(jitter_test)}): per-pixel z with a 1/12 level^2 "
            "quantisation floor, Sidak-corrected; mean z (bias), mean z^2 (noise level) and "
            "the correlation of z between neighbours (one shared jitter pattern), each against "
            "its null distribution from the realisations. The false-alarm rate and the power "
            "for injected defects, measured by tools/bench_jitter.py, are in docs/statistics.md."
            "</p>"
            "<table><thead><tr><th>case</th><th>kind</th><th>verdict</th>"
            "<th>failing pixels</th><th>mean z</th><th>mean z^2</th><th>correlation</th>"
            "</tr></thead><tbody>" + trs + "</tbody></table>")
