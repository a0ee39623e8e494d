"""Friction, backlash, the torque limit and the notch of the drive cascade, against what
physics and the loop's algebra say, in simulated time; seeded random sessions with
invariants."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from nc_sim.plant import frf
from nc_sim.plant import layout as PL
from tests.nc_sim.plant.test_frequency_response import FS, _probe, _x_axis
from tests.nc_sim.sim_helpers import L, make, mdi

INC_MM = 1e-4  # X: one measuring-system increment (wegaufn/wegaufz = 1 · 0.1 µm)


def _trace_while(
    params: dict[str, dict[str, Any]], blocks: list[str], seconds: float
) -> np.ndarray:
    """Record X's drive trace while the MDI blocks run one after the other."""
    sim, m, _ = make(params)
    x = m.axis("X")
    sim.kernel.start_probe(x.slot, np.zeros(round(seconds * FS)), PL.INJECT_TORQUE)
    for block in blocks:
        mdi(m, block)
    sim.run(round(seconds / sim.kernel.cycle_s))
    return sim.kernel.probe_trace()


@pytest.mark.parametrize("tn_us", [0, 20000])
def test_coulomb_friction_costs_a_p_speed_loop_fc_over_kp_and_a_pi_loop_nothing(tn_us: int) -> None:
    kp, fc = 0.3, 0.45  # Nm·s/rad, Nm: a P loop runs 1.5 rad/s slow
    params = _x_axis(
        **{
            "drive.speed_kp": kp,
            "drive.speed_tn": tn_us,
            "sim.mech.coulomb_friction": fc,
        }
    )
    tr = _trace_while(params, ["G01 X150 F2000"], 2.0)  # 33 mm/s: 21 rad/s at 10 mm/rev
    cruise = tr[round(1.5 * FS) :]  # the ramp is long over, the NC's lag settled
    error = float(np.mean(cruise[:, PL.D_W_REF] - cruise[:, PL.D_W_MOTOR]))
    if tn_us == 0:
        assert error == pytest.approx(fc / kp, rel=0.01)
    else:
        assert abs(error) < 0.005 * fc / kp


def test_the_stribeck_curve_sets_the_friction_a_p_loop_pays_at_its_speed() -> None:
    kp, fc, fs, stribeck_rpm = 0.3, 0.3, 0.9, 200.0
    params = _x_axis(
        **{
            "drive.speed_kp": kp,
            "drive.speed_tn": 0,
            "sim.mech.coulomb_friction": fc,
            "sim.mech.breakaway_torque": fs,
            "sim.mech.stribeck_speed": stribeck_rpm,
        }
    )
    cruise = _trace_while(params, ["G01 X150 F2000"], 2.0)[round(1.5 * FS) :]
    w_ref = float(np.mean(cruise[:, PL.D_W_REF]))
    w_s = stribeck_rpm * 2 * math.pi / 60
    w = w_ref
    for _ in range(50):  # the speed where the P loop's torque Kp·(w_ref - w) meets F(w)
        w = w_ref - (fc + (fs - fc) * math.exp(-((w / w_s) ** 2))) / kp
    assert float(np.mean(cruise[:, PL.D_W_MOTOR])) == pytest.approx(w, rel=0.002)


@pytest.mark.parametrize("lead_mm", [5.0, 10.0])
def test_the_motor_turns_the_feed_over_the_travel_per_revolution(lead_mm: float) -> None:
    params = _x_axis(**{"sim.mech.travel_per_rev": round(lead_mm * 1e4)})
    cruise = _trace_while(params, ["G01 X150 F2000"], 2.0)[round(1.5 * FS) :]
    rpm = float(np.mean(cruise[:, PL.D_W_MOTOR])) * 60 / (2 * math.pi)
    assert rpm == pytest.approx(2000.0 / lead_mm, rel=1e-3)


