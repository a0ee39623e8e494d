"""Line plots as inline SVG, drawn on the server from stored data (the report prints without
scripts): a frame, ticks at 1-2-5 steps with their units, one polyline per series, dashed
horizontal reference lines.

The plot area and the data range it shows are written on the frame (`data-*` attributes, with
the x axis' scale: linear, or logarithmic for a frequency response), so a reader can map a
point back to its value.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from html import escape

MAX_POINTS = 2000  # per polyline; longer series are thinned to min/max per column
Y_PAD = 0.05  # of the data's span, above and below
COLOURS = ("#1f5fa8", "#c2410c", "#15803d", "#7e22ce", "#b45309", "#0e7490", "#be185d", "#4d7c0f")
LEGEND_PER_ROW = 5  # legend entries under the plot, per row at most
LEGEND_CHAR_PX = 6.6  # the legend's 11 px text: an average character's width
LEGEND_ROW_PX = 16


@dataclass(frozen=True)
class Line:
    """One series: x and y of equal length (non-finite points are left out)."""

    label: str
    x: Sequence[float]
    y: Sequence[float]


@dataclass(frozen=True)
class Plot:
    """What to draw: lines over a common x, axis titles with units, reference levels."""

    lines: list[Line]
    x_title: str
    x_unit: str
    y_title: str
    y_unit: str
    refs: list[tuple[str, float]] = field(default_factory=list)  # (label, y)
    width: int = 640
    height: int = 260
    log_x: bool = False  # a logarithmic x axis (a frequency response); x must be > 0


@dataclass(frozen=True)
class Frame:
    """Where the data goes: the plot area in px and the data range it shows."""

    left: float
    top: float
    width: float
    height: float
    x0: float
    x1: float
    y0: float
    y1: float
    log_x: bool = False

    def px(self, x: float) -> float:
        if self.log_x:
            span = math.log10(self.x1) - math.log10(self.x0)
            return self.left + (math.log10(x) - math.log10(self.x0)) / span * self.width
        return self.left + (x - self.x0) / (self.x1 - self.x0) * self.width

    def py(self, y: float) -> float:
        return self.top + (self.y1 - y) / (self.y1 - self.y0) * self.height


def nice_ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """Ticks at a 1, 2 or 5 × 10^n step covering [lo, hi] (about `count` of them)."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return []
    if hi <= lo:
        return [lo]
    raw = (hi - lo) / max(1, count)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1.0, 2.0, 5.0, 10.0) if m * mag >= raw)
    first = math.ceil(lo / step - 1e-9) * step
    ticks = []
    v = first
    while v <= hi + step * 1e-9:
        ticks.append(0.0 if abs(v) < step * 1e-9 else v)
        v += step
    return ticks


def log_ticks(lo: float, hi: float) -> list[float]:
    """Ticks at 1, 2 and 5 × 10^n within [lo, hi] (lo > 0)."""
    out: list[float] = []
    for n in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1):
        out += [m * 10.0**n for m in (1.0, 2.0, 5.0) if lo <= m * 10.0**n <= hi]
    return out


def _fmt(v: float) -> str:
    return f"{v:.6g}"


def _finite(line: Line) -> list[tuple[float, float]]:
    return [
        (float(x), float(y))
        for x, y in zip(line.x, line.y, strict=False)
        if math.isfinite(x) and math.isfinite(y)
    ]


def thin(points: list[tuple[float, float]], columns: int) -> list[tuple[float, float]]:
    """At most 2 × `columns` + 2 points: the first and the last, and the min and max of each
    column in order (a peak stays visible however long the series)."""
    if len(points) <= 2 * columns + 2:
        return points
    per = len(points) / columns
    keep = {0, len(points) - 1}
    for c in range(columns):
        lo, hi = int(c * per), int((c + 1) * per)
        if hi > lo:
            chunk = range(lo, hi)
            keep.add(min(chunk, key=lambda i: points[i][1]))
            keep.add(max(chunk, key=lambda i: points[i][1]))
    return [points[i] for i in sorted(keep)]


def _range(values: list[float]) -> tuple[float, float]:
    lo, hi = min(values), max(values)
    if hi == lo:
        pad = abs(lo) * 0.1 or 1.0
        return lo - pad, hi + pad
    return lo, hi


