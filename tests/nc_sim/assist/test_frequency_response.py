"""The frequency-response assistant on a copy: what it finds agrees with physics and with
python-control's margins of the same linear model; it refuses what it cannot measure."""

from __future__ import annotations

import math
from typing import Any

import control
import numpy as np
import pytest

from nc_sim.assist.frequency_response import (
    CHIRP,
    CLOSED_POSITION,
    CLOSED_SPEED,
    MECHANICS,
    OPEN_SPEED,
    frequency_response,
    frequency_response_experiment,
)
from nc_sim.assist.procedure import step_through
from nc_sim.assist.result import ExperimentError
from nc_sim.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.kernel import layout as L
from nc_sim.params import Scope
from nc_sim.snapshot import AxisState
from tests.nc_sim.plant.test_frequency_response import (
    FS,
    _reference_open_loop,
    _speed_loop_params,
    _x_axis,
)
from tests.nc_sim.plant.x_speed_loop import F_AR, Knobs, margins, open_loop
from tests.nc_sim.sim_helpers import make
from tests.nc_sim.training.seats import Seat


def _machine(x: dict[str, Any]) -> MachineConfig:
    """The demo lathe with X on the plain drive cascade of the plant tests, `x` on top."""
    cfg = demo_machine()
    apply_overrides(cfg, Scope.AXIS, "X", _x_axis(**x)["X"])
    return cfg


def test_mechanics_with_friction_measured_at_an_offset_speed_show_the_two_mass_frequencies() -> (
    None
):
    cfg = _machine(
        {
            "drive.inertia_ratio": 4.0,  # J_L/J_M = 3: f_r = 2·f_ar
            "sim.mech.anti_resonance": 45.0,
            "sim.mech.coulomb_friction": 0.2,
        }
    )
    r = frequency_response_experiment(cfg, "X", MECHANICS, offset_rpm=40.0, window_mm=80.0)
    assert r.figure("anti_resonance_1_hz") == pytest.approx(45.0, rel=0.02)
    assert r.figure("resonance_1_hz") == pytest.approx(90.0, rel=0.02)
    names = [s.name for s in r.series]
    assert names == ["magnitude_db", "phase_deg", "coherence"]
    f = np.array(r.series[0].x)
    assert f[0] >= 2.0 and f[-1] <= FS / 2  # the band asked for, up to half the drive rate
    sweep = frequency_response_experiment(
        cfg, "X", MECHANICS, excitation=CHIRP, offset_rpm=40.0, window_mm=80.0
    )
    assert sweep.figure("resonance_1_hz") == pytest.approx(90.0, rel=0.02)


def test_open_speed_loop_margins_agree_with_python_control() -> None:
    cfg = _machine(_speed_loop_params()["X"])
    r = frequency_response_experiment(cfg, "X", OPEN_SPEED, f_min_hz=5.0)
    omega = 2 * np.pi * np.logspace(0.0, np.log10(0.999 * FS / 2), 4000)
    gm, pm, _wcg, wcp = control.margin(control.frd(_reference_open_loop(), omega))
    assert r.figure("phase_margin_deg") == pytest.approx(pm, abs=3.0)
    assert r.figure("gain_margin_db") == pytest.approx(20 * math.log10(gm), abs=1.0)
    assert r.figure("crossover_hz") == pytest.approx(wcp / (2 * np.pi), rel=0.03)


def test_a_loop_that_crosses_0_db_again_reports_its_worst_phase_margin() -> None:
    """The soft-coupling exercise's start (exercises/soft-coupling.toml): the old notch on
    103 Hz, the resonance moved to 73 Hz. The loop crosses 0 dB several times; the margin
    that counts is the least, as python-control's model has it (11.5°), not the first
    crossover's (about 47°) the Bode panel showed a student."""
    seat = Seat("soft-coupling")
    r = step_through(seat.sim, frequency_response(seat.m, "X", OPEN_SPEED, f_min_hz=5.0))
    knobs = Knobs(1.37, 6.3e-3, ((102.8, 0.15, 0.015),))
    pm, gm = margins(open_loop(knobs, F_AR * math.sqrt(0.5)))
    assert r.figure("phase_margin_deg") == pytest.approx(pm, abs=3.0)
    assert r.figure("gain_margin_db") == pytest.approx(gm, abs=1.0)


def test_closed_loops_bandwidths_order_as_the_cascade_says() -> None:
    """The position loop (kv 10/s: a first-order lag at kv/2π = 1.59 Hz while the speed loop
    is far faster) inside the speed loop's bandwidth."""
    cfg = _machine({"sim.plant": "DRIVE_CASCADE", "getriebe[0].kv": 1000})
    pos = frequency_response_experiment(cfg, "X", CLOSED_POSITION, f_min_hz=0.5, offset_rpm=0.0)
    speed = frequency_response_experiment(cfg, "X", CLOSED_SPEED)
    assert pos.figure("bandwidth_hz") == pytest.approx(10.0 / (2 * math.pi), rel=0.1)
    assert speed.figure("bandwidth_hz") > 10 * pos.figure("bandwidth_hz")


def test_an_ideal_plant_or_a_window_too_small_is_refused_before_anything_moves() -> None:
    with pytest.raises(ExperimentError, match="IDEAL"):
        frequency_response_experiment(_machine({"sim.plant": "IDEAL"}), "X")
    cfg = _machine({"sim.plant": "DRIVE_CASCADE"})
    with pytest.raises(ExperimentError, match="window"):
        frequency_response_experiment(cfg, "X", offset_rpm=300.0, window_mm=5.0)


def test_the_axis_returns_to_where_it_started_after_the_offset_motion() -> None:
    """At 30 rpm (10 mm per motor revolution: 5 mm/s) X moves about 17 mm in the 3.3 s of a
    10-average measurement, then goes back: it ends in its exact-stop window."""
    sim, m, _ = make({"X": {}})
    x = m.axis("X")
    start = float(sim.kernel.st[x.slot, L.S_P_ACT])
    r = step_through(sim, frequency_response(m, "X", MECHANICS))
    assert r.figure("measured_s") > 3.0
    window = x.cfg.eng("kenngr.exact_stop_window")
    assert float(sim.kernel.st[x.slot, L.S_P_ACT]) == pytest.approx(start, abs=window)
    assert x.state is AxisState.STANDSTILL