def test_the_speed_setpoint_filter_is_a_first_order_lag_exactly_per_drive_step() -> None:
    t_filter = 0.004
    params = _x_axis(**{"drive.speed_setpoint_filter_t": round(t_filter * 1e6)})
    tr = _trace_while(params, ["G01 X150 F2000"], 0.5)
    w_set, w_ref = tr[1:, PL.D_W_SET], tr[:, PL.D_W_REF]
    moving = np.abs(w_set - w_ref[:-1]) > 0.05
    share = (w_ref[1:] - w_ref[:-1])[moving] / (w_set - w_ref[:-1])[moving]
    np.testing.assert_allclose(share, 1 - math.exp(-(1 / FS) / t_filter), rtol=1e-6)


def test_the_drive_runs_at_its_sampling_time() -> None:
    # 250 µs: four drive steps per NC cycle, and the mechanics still integrate exactly
    sim, m, _ = make(_x_axis(**{"drive.sampling_time": 250}))
    x = m.axis("X")
    steps = 4 * 3000
    sim.kernel.start_probe(x.slot, frf.prbs(11, 0.5, periods=6)[:steps], PL.INJECT_TORQUE)
    sim.run(3000)
    tr = sim.kernel.probe_trace()
    assert len(tr) == steps
    mech = frf.h1(tr[:, PL.D_TORQUE], tr[:, PL.D_W_MOTOR], 4000.0, nperseg=2048).band(10, 300)
    expected_db = -20.0 * np.log10(2 * 0.001 * 2 * np.pi * mech.f_hz)  # J = p0341 · p0342
    np.testing.assert_allclose(mech.magnitude_db, expected_db, atol=1.0)


def test_a_load_below_breakaway_sticks_and_does_not_creep() -> None:
    # no controller at all: 0.2 Nm pushes against 0.5 Nm of breakaway for a second
    params = _x_axis(
        **{
            "drive.speed_kp": 0.0,
            "sim.mech.coulomb_friction": 0.3,
            "sim.mech.breakaway_torque": 0.5,
        }
    )
    tr = _probe(params, np.full(round(1.2 * FS), 0.2), PL.INJECT_TORQUE)
    assert np.all(tr[:, PL.D_W_MOTOR] == 0.0)
    assert tr[-1, PL.D_X_LOAD] == tr[0, PL.D_X_LOAD]


def test_backlash_with_a_direct_measuring_system_costs_the_motor_the_gap_at_each_reversal() -> None:
    b = 0.05  # mm
    params = _x_axis(**{"sim.mech.backlash": round(b * 1e4), "sim.measuring_system": "DIRECT"})
    tr = _trace_while(params, ["G01 X60 F1000", "G01 X50"], 3.0)
    offset = tr[:, PL.D_X_MOTOR] - tr[:, PL.D_X_LOAD]
    forward = offset[round(0.5 * FS)]  # pushing towards +
    back = offset[-1]  # after the reversal, pushing towards -
    assert forward - back == pytest.approx(b, abs=INC_MM)
    # the load (the NC's measuring system) reached the targets: the motor made up the gap
    assert tr[-1, PL.D_X_LOAD] == pytest.approx(50.0, abs=0.01)


# current-setpoint filter n: type, denominator frequency and damping, numerator frequency and
# damping (p1657 … p1671)
FILTER_PARAMS = {
    1: (
        "drive.current_filter_1.type",
        "drive.current_filter_1.denominator_frequency",
        "drive.current_filter_1.denominator_damping",
        "drive.current_filter_1.numerator_frequency",
        "drive.current_filter_1.numerator_damping",
    ),
    2: (
        "drive.current_filter_2.type",
        "drive.current_filter_2.denominator_frequency",
        "drive.current_filter_2.denominator_damping",
        "drive.current_filter_2.numerator_frequency",
        "drive.current_filter_2.numerator_damping",
    ),
    3: (
        "drive.current_filter_3.type",
        "drive.current_filter_3.denominator_frequency",
        "drive.current_filter_3.denominator_damping",
        "drive.current_filter_3.numerator_frequency",
        "drive.current_filter_3.numerator_damping",
    ),
}


