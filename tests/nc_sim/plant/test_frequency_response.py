"""The drive cascade and mechanics measured as an engineer would (an excitation through the
drive probe, H1 from the drive trace), against physics and against python-control's response
and margins of the same linear model built independently from the parameters."""

from __future__ import annotations

import math
from typing import Any

import control
import numpy as np
import pytest

from nc_sim.plant import frf
from nc_sim.plant import layout as PL
from nc_sim.plant.tuning import loop_figures
from tests.nc_sim.sim_helpers import make

TS = 125e-6  # the drive's default step
FS = 1.0 / TS
J_M = 0.001  # p0341 default (kg·m²)


def _x_axis(**extra: Any) -> dict[str, dict[str, Any]]:
    """X on the drive cascade from a plain start (whatever the demo's own plant): rigid,
    J_M 0.001 kg·m² (p0341) twice over (p0342), no filter, no friction, no backlash, 10 mm
    per motor revolution, a PI speed loop; `extra` on top."""
    values: dict[str, Any] = {
        "sim.plant": "DRIVE_CASCADE",
        "getriebe[0].lag_max": 10_000_000,
        "drive.speed_kp": 0.3,
        "drive.speed_tn": 20000,
        "drive.current_loop_t": 250,
        "drive.current_filter_active": 0,
        "drive.motor_inertia": J_M,
        "drive.inertia_ratio": 2.0,
        "sim.mech.anti_resonance": 0.0,
        "sim.mech.damping": 0.05,
        "sim.mech.travel_per_rev": 100000,
        "sim.mech.coulomb_friction": 0.0,
        "sim.mech.breakaway_torque": 0.0,
        "sim.mech.viscous_friction": 0.0,
        "sim.mech.backlash": 0,
        "sim.measuring_system": "DIRECT",
    }
    values.update(extra)
    return {"X": values}


