"""The circle the NC really drives, read with the circularity geometry (issue 38's acceptance,
ideal drive without lag, P position loop, no feedforward): the radius shrinks by the loop's
response at ω = F/R, and unequal kv of X and Z make an ellipse of peak-to-valley
F·|1/kv_x − 1/kv_z| along 45° or 135° that turns over between CW and CCW.

The loop is sampled: the NC reads the position at the start of its cycle and the drive
moves over the cycle (trapezoidal), so its response is python-control's of
L(z) = kv·T·(z + 1) / (2·z·(z − 1)). That shrinks the circle by (1 − kv·T)² of the
continuous R/√(1 + (ω/kv)²): 33.2 µm instead of 34.5 µm at kv 20/s (4 % less, outside the
issue's 2 % for the continuous formula)."""

from __future__ import annotations

import math
from typing import Any

import control
import numpy as np
import pytest

from nc_sim.circularity import deviations, ellipse, fit_circle, radial_deviation
from nc_sim.kernel import layout as L
from tests.nc_sim.sim_helpers import run_program

R, F = 10.0, 1000.0  # mm, mm/min
TURN_S = 2 * math.pi * R / (F / 60.0)  # one revolution at F: 3.77 s


def _axis(kv: float) -> dict[str, Any]:
    return {
        "sim.plant": "IDEAL",
        "sim.drive_t": 0,  # the drive follows at once: the loop is kv's alone
        "getriebe[0].kv": round(kv * 100),
        "lr_param.ff_weight": 0,
    }


def _circle(kv_x: float, kv_z: float, g: int) -> tuple[np.ndarray, np.ndarray]:
    """Three full circles (G18: Z across, X up) about Z-90 X50 from the demo's start
    Z-100 X50; the actual path of the middle one, reached at speed (the first runs up,
    the third runs out: ISO 230-4's overrun)."""
    arc = f"G{g:02d} X50 Z-100 K10"
    program = f"G18 G90 F{F:g}\n{arc}\n{arc}\n{arc}\nM30\n"
    _sim, m, rec = run_program(program, 3 * TURN_S + 1.0, axes={"X": _axis(kv_x), "Z": _axis(kv_z)})
    middle = rec[:, m.channel_slot, L.R_LINE] == 3
    x, z = m.axis("X"), m.axis("Z")
    assert middle.sum() == pytest.approx(TURN_S * 1000, rel=0.01)
    return rec[middle, z.slot, L.R_P_ACT], rec[middle, x.slot, L.R_P_ACT]


def _sampled_gain(kv: float, omega: float) -> float:
    t = 0.001
    z = control.tf([1.0, 0.0], [1.0], t)
    loop = kv * t * (z + 1) / (2 * z * (z - 1))
    h = control.frequency_response(control.feedback(loop, 1), [omega]).complex
    return float(np.abs(np.asarray(h).ravel()[0]))


def test_a_p_loops_circle_shrinks_as_its_sampled_response_says() -> None:
    kv = 20.0
    omega = F / 60.0 / R
    continuous = R / math.sqrt(1.0 + (omega / kv) ** 2) - R  # -34.5 µm
    expected = R * _sampled_gain(kv, omega) - R
    assert expected == pytest.approx(continuous * (1 - kv * 0.001) ** 2, rel=0.005)
    for g in (2, 3):
        d = deviations(*_circle(kv, kv, g), R)
        assert d.radius_change == pytest.approx(expected, rel=0.02)
        assert d.circular < 0.1 * abs(expected)  # and round


def test_unequal_kv_make_an_ellipse_that_turns_over_with_the_direction() -> None:
    kv_x, kv_z = 20.0, 25.0
    p2v = F / 60.0 * abs(1 / kv_x - 1 / kv_z)  # 0.167 mm
    diagonals = []
    for g in (2, 3):
        za, xa = _circle(kv_x, kv_z, g)
        theta, dr = radial_deviation(za, xa, fit_circle(za, xa))
        el = ellipse(theta, dr)
        assert el.peak_to_valley == pytest.approx(p2v, rel=0.05)
        diagonal = 45.0 if abs(el.axis_deg - 45.0) < abs(el.axis_deg - 135.0) else 135.0
        assert el.axis_deg == pytest.approx(diagonal, abs=5.0)
        diagonals.append(diagonal)
    assert sorted(diagonals) == [45.0, 135.0]  # CW and CCW on crossing diagonals
