"""The stress page (`raycheck stress`, stress.html): the extreme scenes' rows and the failing
rows' reference, variant and difference images."""
from __future__ import annotations

from html import escape

from ..records import StressRow
from .html import num_cell, page


def stress_page(rows: list[StressRow], ssim_goal: float) -> str:
    """stress.html: every row, worst first as given, then the failing rows' images."""
    robust = [r for r in rows if r.variant == "robust"]
    ok = sum(r.passed for r in robust)
    head = ("<tr><th>scene</th><th>variant</th><th>size</th><th>NaN/inf pixels</th>"
            "<th>differing &gt;1 level</th><th>SSIM</th><th>cold s</th><th>warm s</th>"
            "<th>status</th></tr>")
    trs = []
    for r in rows:
        status = "pass" if r.passed else "fail"
        trs.append(
            f'<tr class="{status}"><td title="{escape(r.description)}">{escape(r.scene)}'
            f'</td><td>{escape(r.variant)}</td><td>{r.size[0]}x{r.size[1]}</td>'
            + num_cell(r.nonfinite, "{:d}") + num_cell(r.differing, "{:.2%}")
            + num_cell(r.ssim, "{:.4f}") + num_cell(r.cold_s, "{:.2f}")
            + num_cell(r.warm_s, "{:.3f}")
            + f'<td class="{status}">{escape(r.error or status)}</td></tr>')
    fails = []
    for r in rows:
        if r.passed or r.diff is None or r.reference is None or r.image is None:
            continue
        imgs = "".join(
            f'<figure><img src="{escape(src)}" alt="{escape(cap)}" width="{4 * r.size[0]}"'
            f' style="image-rendering:pixelated"><figcaption>{escape(cap)}</figcaption></figure>'
            for src, cap in ((r.reference, "reference (robust float64)"),
                             (r.image, r.variant),
                             (r.diff, f"|difference|, 0..{r.diff_scale:.3g}")))
        fails.append(f'<h3>{escape(r.scene)}: {escape(r.variant)} (SSIM {r.ssim:.4f}, '
                     f'{r.differing:.2%} differing, {r.nonfinite} NaN/inf)</h3>'
                     f'<p>{escape(r.description)}</p><div class="panels">{imgs}</div>')
    body = (f"<h1>raycheck stress: extreme scenes</h1><p>Reference: the tracer in robust mode "
            f"in float64. A row passes with no NaN/inf pixel and SSIM &ge; {ssim_goal}. Robust "
            f"mode passes on {ok} of {len(robust)} scenes. "
            f'<a href="stress.json">All numbers as JSON</a>.</p>'
            f"<table><thead>{head}</thead><tbody>{''.join(trs)}</tbody></table>"
            f"<h2>Failures</h2>{''.join(fails) or '<p>none</p>'}")
    return page("raycheck stress", body)
