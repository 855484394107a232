"""Plots as inline SVG (no plotting library, no CDN): log-log lines (error against run time,
throughput against triangle count) and grouped horizontal bars (render times per scene)."""
from __future__ import annotations

import math
import re
from collections.abc import Collection
from html import escape

PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")
W, H, PAD_L, PAD_R, PAD_T, PAD_B = 520, 340, 70, 20, 30, 50
LEGEND_ROW = 16


def _ticks(lo: float, hi: float) -> list[float]:
    return [10.0**e for e in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)]


def _palette(names: Collection[str]) -> dict[str, str]:
    """A color per series, the same for every series whose name starts with the same word
    (one renderer's solid and dashed lines), in order of first appearance."""
    words = list(dict.fromkeys(_word(n) for n in names))
    return {n: PALETTE[words.index(_word(n)) % len(PALETTE)] for n in names}


def _word(name: str) -> str:
    return re.findall(r"^[a-z]*", name.lower())[0]


def loglog(title: str, xlabel: str, ylabel: str,
           series: dict[str, list[tuple[float, float, str]]],
           dashed: Collection[str] = ()) -> str:
    """series: name -> [(x, y, point label)], x and y > 0; the series named in dashed are
    drawn dashed. A series' color follows the first word of its name (the renderer)."""
    colors = _palette(series)
    pts = [(x, y) for s in series.values() for x, y, _ in s if x > 0 and y > 0]
    if not pts:
        return f"<p>{escape(title)}: no data</p>"
    x0, x1 = min(p[0] for p in pts), max(p[0] for p in pts)
    y0, y1 = min(p[1] for p in pts), max(p[1] for p in pts)
    xt, yt = _ticks(x0, x1), _ticks(y0, y1)
    lx0, lx1 = math.log10(xt[0]), math.log10(xt[-1]) if xt[-1] > xt[0] else math.log10(xt[0]) + 1
    ly0, ly1 = math.log10(yt[0]), math.log10(yt[-1]) if yt[-1] > yt[0] else math.log10(yt[0]) + 1

    def px(x: float) -> float:
        return PAD_L + (math.log10(x) - lx0) / (lx1 - lx0) * (W - PAD_L - PAD_R)

    def py(y: float) -> float:
        return H - PAD_B - (math.log10(y) - ly0) / (ly1 - ly0) * (H - PAD_T - PAD_B)

    total_h = H + LEGEND_ROW * len(series)  # the legend goes under the plot
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{total_h}" '
           f'viewBox="0 0 {W} {total_h}" role="img" aria-label="{escape(title)}">',
           f'<text x="{W / 2}" y="18" text-anchor="middle" font-size="14">{escape(title)}</text>',
           f'<rect x="{PAD_L}" y="{PAD_T}" width="{W - PAD_L - PAD_R}" '
           f'height="{H - PAD_T - PAD_B}" fill="none" stroke="#999"/>']
    for t in xt:
        x = px(t)
        out.append(f'<line x1="{x:.1f}" y1="{PAD_T}" x2="{x:.1f}" y2="{H - PAD_B}" stroke="#eee"/>'
                   f'<text x="{x:.1f}" y="{H - PAD_B + 16}" text-anchor="middle" '
                   f'font-size="11">{t:g}</text>')
    for t in yt:
        y = py(t)
        out.append(f'<line x1="{PAD_L}" y1="{y:.1f}" x2="{W - PAD_R}" y2="{y:.1f}" stroke="#eee"/>'
                   f'<text x="{PAD_L - 6}" y="{y + 4:.1f}" text-anchor="end" '
                   f'font-size="11">{t:g}</text>')
    out.append(f'<text x="{(W + PAD_L) / 2}" y="{H - 12}" text-anchor="middle" '
               f'font-size="12">{escape(xlabel)}</text>')
    out.append(f'<text x="16" y="{(H - PAD_B + PAD_T) / 2}" text-anchor="middle" font-size="12" '
               f'transform="rotate(-90 16 {(H - PAD_B + PAD_T) / 2})">{escape(ylabel)}</text>')
    for k, (name, s) in enumerate(series.items()):
        color = colors[name]
        dash = ' stroke-dasharray="5,4"' if name in dashed else ""
        good = [(px(x), py(y), label) for x, y, label in s if x > 0 and y > 0]
        if good:
            path = " ".join(f"{x:.1f},{y:.1f}" for x, y, _ in good)
            out.append(f'<polyline points="{path}" fill="none" stroke="{color}" '
                       f'stroke-width="2"{dash}/>')
        for x, y, label in good:
            out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="3" fill="{color}">'
                       f'<title>{escape(name)} {escape(label)}</title></circle>')
        ly = H + LEGEND_ROW * k + 4
        out.append(f'<line x1="{PAD_L}" y1="{ly - 4}" x2="{PAD_L + 30}" y2="{ly - 4}" '
                   f'stroke="{color}" stroke-width="2"{dash}/>'
                   f'<text x="{PAD_L + 38}" y="{ly}" font-size="12" fill="{color}">'
                   f'{escape(name)}</text>')
    out.append("</svg>")
    return "".join(out)


def bars(title: str, xlabel: str, groups: dict[str, dict[str, float]]) -> str:
    """Grouped horizontal bars on a linear axis from 0: groups maps a label (a scene) to its
    bars (renderer -> value >= 0), each bar labelled with its value."""
    names = list(dict.fromkeys(n for g in groups.values() for n in g))
    colors = _palette(names)
    values = [v for g in groups.values() for v in g.values()]
    if not values:
        return f"<p>{escape(title)}: no data</p>"
    top = max(max(values), 1e-12) * 1.15
    bar_h, gap, left = 12, 10, 130
    height = PAD_T + len(groups) * (len(names) * bar_h + gap) + PAD_B
    scale = (W - left - PAD_R) / top
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{height}" '
           f'viewBox="0 0 {W} {height}" role="img" aria-label="{escape(title)}">',
           f'<text x="{W / 2}" y="18" text-anchor="middle" font-size="14">{escape(title)}</text>']
    y = PAD_T
    for label, g in groups.items():
        out.append(f'<text x="{left - 6}" y="{y + len(names) * bar_h / 2 + 4:.1f}" '
                   f'text-anchor="end" font-size="12">{escape(label)}</text>')
        for name in names:
            if name in g:
                w = g[name] * scale
                out.append(f'<rect x="{left}" y="{y}" width="{w:.1f}" height="{bar_h - 2}" '
                           f'fill="{colors[name]}"><title>{escape(label)} {escape(name)}: '
                           f'{g[name]:.4g}</title></rect>'
                           f'<text x="{left + w + 4:.1f}" y="{y + bar_h - 3}" font-size="10">'
                           f'{g[name]:.3g}</text>')
            y += bar_h
        y += gap
    axis_y = y
    out.append(f'<line x1="{left}" y1="{PAD_T - 4}" x2="{left}" y2="{axis_y}" stroke="#999"/>')
    out.append(f'<text x="{(W + left) / 2}" y="{axis_y + 28}" text-anchor="middle" '
               f'font-size="12">{escape(xlabel)}</text>')
    for k, name in enumerate(names):
        out.append(f'<text x="{W - PAD_R}" y="{PAD_T + 12 * k}" text-anchor="end" '
                   f'font-size="12" fill="{colors[name]}">{escape(name)}</text>')
    out.append("</svg>")
    return "".join(out)
