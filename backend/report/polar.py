"""The circularity test's polar plot as inline SVG (the report prints without scripts): the
radial deviation over the angle, magnified about the nominal circle at a stated µm per
division, one closed line per direction, the plane's axes named at 0° and 90°."""

from __future__ import annotations

import math
from html import escape

from backend.report.svg import COLOURS, Line

SIZE = 320  # px
BASE = 90.0  # px: the nominal circle
DIVISIONS = 4  # rings inside and outside it
MARGIN = 14.0  # px between the outer ring and the edge
STEPS = (0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)


def division(lines: list[Line]) -> float:
    """The smallest 1-2-5 step (µm per division) that keeps every point within the rings."""
    worst = max((abs(v) for line in lines for v in line.y if math.isfinite(v)), default=0.0)
    return next((d for d in STEPS if d * DIVISIONS >= worst), STEPS[-1])


def render(lines: list[Line], first_axis: str, second_axis: str) -> str:
    """The polar plot of `lines` (x: angle in degrees, y: radial deviation in µm)."""
    per_div = division(lines)
    ring = (SIZE / 2 - MARGIN - BASE) / DIVISIONS
    c = SIZE / 2
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {SIZE} {SIZE + 24}" '
        f'width="{SIZE}" height="{SIZE + 24}" class="polar" data-um-per-division="{per_div:g}">'
    ]
    for k in range(-DIVISIONS, DIVISIONS + 1):
        dash = ' stroke-dasharray="4 3"' if k == 0 else ""
        colour = "#999" if k == 0 else "#ddd"
        out.append(
            f'<circle cx="{c}" cy="{c}" r="{BASE + k * ring:.1f}" fill="none" '
            f'stroke="{colour}"{dash}/>'
        )
    first = escape(first_axis)
    out.append(f'<text x="{SIZE - 4}" y="{c - 4}" text-anchor="end" font-size="11">+{first}</text>')
    out.append(f'<text x="{c + 4}" y="12" font-size="11">+{escape(second_axis)}</text>')
    for i, line in enumerate(lines):
        pts = []
        for deg, dr in zip(line.x, line.y, strict=True):
            if not (math.isfinite(deg) and math.isfinite(dr)):
                continue
            r = BASE + dr / per_div * ring
            t = math.radians(deg)
            pts.append(f"{c + r * math.cos(t):.1f},{c - r * math.sin(t):.1f}")
        colour = COLOURS[i % len(COLOURS)]
        out.append(
            f'<polygon data-series="{escape(line.label)}" fill="none" stroke="{colour}" '
            f'stroke-width="1.4" points="{" ".join(pts)}"/>'
        )
    legend = "   ".join(f"{escape(line.label)}" for line in lines)
    out.append(
        f'<text x="4" y="{SIZE + 16}" font-size="11">{per_div:g} µm per division   {legend}</text>'
    )
    out.append("</svg>")
    return "".join(out)
