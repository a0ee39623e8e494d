"""The preview's tool path: arcs as points on their circle with chords within 1 µm of the arc,
the right way round, in the plane the machine draws (lathe G18: Z across, X up).

Expected values are geometry: the sagitta of a chord, the quarter points of a circle, the
projection of a helix."""

from __future__ import annotations

import itertools
import math

from nc_sim.channel import canon
from nc_sim.channel.interpreter import interpret
from nc_sim.channel.preview import (
    CHORD_TOLERANCE_MM,
    MAX_ARC_POINTS,
    arc_positions,
    preview,
)


def _calls(text: str, axes: tuple[str, ...] = ("X", "Y", "Z"), **start: float) -> list[canon.Call]:
    sink = canon.ListSink()
    interpret(text, sink, axes=axes, start=start)
    return sink.calls


def _chord_errors(
    points: list[tuple[float, float]], centre: tuple[float, float], r: float
) -> float:
    """The largest distance of any point or chord midpoint from the circle."""
    worst = 0.0
    for (x0, y0), (x1, y1) in itertools.pairwise(points):
        for x, y in ((x0, y0), ((x0 + x1) / 2, (y0 + y1) / 2)):
            worst = max(worst, abs(math.hypot(x - centre[0], y - centre[1]) - r))
    return worst


def test_every_arc_point_and_chord_stays_within_1_um_of_its_circle() -> None:
    # G17, radius 50 about (50, 0): G03 from (0, 0) half way round to (100, 0); counter-
    # clockwise from the circle's left end it passes below the centre, through (50, -50)
    calls = _calls("G17 G90 F500\nG03 X100 Y0 I50 J0\nM30")
    p = preview(calls, {"X": 0.0, "Y": 0.0, "Z": 0.0}, ("X", "Y", "Z"))
    (arc,) = [s for s in p.segments if not s.rapid]
    assert arc.points[0] == (0.0, 0.0) and arc.points[-1] == (100.0, 0.0)
    assert _chord_errors(arc.points, (50.0, 0.0), 50.0) <= CHORD_TOLERANCE_MM
    # counter-clockwise from the left end of the circle: down through (50, -50)
    lowest = min(arc.points, key=lambda q: q[1])
    assert math.isclose(lowest[0], 50.0, abs_tol=0.5)
    assert math.isclose(lowest[1], -50.0, abs_tol=1e-3)
    assert max(q[1] for q in arc.points) <= 1e-9
    # the fewest chords that keep the sagitta: n ≥ π / (2·acos(1 − t/r)) for a half circle
    least = math.pi / (2 * math.acos(1 - CHORD_TOLERANCE_MM / 50.0))
    assert math.ceil(least) <= len(arc.points) - 1 <= math.ceil(least) + 1


