"""The step-response assistant on a copy: the speed loop's step agrees with python-control's
step response of the same linear model; the position loop's with the first-order loop kv
gives when the speed loop is far faster; what the drive's parameters expect sits beside."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from nc_sim.assist.result import ExperimentError
from nc_sim.assist.step_response import POSITION, SPEED, step_response_experiment
from nc_sim.plant.linear import step_figures
from tests.nc_sim.assist.test_frequency_response import _machine
from tests.nc_sim.plant.test_frequency_response import (
    TS,
    _reference_open_loop,
    _speed_loop_params,
)


def test_a_speed_step_rises_and_overshoots_as_python_control_has_the_loop() -> None:
    cfg = _machine(_speed_loop_params()["X"])
    r = step_response_experiment(cfg, "X", SPEED, speed_rpm=30.0, duration_s=0.3)
    closed = control.feedback(_reference_open_loop(), 1)
    t = np.arange(round(0.3 / TS)) * TS
    y = np.asarray(control.step_response(closed, T=t).outputs).ravel()
    ref = step_figures(t, y, 1.0)
    assert ref.rise_s is not None
    assert r.figure("rise_ms") == pytest.approx(ref.rise_s * 1000, rel=0.1)
    assert r.figure("overshoot_pct") == pytest.approx(ref.overshoot_pct, rel=0.1)


def test_a_position_step_is_the_first_order_loop_of_kv() -> None:
    """kv 10/s on a speed loop of some 30 Hz: rise 10-90 % = ln 9 / kv = 220 ms, no
    overshoot, within ±2 % after ln 50 / kv = 391 ms (10 % for the inner loop's lag)."""
    cfg = _machine({"getriebe[0].kv": 1000})
    r = step_response_experiment(cfg, "X", POSITION, position_mm=0.05, duration_s=1.0)
    assert r.figure("rise_ms") == pytest.approx(1000 * math.log(9) / 10, rel=0.1)
    assert r.figure("overshoot_pct") < 0.5
    assert r.figure("settling_ms") == pytest.approx(1000 * math.log(50) / 10, rel=0.1)
    assert r.figure("rise_ms_expected") == pytest.approx(r.figure("rise_ms"), rel=0.05)


def test_a_resonance_the_drive_does_not_know_shows_against_the_expected_step() -> None:
    """A soft coupling (anti-resonance 25 Hz, resonance 25·√4 = 50 Hz) under a stiff speed
    loop rings: more overshoot than the drive's rigid model says, and the note says why."""
    cfg = _machine(
        {
            "drive.speed_kp": 1.2,
            "drive.inertia_ratio": 4.0,
            "sim.mech.anti_resonance": 25.0,
            "sim.mech.damping": 0.02,
        }
    )
    r = step_response_experiment(cfg, "X", SPEED, speed_rpm=20.0, duration_s=0.5)
    assert r.figure("overshoot_pct") > r.figure("overshoot_pct_expected") + 5.0
    assert any("mechanics" in n for n in r.notes)


def test_a_step_needs_the_cascade_and_an_axis_at_rest() -> None:
    with pytest.raises(ExperimentError, match="IDEAL"):
        step_response_experiment(_machine({"sim.plant": "IDEAL"}), "X")
