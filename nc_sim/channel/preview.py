"""The commanded tool path of a program as polylines in one plane, for a preview plot.

Pure geometry on canonical calls (nc_sim/channel/canon.py): every straight move is one
segment from where the axes are to its end; every arc (G02/G03, a helix too) is computed in its
own plane as points on its circle, so close together that no chord strays more than
`CHORD_TOLERANCE_MM` from the arc (at most `MAX_ARC_POINTS` per arc), then every point is
projected onto the plane shown. Other calls (spindle, feed, dwell, M functions) do not move the
tool and draw nothing.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from nc_sim.channel import canon
from nc_sim.channel.modal import PLANES

CHORD_TOLERANCE_MM = 0.001  # sagitta of each chord of an arc: 1 µm
MAX_ARC_POINTS = 2000  # points of one arc (beyond this the chords stray further)
MAX_POINTS = 200_000  # points of a whole preview (a bigger one is cut and marked truncated)
_FULL_CIRCLE_MM = 1e-9  # start and end this close: G02/G03 runs the whole circle


@dataclass(frozen=True)
class Polyline:
    """The path of one canonical motion: its source line, rapid (G00) or not, (h, v) points."""

    line: int
    rapid: bool
    points: list[tuple[float, float]]


@dataclass(frozen=True)
class Preview:
    """Polylines in `plane` (17, 18, 19), drawn over its `axes` (horizontal, vertical)."""

    plane: int
    axes: tuple[str, str]
    segments: list[Polyline]
    truncated: bool  # the program has more points than MAX_POINTS: the rest is left out


def view_plane(calls: Iterable[canon.Call], axes: Sequence[str]) -> int:
    """The plane to show: the first one the program selects, else the first whose two axes
    the machine has (G17 on a mill, G18 on a lathe with X and Z), else G17."""
    for call in calls:
        if isinstance(call, canon.SelectPlane):
            return call.plane
    names = {a.upper() for a in axes}
    return next((p for p, (h, v, _) in PLANES.items() if {h, v} <= names), 17)


def arc_sweep_rad(
    start: tuple[float, float], end: tuple[float, float], arc: canon.ArcFeed
) -> float:
    """The signed angle the arc turns through about its centre: positive counter-clockwise
    (G03), negative clockwise (G02); a whole turn when start and end coincide."""
    ca, cb = arc.centre
    a0 = math.atan2(start[1] - cb, start[0] - ca)
    a1 = math.atan2(end[1] - cb, end[0] - ca)
    full = math.hypot(end[0] - start[0], end[1] - start[1]) <= _FULL_CIRCLE_MM
    if arc.turn > 0:
        sweep = (a1 - a0) % math.tau
        return math.tau if full or sweep == 0.0 else sweep
    sweep = (a0 - a1) % math.tau
    return -math.tau if full or sweep == 0.0 else -sweep


def arc_steps(radius_mm: float, sweep_rad: float, tolerance_mm: float, max_points: int) -> int:
    """Chords for an arc: the fewest whose sagitta r·(1 − cos(Δφ/2)) stays within
    `tolerance_mm`, at most `max_points`."""
    tiny = radius_mm <= tolerance_mm
    step = math.pi if tiny else 2.0 * math.acos(1.0 - tolerance_mm / radius_mm)
    return max(1, min(max_points, math.ceil(abs(sweep_rad) / step - 1e-9)))


def arc_positions(
    start: Mapping[str, float],
    arc: canon.ArcFeed,
    tolerance_mm: float = CHORD_TOLERANCE_MM,
    max_points: int = MAX_ARC_POINTS,
) -> list[dict[str, float]]:
    """Every axis' position at the points along the arc after `start`, its end last. In the
    arc's plane the points lie on the circle (a radius that differs between start and end
    within the interpreter's tolerance changes linearly); every other axis (a helix' normal
    axis) moves in proportion to the angle."""
    a, b, _ = PLANES[arc.plane]
    end = dict(arc.end)
    ca, cb = arc.centre
    s = (start.get(a, 0.0), start.get(b, 0.0))
    e = (end.get(a, 0.0), end.get(b, 0.0))
    r0 = math.hypot(s[0] - ca, s[1] - cb)
    r1 = math.hypot(e[0] - ca, e[1] - cb)
    sweep = arc_sweep_rad(s, e, arc)
    n = arc_steps(max(r0, r1), sweep, tolerance_mm, max_points)
    a0 = math.atan2(s[1] - cb, s[0] - ca)
    out: list[dict[str, float]] = []
    for i in range(1, n):
        f = i / n
        phi, r = a0 + sweep * f, r0 + (r1 - r0) * f
        pos = {k: start.get(k, 0.0) + (v - start.get(k, 0.0)) * f for k, v in end.items()}
        pos[a], pos[b] = ca + r * math.cos(phi), cb + r * math.sin(phi)
        out.append(pos)
    out.append(end)
    return out


def preview(
    calls: Iterable[canon.Call],
    start: Mapping[str, float],
    axes: Sequence[str],
    max_points: int = MAX_POINTS,
) -> Preview:
    """The tool path of `calls` from `start` (where the axes are) in the plane `view_plane`
    chooses for this machine's `axes`."""
    calls = list(calls)
    plane = view_plane(calls, axes)
    h, v, _ = PLANES[plane]
    pos = {k.upper(): float(x) for k, x in start.items()}
    segments: list[Polyline] = []
    total = 0

    def at(p: Mapping[str, float]) -> tuple[float, float]:
        return (p.get(h, 0.0), p.get(v, 0.0))

    for call in calls:
        if isinstance(
            call, canon.StraightTraverse | canon.StraightFeed | canon.ThreadFeed | canon.TapFeed
        ):
            path = [dict(call.end)]
        elif isinstance(call, canon.ArcFeed):
            path = arc_positions(pos, call)
        else:
            continue
        points = [at(pos), *(at(p) for p in path)]
        if total + len(points) > max_points:
            return Preview(plane, (h, v), segments, True)
        total += len(points)
        rapid = isinstance(call, canon.StraightTraverse)
        segments.append(Polyline(call.line, rapid, points))
        pos.update(path[-1])
    return Preview(plane, (h, v), segments, False)
