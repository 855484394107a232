"""A log-log line plot as inline SVG (no plotting library, no CDN): error against run time."""
from __future__ import annotations

import math
from html import escape

COLORS = {"tracer": "#1f77b4", "mitsuba": "#d62728"}
W, H, PAD_L, PAD_R, PAD_T, PAD_B = 520, 340, 70, 20, 30, 50


def _ticks(lo: float, hi: float) -> list[float]:
    return [10.0**e for e in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)]


def loglog(title: str, xlabel: str, ylabel: str,
           series: dict[str, list[tuple[float, float, str]]]) -> str:
    """series: name -> [(x, y, point label)], x and y > 0."""
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

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
           f'viewBox="0 0 {W} {H}" role="img" aria-label="{escape(title)}">',
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
        color = COLORS.get(name.split()[0], "#333")
        dash = ' stroke-dasharray="5,4"' if "size" in name else ""
        good = [(px(x), py(y), label) for x, y, label in s if x > 0 and y > 0]
        if good:
            path = " ".join(f"{x:.1f},{y:.1f}" for x, y, _ in good)
            out.append(f'<polyline points="{path}" fill="none" stroke="{color}" stroke-width="2"{dash}/>')
        for x, y, label in good:
            out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="3" fill="{color}">'
                       f'<title>{escape(name)} {escape(label)}</title></circle>')
        out.append(f'<text x="{W - PAD_R - 8}" y="{PAD_T + 16 + 16 * k}" text-anchor="end" '
                   f'font-size="12" fill="{color}">{escape(name)}</text>')
    out.append("</svg>")
    return "".join(out)