def test_g02_turns_clockwise_the_short_way() -> None:
    calls = _calls("G17 F500\nG02 X0 Y-10 I-10 J0\nM30", X=10.0, Y=0.0)
    p = preview(calls, {"X": 10.0, "Y": 0.0, "Z": 0.0}, ("X", "Y", "Z"))
    (arc,) = p.segments
    # a quarter circle clockwise from (10, 0) to (0, -10) about the origin: all in x ≥ 0, y ≤ 0
    assert all(x >= -1e-9 and y <= 1e-9 for x, y in arc.points)
    mid = arc.points[len(arc.points) // 2]
    assert math.isclose(mid[0], mid[1] * -1, abs_tol=0.05)  # near (7.07, -7.07)
    assert _chord_errors(arc.points, (0.0, 0.0), 10.0) <= CHORD_TOLERANCE_MM


def test_a_full_circle_goes_all_the_way_round() -> None:
    calls = _calls("G17 F500\nG03 X10 Y0 I-10 J0\nM30", X=10.0, Y=0.0)
    (arc,) = preview(calls, {"X": 10.0, "Y": 0.0}, ("X", "Y", "Z")).segments
    xs, ys = [q[0] for q in arc.points], [q[1] for q in arc.points]
    t = CHORD_TOLERANCE_MM  # the extremes may fall between two points, within one sagitta
    assert math.isclose(min(xs), -10.0, abs_tol=t) and math.isclose(max(ys), 10.0, abs_tol=t)
    assert math.isclose(min(ys), -10.0, abs_tol=t)
    assert _chord_errors(arc.points, (0.0, 0.0), 10.0) <= CHORD_TOLERANCE_MM


def test_a_huge_arc_is_capped_in_points() -> None:
    arc = canon.ArcFeed(1, (("X", -10000.0), ("Y", 0.0)), 17, (0.0, 0.0), 1)
    path = arc_positions({"X": 10000.0, "Y": 0.0}, arc)
    assert len(path) == MAX_ARC_POINTS
    assert path[-1] == {"X": -10000.0, "Y": 0.0}
    for q in path:  # the points still lie on the circle
        assert abs(math.hypot(q["X"], q["Y"]) - 10000.0) <= 1e-6


def test_lathe_draws_g18_with_z_across_and_x_up() -> None:
    """A lathe (X, Z): ZX plane, centre given as (Z, X); G03 counter-clockwise seen from +Y,
    which is counter-clockwise with Z across and X up (Z × X = Y)."""
    text = "G18 G90 F200\nG01 X20 Z0\nG03 X30 Z-10 K-10 I0\nM30"
    calls = _calls(text, axes=("X", "Z"), X=50.0, Z=5.0)
    p = preview(calls, {"X": 50.0, "Z": 5.0, "S": 123.0}, ("X", "Z"))
    assert p.plane == 18 and p.axes == ("Z", "X")
    line, arc = p.segments
    assert line.points == [(5.0, 50.0), (0.0, 20.0)]  # (Z, X)
    assert arc.points[-1] == (-10.0, 30.0)
    # centre (Z, X) = (-10, 20), radius 10: a quarter from angle 0 to 90°, halfway at 45°
    assert _chord_errors(arc.points, (-10.0, 20.0), 10.0) <= CHORD_TOLERANCE_MM
    h = 10.0 / math.sqrt(2.0)
    assert min(math.dist(q, (-10.0 + h, 20.0 + h)) for q in arc.points) < 0.01
    assert all(z >= -10.0 - 1e-9 and x >= 20.0 - 1e-9 for z, x in arc.points)


def test_a_lathe_program_without_g18_is_still_drawn_in_zx() -> None:
    calls = _calls("G00 X10 Z2\nM30", axes=("X", "Z"))
    p = preview(calls, {"X": 0.0, "Z": 0.0}, ("X", "Z"))
    assert p.plane == 18 and p.segments[0].rapid
    assert p.segments[0].points == [(0.0, 0.0), (2.0, 10.0)]


def test_a_helix_is_a_circle_seen_along_its_axis() -> None:
    calls = _calls("G17 F300\nG03 X10 Y0 Z-6 I-10 J0\nM30", X=10.0, Y=0.0, Z=0.0)
    (arc,) = preview(calls, {"X": 10.0, "Y": 0.0, "Z": 0.0}, ("X", "Y", "Z")).segments
    assert _chord_errors(arc.points, (0.0, 0.0), 10.0) <= CHORD_TOLERANCE_MM
    # seen in G18 (the program selects nothing else here, so project by hand): Z falls evenly
    helix = next(c for c in calls if isinstance(c, canon.ArcFeed))
    path = arc_positions({"X": 10.0, "Y": 0.0, "Z": 0.0}, helix)
    quarter = path[len(path) // 4 - 1]
    turned = math.atan2(quarter["Y"], quarter["X"]) % math.tau
    assert math.isclose(quarter["Z"], -6.0 * turned / math.tau, abs_tol=1e-9)


def test_a_budget_cuts_the_preview_and_says_so() -> None:
    text = "\n".join(f"G01 X{i} Y{i % 2} F100" for i in range(1, 50)) + "\nM30"
    p = preview(_calls(text), {}, ("X", "Y", "Z"), max_points=20)
    assert p.truncated and sum(len(s.points) for s in p.segments) <= 20
    assert not preview(_calls(text), {}, ("X", "Y", "Z")).truncated


def test_thread_cuts_and_tapping_are_drawn_as_the_straight_feeds_they_are() -> None:
    """G33 and G63 move straight to their end (a lathe, G18: Z across, X up); the G00 after
    them starts where they ended. G51: X72 is 36 mm radius, X80 40 mm."""
    text = "G51 G00 X72 Z105\nM3 S400\nG33 Z48 K1.5\nG00 X80\nM5\nG63 Z40 F300 S200\nM30"
    calls = _calls(text, axes=("X", "Z"))
    p = preview(calls, {"X": 0.0, "Z": 0.0}, ("X", "Z"))
    assert [(s.line, s.rapid, s.points) for s in p.segments] == [
        (1, True, [(0.0, 0.0), (105.0, 36.0)]),
        (3, False, [(105.0, 36.0), (48.0, 36.0)]),
        (4, True, [(48.0, 36.0), (48.0, 40.0)]),
        (6, False, [(48.0, 40.0), (40.0, 40.0)]),
    ]