def _per_row(plot: Plot) -> int:
    """Legend entries per row: as many of the longest as fit the plot's width (at most
    LEGEND_PER_ROW; 'S1.speed_cmd_rpm' ran into its neighbour at a fifth of the width)."""
    longest = max((len(line.label) for line in plot.lines), default=0)
    entry = longest * LEGEND_CHAR_PX + 28.0  # the line sample, its gap, the text, air
    return max(1, min(LEGEND_PER_ROW, int((plot.width - 80.0) // entry)))


def _legend_rows(plot: Plot) -> int:
    return 0 if len(plot.lines) < 2 else -(-len(plot.lines) // _per_row(plot))


def frame_of(plot: Plot, points: list[list[tuple[float, float]]]) -> Frame | None:
    """The plot area and the range it shows: x tight to the data, y taking in the data and the
    reference levels near it, with a margin; None without a single finite point."""
    xs = [p[0] for pts in points for p in pts if p[0] > 0.0 or not plot.log_x]
    ys = [p[1] for pts in points for p in pts]
    if not xs:
        return None
    x0, x1 = _range(xs)
    y0, y1 = _range(ys)
    # a level near the data is taken in; one far off would flatten the data (it is named at
    # the plot's edge instead)
    near = [v for _, v in plot.refs if y0 - (y1 - y0) <= v <= y1 + (y1 - y0)]
    y0, y1 = min([y0, *near]), max([y1, *near])
    pad = (y1 - y0) * Y_PAD  # the line clear of the frame
    y0, y1 = y0 - pad, y1 + pad
    left, right, top, bottom = 64.0, 16.0, 12.0, 44.0 + _legend_rows(plot) * LEGEND_ROW_PX
    width, height = plot.width - left - right, plot.height - top - bottom
    return Frame(left, top, width, height, x0, x1, y0, y1, plot.log_x and x0 < x1)


def render(plot: Plot) -> str:
    """The plot as an <svg> element (sized in px, scaled to the column's width in print)."""
    points = [[p for p in _finite(line) if p[0] > 0.0 or not plot.log_x] for line in plot.lines]
    f = frame_of(plot, points)
    w, h = plot.width, plot.height
    head = (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="plot" viewBox="0 0 {w} {h}" '
        f'width="{w}" height="{h}" role="img" aria-label="{escape(plot.y_title)} over '
        f'{escape(plot.x_title)}">'
    )
    if f is None:
        return head + f'<text x="{w / 2}" y="{h / 2}" text-anchor="middle">no data</text></svg>'
    out = [
        head,
        f'<rect class="frame" x="{f.left}" y="{f.top}" width="{f.width}" height="{f.height}" '
        f'data-x0="{f.x0!r}" data-x1="{f.x1!r}" data-y0="{f.y0!r}" data-y1="{f.y1!r}" '
        f'data-x-scale="{"log" if f.log_x else "linear"}" '
        'fill="none" stroke="#444" stroke-width="1"/>',
    ]
    bottom = f.top + f.height
    for t in log_ticks(f.x0, f.x1) if f.log_x else nice_ticks(f.x0, f.x1, 8):
        x = f.px(t)
        out.append(
            f'<line x1="{x:.2f}" y1="{f.top}" x2="{x:.2f}" y2="{bottom}" stroke="#ddd"/>'
            f'<text x="{x:.2f}" y="{bottom + 14}" text-anchor="middle">{_fmt(t)}</text>'
        )
    for t in nice_ticks(f.y0, f.y1):
        y = f.py(t)
        out.append(
            f'<line x1="{f.left}" y1="{y:.2f}" x2="{f.left + f.width}" y2="{y:.2f}" '
            f'stroke="#ddd"/><text x="{f.left - 6}" y="{y + 4:.2f}" text-anchor="end">'
            f"{_fmt(t)}</text>"
        )
    x_title = f"{plot.x_title} [{plot.x_unit}]".strip() if plot.x_unit else plot.x_title
    y_title = f"{plot.y_title} [{plot.y_unit}]".strip() if plot.y_unit else plot.y_title
    out.append(
        f'<text x="{f.left + f.width / 2}" y="{bottom + 32}" text-anchor="middle">'
        f"{escape(x_title)}</text>"
        f'<text transform="translate(14 {f.top + f.height / 2}) rotate(-90)" '
        f'text-anchor="middle">{escape(y_title)}</text>'
    )
    for label, v in plot.refs:
        if not math.isfinite(v):
            continue
        if not f.y0 <= v <= f.y1:
            above = v > f.y1
            y = f.top + 12 if above else bottom - 4
            out.append(
                f'<text class="ref-off" x="{f.left + f.width - 4}" y="{y:.2f}" '
                f'text-anchor="end" fill="#444">{escape(label)} {"↑" if above else "↓"} '
                "(off the scale)</text>"
            )
            continue
        y = f.py(v)
        out.append(
            f'<line class="ref" x1="{f.left}" y1="{y:.2f}" x2="{f.left + f.width}" '
            f'y2="{y:.2f}" stroke="#666" stroke-dasharray="5 4"/>'
            f'<text x="{f.left + f.width - 4}" y="{y - 4:.2f}" text-anchor="end" '
            f'fill="#444">{escape(label)}</text>'
        )
    for i, (line, pts) in enumerate(zip(plot.lines, points, strict=True)):
        shown = thin(pts, MAX_POINTS // 2 - 1)
        coords = " ".join(f"{f.px(x):.2f},{f.py(y):.2f}" for x, y in shown)
        colour = COLOURS[i % len(COLOURS)]
        out.append(
            f'<polyline data-series="{escape(line.label)}" fill="none" stroke="{colour}" '
            f'stroke-width="1.5" points="{coords}"/>'
        )
    if len(plot.lines) > 1:  # the legend in rows under the x axis' title
        per_row = _per_row(plot)
        column = f.width / per_row
        for i, line in enumerate(plot.lines):
            colour = COLOURS[i % len(COLOURS)]
            x = f.left + (i % per_row) * column
            y = bottom + 50 + (i // per_row) * LEGEND_ROW_PX
            out.append(
                f'<line x1="{x:.1f}" y1="{y - 4}" x2="{x + 16:.1f}" y2="{y - 4}" '
                f'stroke="{colour}" stroke-width="2"/>'
                f'<text x="{x + 20:.1f}" y="{y}">{escape(line.label)}</text>'
            )
    out.append("</svg>")
    return "".join(out)
