"""The circularity test's geometry against analytic paths: an offset circle, the radius a P
position loop leaves (R/√(1 + (ω/kv)²), issue 38's worked numbers), an ellipse at 45° and
135°, CW and CCW at different radii, a reversal spike at a quadrant point."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc_sim.circularity import (
    bidirectional_deviation,
    deviations,
    ellipse,
    fit_circle,
    radial_deviation,
    reversal_spikes,
)

R = 10.0  # mm
PHI = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False)


def circle(radius: float, x0: float = 0.0, y0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    return x0 + radius * np.cos(PHI), y0 + radius * np.sin(PHI)


def rotated_ellipse(e: float, axis_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Semi-axes R + e along axis_deg and R - e across it."""
    u, v = (R + e) * np.cos(PHI), (R - e) * np.sin(PHI)
    c, s = math.cos(math.radians(axis_deg)), math.sin(math.radians(axis_deg))
    return c * u - s * v, s * u + c * v


def test_an_offset_circle_is_fitted_exactly() -> None:
    x, y = circle(R, 3.0, -2.0)
    fit = fit_circle(x, y)
    assert (fit.x0, fit.y0, fit.radius) == pytest.approx((3.0, -2.0, R), abs=1e-9)
    d = deviations(x, y, R)
    assert d.circular == pytest.approx(0.0, abs=1e-9)
    assert d.radius_change == pytest.approx(0.0, abs=1e-9)


def test_a_p_loops_shrunken_circle_reads_as_its_radius_change() -> None:
    """F = 1000 mm/min, R = 10 mm, kv = 20/s: ω = F/R, the radius R/√(1 + (ω/kv)²): 34.5 µm
    less."""
    omega = 1000.0 / 60.0 / R
    actual = R / math.sqrt(1.0 + (omega / 20.0) ** 2)
    d = deviations(*circle(actual), R)
    assert d.radius_change == pytest.approx(-0.0345, rel=0.01)
    assert d.radial_max == pytest.approx(d.radius_change, abs=1e-9)  # round, only smaller
    assert d.circular == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("axis_deg", [45.0, 135.0])
def test_an_ellipse_shows_its_peak_to_valley_and_its_long_axis(axis_deg: float) -> None:
    e = 0.005  # 5 µm: peak-to-valley 10 µm
    x, y = rotated_ellipse(e, axis_deg)
    theta, dr = radial_deviation(x, y, fit_circle(x, y))
    el = ellipse(theta, dr)
    assert el.peak_to_valley == pytest.approx(2 * e, rel=0.01)
    assert el.axis_deg == pytest.approx(axis_deg, abs=0.5)
    assert deviations(x, y, R).circular == pytest.approx(2 * e, rel=0.02)


def test_cw_and_ccw_at_different_radii_are_each_round_but_apart_together() -> None:
    d = 0.002
    cw, ccw = circle(R + d), circle(R - d)
    assert deviations(*cw, R).circular == pytest.approx(0.0, abs=1e-9)
    assert deviations(*ccw, R).circular == pytest.approx(0.0, abs=1e-9)
    assert bidirectional_deviation([cw, ccw]) == pytest.approx(2 * d, rel=1e-6)


def test_a_reversal_spike_is_found_at_its_quadrant_with_its_height() -> None:
    """A 4 µm spike 2° wide where X reverses (90°), on top of a 10 µm ellipse."""
    x, y = rotated_ellipse(0.005, 45.0)
    ang = np.arctan2(y, x)
    polar = np.degrees(ang) % 360.0
    r = np.hypot(x, y) + 0.004 * np.exp(-(((polar - 90.0) / 2.0) ** 2))
    x, y = r * np.cos(ang), r * np.sin(ang)
    th, dr = radial_deviation(x, y, fit_circle(x, y))
    spikes = {round(s.angle_deg / 90.0) % 4: s for s in reversal_spikes(th, dr)}
    assert spikes[1].height == pytest.approx(0.004, rel=0.05)
    assert spikes[1].angle_deg == pytest.approx(90.0, abs=1.0)
    for q in (0, 2, 3):  # the other quadrants: no spike
        assert abs(spikes[q].height) < 0.0002