@pytest.mark.parametrize("which", [1, 2, 3])
def test_a_notch_at_the_resonance_takes_its_depth_off_the_closed_loop_peak(which: int) -> None:
    f_ar, ratio = 300.0, 3.0  # resonance f_ar·√3 = 519.6 Hz, far above the speed loop
    f_r = f_ar * math.sqrt(ratio)
    depth_db = 20.0 * math.log10(0.5 / 0.05)  # Dd / Dn: 20 dB
    base = {
        "drive.speed_kp": 0.8,
        "drive.inertia_ratio": ratio,
        "sim.mech.anti_resonance": f_ar,
        "sim.mech.damping": 0.02,
    }
    kind, f_den, d_den, f_num, d_num = FILTER_PARAMS[which]
    notch = {
        "drive.current_filter_active": 1 << (which - 1),
        kind: "GENERAL_2ND_ORDER",
        f_den: f_r,
        d_den: 0.5,
        f_num: f_r,
        d_num: 0.05,
    }

    def peak_db(extra: dict[str, Any]) -> float:
        tr = _probe(_x_axis(**base, **extra), frf.prbs(13, 1.0, periods=8), PL.INJECT_SPEED)
        closed = frf.h1(tr[:, PL.D_W_REF], tr[:, PL.D_W_MOTOR], FS, nperseg=8192)
        return float(np.max(closed.band(0.9 * f_r, 1.1 * f_r).magnitude_db))

    without, with_notch = peak_db({}), peak_db(notch)
    assert without - with_notch >= depth_db - 2.0


@pytest.mark.parametrize("seed", range(6))
def test_seeded_random_sessions_keep_the_plant_sound(seed: int) -> None:
    """Random plants and moves: no NaN, the torque setpoint within its limit, and with the
    drive's enables gone the plant comes to rest."""
    rng = np.random.default_rng(seed)
    limit = float(rng.uniform(1.0, 5.0))
    params = _x_axis(
        **{
            "drive.speed_kp": float(rng.uniform(0.05, 1.0)),
            "drive.speed_tn": int(rng.choice([0, 5000, 20000, 100000])),
            "drive.torque_limit": limit,
            "drive.inertia_ratio": float(rng.uniform(1.0, 6.0)),
            "sim.mech.anti_resonance": float(rng.choice([0.0, rng.uniform(30.0, 400.0)])),
            "sim.mech.damping": float(rng.uniform(0.01, 0.3)),
            "sim.mech.coulomb_friction": float(rng.uniform(0.0, 0.5)),
            "sim.mech.breakaway_torque": float(rng.uniform(0.0, 0.8)),
            "sim.mech.viscous_friction": float(rng.uniform(0.0, 0.01)),
            "sim.mech.backlash": int(rng.integers(0, 500)),
            "sim.measuring_system": str(rng.choice(["DIRECT", "INDIRECT"])),
        }
    )
    sim, m, _ = make(params)
    x = m.axis("X")
    n = 4.0
    sim.kernel.start_probe(x.slot, np.zeros(round(n * FS)), PL.INJECT_TORQUE)
    for _ in range(4):
        target = float(rng.uniform(20.0, 120.0))
        mdi(m, f"G01 X{target:.3f} F{float(rng.uniform(200.0, 4000.0)):.0f}")
        sim.run(round(n / 4 / sim.kernel.cycle_s))
    tr = sim.kernel.probe_trace()
    assert np.all(np.isfinite(tr))
    assert np.all(np.abs(tr[:, PL.D_T_SET]) <= limit + 1e-9)
    # the enables go: no torque, the brake holds, motor and load at rest
    sim.kernel.ist[x.slot, L.I_ENABLED] = 0  # as a drive-off of the PLC leaves it
    sim.kernel.start_probe(x.slot, np.zeros(round(0.1 * FS)), PL.INJECT_TORQUE)
    sim.run(100)
    rest = sim.kernel.probe_trace()[-8:]
    assert np.all(rest[:, PL.D_W_MOTOR] == 0.0) and np.all(rest[:, PL.D_W_LOAD] == 0.0)