def _probe(params: dict[str, dict[str, Any]], excitation: np.ndarray, point: int) -> np.ndarray:
    """Hold X at rest under the NC, run the excitation through its drive, return the trace
    (the first 0.2 s, while the loops settle into the excitation, left out)."""
    sim, m, _ = make(params)
    x = m.axis("X")
    sim.kernel.start_probe(x.slot, excitation, point)
    steps_per_cycle = round(sim.kernel.cycle_s / TS)
    sim.run(len(excitation) // steps_per_cycle)
    trace = sim.kernel.probe_trace()
    assert len(trace) == len(excitation) // steps_per_cycle * steps_per_cycle
    return trace[round(0.2 * FS) :]


def _mechanics(params: dict[str, dict[str, Any]]) -> frf.Frf:
    """Motor torque -> motor speed, excited with a PRBS at the torque setpoint."""
    exc = frf.prbs(13, 0.5, periods=12)
    tr = _probe(params, exc, PL.INJECT_TORQUE)
    return frf.h1(tr[:, PL.D_TORQUE], tr[:, PL.D_W_MOTOR], FS, nperseg=8192)


def test_two_mass_mechanics_shows_anti_resonance_and_resonance_where_physics_puts_them() -> None:
    # J_L/J_M = 2 (p0342 = 3): f_r = f_ar·√(1 + J_L/J_M) = 60·√3 = 103.92 Hz
    m = _mechanics(_x_axis(**{"drive.inertia_ratio": 3.0, "sim.mech.anti_resonance": 60.0}))
    peaks, dips = frf.resonances(m.band(5.0, 1000.0))
    assert len(peaks) == 1 and len(dips) == 1, (peaks, dips)
    assert dips[0] == pytest.approx(60.0, rel=0.02)
    assert peaks[0] == pytest.approx(60.0 * math.sqrt(3.0), rel=0.02)


def test_rigid_mechanics_is_an_integrator_of_the_total_inertia() -> None:
    m = _mechanics(_x_axis(**{"drive.inertia_ratio": 2.5})).band(10.0, 300.0)
    j = 2.5 * J_M
    expected_db = -20.0 * np.log10(j * 2.0 * np.pi * m.f_hz)  # -20 dB/decade
    np.testing.assert_allclose(m.magnitude_db, expected_db, atol=1.0)
    np.testing.assert_allclose(m.phase_deg, -90.0, atol=3.0)


# --- the speed loop against python-control ----------------------------------------------------

KP, TN = 0.3, 0.02  # p1460 (Nm·s/rad), p1462 (s)
T_I = 250e-6  # current loop
F_LP, D_LP = 1500.0, 0.7  # current setpoint filter 1: PT2 low pass
F_AR, RATIO, DAMP = 80.0, 2.0, 0.1


def _speed_loop_params() -> dict[str, dict[str, Any]]:
    return _x_axis(
        **{
            "drive.speed_kp": KP,
            "drive.speed_tn": round(TN * 1e6),
            "drive.current_loop_t": round(T_I * 1e6),
            "drive.current_filter_active": 1,
            "drive.current_filter_1.denominator_frequency": F_LP,
            "drive.current_filter_1.denominator_damping": D_LP,
            "drive.inertia_ratio": RATIO,
            "sim.mech.anti_resonance": F_AR,
            "sim.mech.damping": DAMP,
        }
    )


def _reference_open_loop() -> Any:
    """L(z) = PI(z) · z⁻¹ (computing time) · ZOH[low pass · current loop · two-mass](z), from
    the textbook transfer functions of each block."""
    s = control.tf("s")
    jm, jl = J_M, J_M * (RATIO - 1.0)
    k = jl * (2 * np.pi * F_AR) ** 2
    d = 2 * DAMP * np.sqrt(k * jl)
    mech = (jl * s**2 + d * s + k) / (s * (jm * jl * s**2 + d * (jm + jl) * s + k * (jm + jl)))
    wd = 2 * np.pi * F_LP
    low_pass = wd**2 / (s**2 + 2 * D_LP * wd * s + wd**2)
    current = 1 / (T_I * s + 1)
    plant = control.c2d(control.ss(low_pass * current * mech), TS, method="zoh")
    z = control.tf([1.0, 0.0], [1.0], TS)
    pi = KP * (1 + TS / TN * z / (z - 1))
    return pi * plant / z


def _measured_speed_loop() -> tuple[frf.Frf, frf.Frf]:
    """(closed loop w_ref -> w_motor, open loop speed error -> w_motor), excited at the
    speed setpoint."""
    tr = _probe(_speed_loop_params(), frf.prbs(14, 2.0, periods=10), PL.INJECT_SPEED)
    w_ref, w = tr[:, PL.D_W_REF], tr[:, PL.D_W_MOTOR]
    closed = frf.h1(w_ref, w, FS, nperseg=16384)
    open_loop = frf.h1(w_ref - w, w, FS, nperseg=16384)
    return closed, open_loop


def _response(sys: Any, f_hz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    resp = control.frequency_response(sys, 2 * np.pi * f_hz)
    h = np.asarray(resp.complex).ravel()
    return 20 * np.log10(np.abs(h)), np.degrees(np.angle(h))


def _phase_close(measured: np.ndarray, reference: np.ndarray, tol: float) -> None:
    diff = (measured - reference + 180.0) % 360.0 - 180.0
    assert np.max(np.abs(diff)) <= tol, float(np.max(np.abs(diff)))


def test_closed_and_open_speed_loop_agree_with_python_control_to_a_quarter_of_the_drive_rate() -> (
    None
):
    closed, open_loop = _measured_speed_loop()
    ref_open = _reference_open_loop()
    ref_closed = control.feedback(ref_open, 1)
    for measured, ref in ((closed, ref_closed), (open_loop, ref_open)):
        band = measured.band(10.0, FS / 4)
        mag, ph = _response(ref, band.f_hz)
        np.testing.assert_allclose(band.magnitude_db, mag, atol=1.0)
        _phase_close(np.degrees(np.angle(band.h)), ph, 3.0)


def test_speed_loop_margins_agree_with_python_control() -> None:
    _, open_loop = _measured_speed_loop()
    band = open_loop.band(5.0, FS / 2)
    got = loop_figures(band.f_hz, band.h)
    assert got is not None
    # python-control's margins from the model's response on a fine grid (its polynomial
    # method warns of round-off with these coefficients)
    omega = 2 * np.pi * np.logspace(0.0, np.log10(0.999 * FS / 2), 4000)
    gm, pm, wcg, wcp = control.margin(control.frd(_reference_open_loop(), omega))
    assert got.phase_margin_deg == pytest.approx(pm, abs=3.0)
    assert got.gain_margin_db == pytest.approx(20 * np.log10(gm), abs=1.0)
    assert got.crossover_hz == pytest.approx(wcp / (2 * np.pi), rel=0.03)
    assert got.phase_crossover_hz is not None
    assert got.phase_crossover_hz == pytest.approx(wcg / (2 * np.pi), rel=0.03)
