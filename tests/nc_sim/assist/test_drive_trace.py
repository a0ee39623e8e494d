"""The drive's oscilloscope on a copy: its signals at the drive's rate obey Newton on a rigid,
frictionless axis, and show the backlash taken up."""

from __future__ import annotations

import numpy as np
import pytest

from nc_sim.assist.drive_trace import drive_trace_experiment
from tests.nc_sim.assist.test_frequency_response import _machine

J_TOTAL = 0.002  # the plain test axis: p0341 0.001 kg·m² × p0342 2


def test_the_trace_runs_at_the_drive_rate_and_obeys_newton() -> None:
    r = drive_trace_experiment(_machine({}), "X", distance=5.0, duration_s=0.25)
    assert r.figure("rate_hz") == pytest.approx(8000.0)
    assert r.figure("samples") == 0.25 * 8000
    by = {s.name: s for s in r.series}
    t = np.array(by["motor speed"].x)
    assert np.allclose(np.diff(t), 1 / 8000)  # every sample, 125 µs apart
    w = np.array(by["motor speed"].y) * 2 * np.pi / 60  # rad/s
    torque = np.array(by["torque"].y)
    # J·dω/dt = the torque over the step (its mean of both ends: the current loop's state
    # changes within the step); the move accelerates, so the test is not of zeros
    accel_torque = J_TOTAL * np.diff(w) * 8000
    mean_torque = 0.5 * (torque[1:] + torque[:-1])
    assert np.max(np.abs(mean_torque)) > 1.0
    np.testing.assert_allclose(accel_torque, mean_torque, atol=0.02 * np.max(np.abs(torque)))


def test_the_motor_runs_ahead_of_the_load_by_half_the_backlash_once_it_pushes() -> None:
    b_mm = 0.02
    r = drive_trace_experiment(
        _machine({"sim.mech.backlash": round(b_mm * 1e4)}), "X", distance=2.0, duration_s=0.3
    )
    twist = next(s for s in r.series if s.name == "motor ahead of load")
    assert twist.y[-1] == pytest.approx(b_mm / 2 * 1000, abs=0.1)  # µm, pushing forwards
