"""Spindle behaviours against the manuals [000, 001] and physics, in simulated time."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from nc_sim.commands import (
    Accepted,
    HliWrite,
    Mdi,
    PlcMode,
    Refused,
    Reset,
    SpindlePosition,
    SpindleRun,
)
from nc_sim.errors import Code
from nc_sim.kernel.curve import curve_accel
from nc_sim.kernel.step import V_ACT_FILTER_S
from nc_sim.machine.machine import Machine
from nc_sim.sim import Simulation
from nc_sim.snapshot import AxisState
from nc_sim.spindle.gears import GearRange, select_gear
from tests.nc_sim.sim_helpers import L, make, mdi, record

DT = 0.001
RPM = 6.0  # °/s per rpm
S = "S1"


def codes(m: Machine) -> list[int]:
    return [e.code for e in m.events]


def first(mask: np.ndarray) -> int:
    """Index of the first true sample (fails when there is none)."""
    idx = np.flatnonzero(mask)
    assert idx.size, "condition never met"
    return int(idx[0])


def trapezoid_time_to(v: float, a: float, tr: float) -> float:
    """Time a jerk-limited ramp from rest (a, ramp time tr) takes to reach speed v [002 §2.2]."""
    j = a / tr
    v_jerk = 0.5 * a * tr  # speed gained while the acceleration builds up
    if v <= v_jerk:
        return math.sqrt(2 * v / j)
    return tr + (v - v_jerk) / a


# --- endless rotation, speed monitoring ------------------------------------------------------
def test_sensorless_speed_reached_edge_is_the_commands_band_entry() -> None:
    sim, m, cfg = make({S: {"sim.sensorless": 1}}, {"spindel[0].m3_synch": 0})
    s = m.axis(S)
    mdi(m, "M3 S1000")
    rec = record(sim, 3.0)[:, s.slot]
    a = cfg.axis(S).eng("getriebe[2].slope_profil.a_beschl", 3)
    tr = cfg.axis(S).eng("getriebe[2].slope_profil.tr_beschl_zu", 3)
    # band ±10 % (vb_prozent 100): reached when the command passes 900 rpm
    t_edge = (first(rec[:, L.R_SPEED_REACHED] == 1) + 1) * DT
    t_band = trapezoid_time_to(0.9 * 1000 * RPM, a, tr)
    assert 0.0 <= t_edge - t_band <= DT + 1e-9  # the first sample at or after the entry
    assert rec[-1, L.R_LAG] == 0.0  # no encoder: the actual value is the command
    assert rec[-1, L.R_OPEN_LOOP] == L.LOOP_SPEED_CONTROL


def test_speed_reached_with_encoder_follows_the_loop_delay_and_stopped_below_vb_min_null() -> None:
    sim, m, cfg = make(channel={"spindel[0].m3_synch": 0, "spindel[0].m5_synch": 0})
    s = m.axis(S)
    m.submit(Mdi("M3 S1000"))
    rec = record(sim, 3.0)[:, s.slot]
    a = cfg.axis(S).eng("getriebe.slope_profil.a_beschl", 3)
    tr = cfg.axis(S).eng("getriebe.slope_profil.tr_beschl_zu", 3)
    kv = cfg.axis(S).eng("getriebe.kv", 3)
    t_cmd = trapezoid_time_to(0.9 * 6000.0, a, tr)
    t_edge = (first(rec[:, L.R_SPEED_REACHED] == 1) + 1) * DT
    # a P loop follows a speed ramp 1/kv behind (the drive lag adds nothing to that for a
    # type-1 loop); the measured speed's filter adds its time constant
    assert t_edge - t_cmd == pytest.approx(1 / kv + V_ACT_FILTER_S, abs=0.002)
    # monitoring: active with the M3, invalid while the command still changes
    assert rec[10, L.R_MON_ACTIVE] == 1 and rec[10, L.R_MON_INVALID] == 1
    assert rec[-1, L.R_MON_ACTIVE] == 1 and rec[-1, L.R_MON_INVALID] == 0
    m.submit(Mdi("M5"))
    rec = record(sim, 3.0)[:, s.slot]
    assert rec[-1, L.R_MON_ACTIVE] == 0 and s.state is AxisState.STANDSTILL
    v_zero = cfg.axis(S).eng("getriebe.vb_min_null", 3)
    i = first(rec[:, L.R_STOPPED] == 1)
    assert abs(rec[i, L.R_V_ACT]) < v_zero <= abs(rec[i - 1, L.R_V_ACT])


def test_speed_monitoring_flags_have_one_edge_each() -> None:
    """A quantised encoder's ripple must not toggle the flags: M3 S1000 gives one "speed
    reached" edge and event; M5 one "stopped" edge, and the settled loop stops counting."""
    sim, m, _ = make(channel={"spindel[0].m3_synch": 0, "spindel[0].m5_synch": 0})
    s = m.axis(S)
    m.submit(Mdi("M3 S1000"))
    rec = record(sim, 3.0)[:, s.slot]
    assert np.count_nonzero(np.diff(rec[:, L.R_SPEED_REACHED])) == 1
    assert codes(m).count(Code.EV_SPEED_REACHED) == 1
    m.submit(Mdi("M5"))
    rec = record(sim, 6.0)[:, s.slot]
    edges = np.flatnonzero(np.diff(rec[:, L.R_STOPPED]))
    assert len(edges) == 1 and rec[edges[0] + 1, L.R_STOPPED] == 1
    rest = rec[-2000:]  # the last 2 s: no hunting across an increment edge
    assert np.ptp(rest[:, L.R_P_ACT]) == 0.0 and np.abs(rest[:, L.R_V_ACT]).max() < 1e-6


def test_override_example_g167_and_rev_from_the_manual() -> None:
    """[000 §2.4.1] at 50 %: S[M3 REV1000] 500 rpm; S[G167] 1000 rpm; S[REV3000] 1500 rpm."""
    sim, m, _ = make(channel={"spindel[0].m3_synch": 0})
    s = m.axis(S)
    m.submit(HliWrite("override", 500, S))
    m.submit(Mdi("S[M3 REV1000]"))
    rec = record(sim, 2.0)[:, s.slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(500.0)
    assert rec[-1, L.R_OVERRIDE] == pytest.approx(0.5)
    m.submit(Mdi("S[G167]"))
    rec = record(sim, 2.0)[:, s.slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(1000.0)
    m.submit(Mdi("S[REV3000]"))
    rec = record(sim, 4.0)[:, s.slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(1500.0)
    m.submit(HliWrite("override_valid", 0, S))  # invalid override: 100 %
    rec = record(sim, 4.0)[:, s.slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(3000.0)


# --- M19 --------------------------------------------------------------------------------------
def _m19(m: Machine, sim: Simulation, text: str, seconds: float = 6.0) -> np.ndarray:
    mdi(m, text)
    return record(sim, seconds)


def _approach_sign(r: np.ndarray) -> float:
    moving = np.flatnonzero(np.abs(r[:, L.R_V_CMD]) > 1e-9)
    return float(np.sign(r[moving[-1], L.R_V_CMD]))


def test_m19_shortest_way_from_standstill_and_exact_stop() -> None:
    sim, m, cfg = make()
    s = m.axis(S)
    rec = _m19(m, sim, "M19 S.POS=10")[:, s.slot]  # homes automatically first
    assert Code.EV_HOMED in codes(m) and s.homed
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    done = next(e for e in m.events if e.code == Code.EV_IN_POSITION)
    p_done = rec[done.cycle - 21, L.R_P_ACT]  # record starts after 20 settle cycles
    assert abs((p_done - 10.0 + 180) % 360 - 180) <= window
    # the edge is the first sample inside the window: the one before was still outside
    assert abs((rec[done.cycle - 22, L.R_P_ACT] - 10.0 + 180) % 360 - 180) > window
    p0 = rec[-1, L.R_P_CMD]
    rec = _m19(m, sim, "M19 S.POS=350")[:, s.slot]  # 20° back is shorter than 340° on
    assert rec[-1, L.R_P_CMD] - p0 == pytest.approx(-20.0)
    assert s.state is AxisState.STANDSTILL and rec[-1, L.R_IN_POS] == 1


@pytest.mark.parametrize(("m_dir", "sign"), [("M3", 1.0), ("M4", -1.0)])
def test_m19_with_direction_from_standstill_turns_that_way(m_dir: str, sign: float) -> None:
    sim, m, cfg = make()
    s = m.axis(S)
    _m19(m, sim, "M19 S.POS=0")
    p0 = m.k.st[s.slot, L.S_P_CMD]
    rec = _m19(m, sim, f"M19 S.POS=30 {m_dir}")[:, s.slot]
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    assert _approach_sign(rec) == sign
    moved = rec[-1, L.R_P_CMD] - p0
    assert moved == pytest.approx(30.0 if sign > 0 else -330.0)
    assert abs((rec[-1, L.R_P_ACT] - 30.0 + 180) % 360 - 180) <= window
    assert np.all(np.sign(rec[:, L.R_V_CMD]) * sign >= 0)  # never the other way


def test_m19_from_rotation_keeps_the_direction_and_with_m3_reverses() -> None:
    sim, m, cfg = make(channel={"spindel[0].m4_synch": 0, "spindel[0].m3_synch": 0})
    s = m.axis(S)
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    _m19(m, sim, "M19 S.POS=0")
    m.submit(Mdi("M4 S800"))
    record(sim, 2.5)
    rec = _m19(m, sim, "M19 S.POS=123")[:, s.slot]
    assert np.all(rec[:, L.R_V_CMD] <= 1e-9)  # continued in M4 direction, no reversal
    assert abs((rec[-1, L.R_P_ACT] - 123.0 + 180) % 360 - 180) <= window
    m.submit(Mdi("M4 S800"))
    record(sim, 2.5)
    rec = _m19(m, sim, "M19 S.POS=200 M3 S100")[:, s.slot]  # reversal [001 Fig. 1]
    assert rec[:, L.R_V_CMD].min() < -700 * RPM and _approach_sign(rec) == 1.0
    assert abs((rec[-1, L.R_P_ACT] - 200.0 + 180) % 360 - 180) <= window
    assert rec[:, L.R_V_CMD].max() <= 100 * RPM + 1e-6  # positioning speed S100


def test_preferred_direction_refuses_the_other_with_60254_until_reset() -> None:
    sim, m, _ = make({S: {"kenngr.vorz_richtung": 1, "kenngr.beweg_richt": 1}})
    s = m.axis(S)
    m.submit(Mdi("M4 S500"))
    record(sim, 0.1)
    assert Code.SPINDLE_PREFERRED_DIRECTION in codes(m) and s.state is AxisState.ERROR
    m.submit(Mdi("M3 S500"))  # even the allowed direction is refused: error state until reset
    assert m.events[-1].code == Code.CHANNEL_ERROR_STATE and m.events[-1].axis == S
    record(sim, 0.1)
    assert s.state is AxisState.ERROR
    # the refusal is logged, the spindle's error stays the cause: 60254, not 90015
    assert [e.code for e in m.snapshot().job_errors] == [Code.SPINDLE_PREFERRED_DIRECTION]
    m.submit(Reset())
    m.submit(Mdi("M3 S500"))
    record(sim, 2.0)
    assert m.axis(S).state is AxisState.ENDLESS
    m.submit(Mdi("M5"))
    record(sim, 2.0)
    rec = _m19(m, sim, "M19 S.POS=300")[:, s.slot]  # no direction given: the preferred one
    assert np.all(rec[:, L.R_V_CMD] >= -1e-9)


def test_sensorless_spindle_cannot_position() -> None:
    sim, m, _ = make({S: {"sim.sensorless": 1}})
    m.submit(Mdi("M19 S.POS=90"))
    record(sim, 0.1)
    assert Code.SPINDLE_SENSORLESS_M19 in codes(m)
    assert m.axis(S).state is AxisState.STANDSTILL


# --- homing, reference, control limit ---------------------------------------------------------
def test_g74_homes_on_the_zero_mark_and_stops_on_ref_pos() -> None:
    sim, m, cfg = make({S: {"sim.ref_cam_pos": 1234567, "kenngr.ref_pos": 900000}})
    s = m.axis(S)
    rec = _m19(m, sim, "S[G74]")[:, s.slot]
    assert s.homed and s.state is AxisState.STANDSTILL
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    assert abs((rec[-1, L.R_P_ACT] - 90.0 + 180) % 360 - 180) <= window
    # the NC's 90° is the physical zero mark at 123.4567° of the load
    x = m.k.st[s.slot, L.S_X_MOTOR]
    assert (x - 123.4567 + 180) % 360 - 180 == pytest.approx(0.0, abs=window)


def test_digital_drive_needs_g74_before_m19() -> None:
    sim, m, cfg = make({S: {"kenngr.achs_mode": 0x101}})
    s = m.axis(S)
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    m.submit(Mdi("M19 S.POS=45"))
    record(sim, 0.2)
    assert Code.SPINDLE_NOT_HOMED in codes(m) and s.state is AxisState.ERROR
    m.submit(Reset())
    _m19(m, sim, "S[G74]")
    rec = _m19(m, sim, "M19 S.POS=45")[:, s.slot]
    assert s.homed and abs((rec[-1, L.R_P_ACT] - 45.0 + 180) % 360 - 180) <= window


def test_control_limit_opens_the_loop_loses_and_regains_the_reference() -> None:
    limit_rpm = 2000
    sim, m, cfg = make(
        {S: {"getriebe[2].vb_regelgrenze": limit_rpm * 6000}},
        {"spindel[0].m3_synch": 0},
    )
    s = m.axis(S)
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    _m19(m, sim, "M19 S.POS=0")
    assert s.homed
    m.submit(Mdi("M3 S3000"))
    rec = record(sim, 8.0)[:, s.slot]
    i = first(rec[:, L.R_OPEN_LOOP] == L.LOOP_CONTROL_LIMIT)
    assert rec[i, L.R_V_CMD] > limit_rpm * RPM >= rec[i - 1, L.R_V_CMD]
    assert rec[i, L.R_HOMED] == 0 and not s.homed and Code.EV_REFERENCE_LOST in codes(m)
    assert s.state is AxisState.OPEN_LOOP and rec[-1, L.R_MON_INVALID] == 1
    kv = cfg.axis(S).eng("getriebe.kv", 3)
    assert rec[-1, L.R_LAG] == pytest.approx(3000 * RPM / kv, rel=1e-3)  # simulated from lag
    homed_before = codes(m).count(Code.EV_HOMED)
    rec = _m19(m, sim, "M19 S.POS=270", 8.0)[:, s.slot]
    j = first(rec[:, L.R_OPEN_LOOP] == L.LOOP_CLOSED)
    assert abs(rec[j, L.R_V_CMD]) <= limit_rpm * RPM
    assert codes(m).count(Code.EV_HOMED) == homed_before + 1  # automatic homing before M19
    assert abs((rec[-1, L.R_P_ACT] - 270.0 + 180) % 360 - 180) <= window


def test_changeover_to_speed_control_and_back_for_m19_as_in_the_manual() -> None:
    """[001 §2.3]: 767 = 200 rpm, 768 = 100 rpm; M4 S1000, then M19 S.POS=180 M4 S500."""
    sim, m, cfg = make(
        {
            S: {
                "antr.sai_op_mode_change.v_velocity_control_on": 1200000,
                "antr.sai_op_mode_change.v_position_control_on": 600000,
            }
        },
        {"spindel[0].m4_synch": 0},
    )
    s = m.axis(S)
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    _m19(m, sim, "M19 S.POS=0")
    m.submit(Mdi("M4 S1000"))
    rec = record(sim, 3.0)[:, s.slot]
    i = first(rec[:, L.R_OPEN_LOOP] == L.LOOP_SPEED_CONTROL)
    assert abs(rec[i, L.R_V_CMD]) > 200 * RPM >= abs(rec[i - 1, L.R_V_CMD])
    assert s.homed  # speed control below the control limit keeps the reference
    rec = _m19(m, sim, "M19 S.POS=180 M4 S500")[:, s.slot]
    j = first(rec[:, L.R_OPEN_LOOP] == L.LOOP_CLOSED)
    assert abs(rec[j - 1, L.R_V_CMD]) == pytest.approx(100 * RPM)  # down to 768 first
    closed = rec[j:, L.R_OPEN_LOOP]
    assert np.all(closed == L.LOOP_CLOSED)  # the 500 rpm positioning stays position-controlled
    assert abs((rec[-1, L.R_P_ACT] - 180.0 + 180) % 360 - 180) <= window
    # special case [001 p.15]: positioning speed above the changeover speed, still closed
    assert np.abs(rec[j:, L.R_V_CMD]).max() <= 500 * RPM + 1e-6


def test_switch_back_from_speed_control_takes_over_the_lag_without_a_step() -> None:
    """[001 §2.3] 767 = 768 = 800 rpm: M19 after M3 S1000 decelerates to 800 rpm and closes the
    loop at speed; the loop takes over the lag it would have had, with no jump of one
    cycle's travel (800 rpm = 4.8° per cycle), so lag monitoring stays quiet."""
    rpm = 800
    sim, m, cfg = make(
        {
            S: {
                "antr.sai_op_mode_change.v_velocity_control_on": rpm * 6000,
                "antr.sai_op_mode_change.v_position_control_on": rpm * 6000,
            }
        },
        {"spindel[0].m3_synch": 0},
    )
    s = m.axis(S)
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    m.submit(Mdi("M3 S1000"))
    record(sim, 3.0)
    assert m.k.ist[s.slot, L.I_OPEN_LOOP] == L.LOOP_SPEED_CONTROL
    rec = _m19(m, sim, "M19 S.POS=180")[:, s.slot]
    assert Code.LAG_MONITORING not in codes(m)
    j = first(rec[:, L.R_OPEN_LOOP] == L.LOOP_CLOSED)
    v = abs(rec[j, L.R_V_CMD])
    assert v == pytest.approx(rpm * RPM)
    step = abs(rec[j, L.R_LAG] - rec[j - 1, L.R_LAG])
    assert step < 0.05 * v * DT  # far below one cycle of travel
    assert abs((rec[-1, L.R_P_ACT] - 180.0 + 180) % 360 - 180) <= window


def test_changeover_stays_in_speed_control_for_a_lower_speed_and_reset_switches_back() -> None:
    sim, m, _ = make(
        {S: {"antr.sai_op_mode_change.v_velocity_control_on": 1200000}},
        {"spindel[0].m3_synch": 0, "main_spindle_gear_change": 0},  # S150 in this stage
    )
    s = m.axis(S)
    m.submit(Mdi("M3 S1000"))
    record(sim, 3.0)
    m.submit(Mdi("M3 S150"))
    rec = record(sim, 3.0)[:, s.slot]
    assert np.all(rec[:, L.R_OPEN_LOOP] == L.LOOP_SPEED_CONTROL)
    m.submit(Reset())
    record(sim, 0.01)
    assert m.k.ist[s.slot, L.I_OPEN_LOOP] == L.LOOP_CLOSED


def test_old_changeover_names_p_axis_00265_00266_keep_working() -> None:
    """[001 p.18-19]: 00767/00768 replace 00265/00266, "however, the latter retains its
    functionality": 200 rpm / 100 rpm by the old names change over and back as the new do."""
    sim, m, _ = make(
        {
            S: {
                "antr.velocity_position_control_on": 1200000,
                "antr.velocity_position_control_off": 600000,
            }
        },
        {"spindel[0].m4_synch": 0},
    )
    s = m.axis(S)
    _m19(m, sim, "M19 S.POS=0")
    m.submit(Mdi("M4 S1000"))
    rec = record(sim, 3.0)[:, s.slot]
    i = first(rec[:, L.R_OPEN_LOOP] == L.LOOP_SPEED_CONTROL)
    assert abs(rec[i, L.R_V_CMD]) > 200 * RPM >= abs(rec[i - 1, L.R_V_CMD])
    rec = _m19(m, sim, "M19 S.POS=180 M4 S500")[:, s.slot]
    j = first(rec[:, L.R_OPEN_LOOP] == L.LOOP_CLOSED)
    assert abs(rec[j - 1, L.R_V_CMD]) == pytest.approx(100 * RPM)  # down to 00266 first


# the drive of the manual's example: 32767 digits (10 V) turn the motor at 3000 rpm
DRIVE_3000 = {"sim.getriebe[2].drive_gain": 32767 / 1080, "lr_hw[0].da_max": 32767}
SPEED_SCALING = {
    "antr.operation_mode": "OPEN_POSITION_LOOP_MODE",
    "antr.v_time_base": 0,
    "antr.v_reso_num": 32767,
    "antr.v_reso_denom": 1080000000,
    "getriebe[2].multi_gain_z": 1,  # a position-loop scaling far off: it must not be used
    "getriebe[2].multi_gain_n": 100000,
}


@pytest.mark.parametrize("sensorless", [1, 0])
def test_speed_controlled_spindle_outputs_with_the_speed_scaling(sensorless: int) -> None:
    """[000 §2.2.4.1]: OPEN_POSITION_LOOP_MODE outputs the command speed with v_reso: 3000 rpm
    is 32767 digits, 1500 rpm half of it; with an encoder the spindle really turns at S."""
    sim, m, _ = make(
        {S: {**SPEED_SCALING, **DRIVE_3000, "sim.sensorless": sensorless}},
        {"spindel[0].m3_synch": 0, "main_spindle_gear_change": 0},
    )
    s = m.axis(S)
    assert s.gear == 3
    m.submit(Mdi("M3 S3000"))
    rec = record(sim, 7.0)[:, s.slot]  # 500 rpm/s in this gear stage
    assert np.all(rec[:, L.R_OPEN_LOOP] == L.LOOP_SPEED_CONTROL)
    assert rec[-1, L.R_DA] == pytest.approx(32767.0)
    assert rec[-1, L.R_V_ACT] / RPM == pytest.approx(3000.0, rel=1e-3)
    assert rec[-1, L.R_SPEED_REACHED] == 1
    m.submit(Mdi("M3 S1500"))
    rec = record(sim, 4.0)[:, s.slot]
    assert rec[-1, L.R_DA] == pytest.approx(32767.0 / 2)
    assert rec[-1, L.R_V_ACT] / RPM == pytest.approx(1500.0, rel=1e-3)
    # no position control: cannot be positioned
    err = m.submit(SpindlePosition(S, 90.0, None, None))
    assert isinstance(err, Refused) and err.code == Code.SPINDLE_SENSORLESS_M19


# --- acceleration curves ---------------------------------------------------------------------
POLY = {"n_grenz": 12000, "a_konst": 16000, "b3": -1.92901234e-10, "b2": 2.08333333e-5}
HYPER = {"n_grenz": 12000, "a_konst": 16000, "b1": 2.285714e4, "b2": 4.166666e-1}


def _curve(typ: int, **p: float) -> float:
    return curve_accel(
        typ,
        p["n"],
        p.get("n_grenz", 0.0),
        p.get("a_konst", 0.0),
        p.get("b1", 0.0),
        p.get("b2", 0.0),
        p.get("b3", 0.0),
        p.get("a_min", 0.0),
        p.get("a_max", 0.0),
        p.get("n1", 0.0),
        p.get("n2", 0.0),
    )


@pytest.mark.parametrize(("n", "a"), [(6000, 16000), (24000, 8000), (36000, 4000), (48000, 2000)])
def test_polynomial_curve_reproduces_the_manuals_points(n: float, a: float) -> None:
    assert _curve(2, n=n, b1=-0.88888888, **POLY) == pytest.approx(a, rel=1e-4)


@pytest.mark.parametrize(("n", "a"), [(12000, 16000), (24000, 8000), (36000, 4000)])
def test_hyperbola_curve_reproduces_the_manuals_points(n: float, a: float) -> None:
    assert _curve(1, n=n, b3=2.857142e-2, **HYPER) == pytest.approx(a, rel=1e-4)


@pytest.mark.parametrize(
    ("n", "a"), [(5000, 16000), (10000, 16000), (15000, 16000 * 10 / 15), (40000, 2000)]
)
def test_asynchronous_curve(n: float, a: float) -> None:
    assert _curve(3, n=n, a_max=16000, n1=10000, n2=20000) == pytest.approx(a)


def _curve_spindle(params: dict[str, float]) -> dict[str, object]:
    base: dict[str, object] = {
        "kenngr.getriebe_stufe": 6,
        "getriebe[5].dynamik.vb_max": 48000000,
        "getriebe[5].vb_regelgrenze": 60000000,
        "getriebe[5].dynamik.a_max": 100000,
        "sim.drive_a_max": 0,
    }
    for k, v in params.items():
        base[f"getriebe[5].beschl_kennlinie.{k}"] = v
    return base


def _ramp_time(a_of_n: Callable[[float], float], v: float) -> float:
    """∫ dn / a(n) from 0 to v, independent of the kernel (fine trapezoid rule)."""
    n = np.linspace(0.0, v, 200001)
    a = np.array([a_of_n(x) for x in n])
    return float(np.sum(0.5 * (1 / a[1:] + 1 / a[:-1]) * np.diff(n)))


@pytest.mark.parametrize("typ", [1, 2, 3])
def test_curve_ramp_takes_the_integral_of_dn_over_a_and_never_exceeds_the_curve(typ: int) -> None:
    # the curve's parameters, as getriebe[5].beschl_kennlinie.* below: typ, n_grenz, a_konst,
    # b1, b2 (P-AXIS-00027), b3, a_min; for type 3 a_max (P-AXIS-00240), n1 (P-AXIS-00241)
    # and n2 (P-AXIS-00242)
    b1 = {1: 2.285714e4, 2: -0.88888888, 3: 0.0}[typ]
    b3 = {1: 2.857142e-2, 2: -1.92901234e-10, 3: 0.0}[typ]
    params: dict[str, float] = {
        "typ": typ,
        "n_grenz": 12000000,
        "a_konst": 16000,
        "b1": b1,
        "b2": 4.166666e-1 if typ == 1 else 2.08333333e-5,
        "b3": b3,
        "a_min": 3000,
        "a_max": 16000,
        "n1": 10000000,
        "n2": 20000000,
    }
    sim, m, _ = make({S: _curve_spindle(params)}, {"spindel[0].m3_synch": 0})
    s = m.axis(S)

    def a_of(n: float) -> float:  # the manual's formulas, written out here
        nl, ak = 12000.0, 16000.0
        if typ == 1:
            nu2 = (n / nl) ** 2
            a = ak if n <= nl else b1 / (1 + params["b2"] * nu2 * (1 + b3 * nu2))
        elif typ == 2:
            dn = n - nl
            a = ak if n <= nl else b3 * dn**3 + params["b2"] * dn**2 + b1 * dn + ak
        else:
            a = 16000.0 if n <= 10000 else 16000 * 10000 / n * (1 if n <= 20000 else 20000 / n)
        return max(a, 3000.0)

    m.submit(Mdi("M3 S7000"))
    rec = record(sim, 10.0)[:, s.slot]
    t_end = (first(rec[:, L.R_V_CMD] >= 42000 - 1e-6) + 1) * DT
    assert t_end == pytest.approx(_ramp_time(a_of, 42000), abs=2 * DT)
    v_prev = np.concatenate(([0.0], rec[:-1, L.R_V_CMD]))
    allowed = np.array([a_of(abs(v)) for v in v_prev])
    assert np.all(np.abs(rec[:, L.R_A_CMD]) <= allowed * (1 + 1e-9))
    m.submit(Mdi("M5"))  # the curve also brakes
    rec = record(sim, 10.0)[:, s.slot]
    t_stop = (first(rec[:, L.R_V_CMD] <= 1e-9) + 1) * DT
    assert t_stop == pytest.approx(_ramp_time(a_of, 42000), abs=2 * DT)


# --- gear change ------------------------------------------------------------------------------
MANUAL_TABLE = [
    GearRange(50, 560),
    GearRange(400, 800),
    GearRange(700, 3500),
    GearRange(3501, 4000),
    GearRange(3800, 5500),
    GearRange(5400, 7000),
]


def test_automatic_gear_selection_against_the_manuals_example() -> None:
    """[000 p.37] S650 M41, S750 -, S950 M42, S1050 -, S750 M41*, S500 -*, S350 -*, S8000 error.

    *The manual's own table contradicts two lines: after M42 (700-3500) S750 is held by the
    current stage, so the rule keeps M42 (the manual changes to M41); then S500 needs M40
    (the manual stays in M41), and S350 lies outside M41 (400-800) anyway (the manual keeps
    M41). We follow the rule: keep the current stage when it holds S, else search.
    """
    gear, got = 1, []
    for rpm in (650, 750, 950, 1050, 750, 500, 350):
        choice = select_gear(MANUAL_TABLE, gear, rpm, True, 0, None)
        assert choice.error is None
        got.append(choice.gear)
        gear = choice.gear or gear
    assert got == [2, 2, 3, 3, 3, 1, 1]
    assert select_gear(MANUAL_TABLE, gear, 8000, True, 0, None).error is Code.GEAR_NO_RANGE
    assert select_gear(MANUAL_TABLE, 3, 750, True, 0, 2).gear == 2  # M41 S750
    assert select_gear(MANUAL_TABLE, 3, 750, True, 0, 1).error is Code.GEAR_WRONG_STAGE
    # range_way top-down takes the highest holding range: 3900 -> M44 (not M43)
    assert select_gear(MANUAL_TABLE, 1, 3900, True, 1, None).gear == 5
    assert select_gear(MANUAL_TABLE, 1, 3900, True, 0, None).gear == 4


def test_manual_gear_selection_against_the_manuals_example() -> None:
    """[000 p.38] with autom_range 0. "M41 S350 OK" contradicts the table (M41 is 400-800):
    the rule refuses it as the wrong stage, as the next line does for M41 S200."""
    steps = [(2, 650, 2), (2, 750, 2), (3, 950, 3), (3, 1050, 3), (2, 750, 2), (2, 500, 2)]
    gear = 1
    for programmed, rpm, expected in steps:
        choice = select_gear(MANUAL_TABLE, gear, rpm, False, 0, programmed)
        assert choice.gear == expected
        gear = expected
    assert select_gear(MANUAL_TABLE, gear, 350, False, 0, 2).error is Code.GEAR_WRONG_STAGE
    assert select_gear(MANUAL_TABLE, gear, 200, False, 0, 2).error is Code.GEAR_WRONG_STAGE
    err = select_gear(MANUAL_TABLE, gear, 950, False, 0, None)
    assert err.error is Code.GEAR_NOT_PROGRAMMED and "M42" in err.detail


def test_gear_change_sequence_adopts_the_new_gear_record_and_resumes() -> None:
    sim, m, cfg = make(
        {S: {"getriebe[2].kv": 2000, "getriebe[1].getr_schalt_pos": 450000}},
        {"spindel[0].m3_synch": 0},
    )
    s = m.axis(S)
    m.submit(Mdi("M3 S650"))  # from M42 (start-up stage 3) to M41
    rec = record(sim, 4.0)[:, s.slot]
    assert s.gear == 2 and s.state is AxisState.ENDLESS
    out = next(e for e in m.events if e.code == Code.EV_M_OUTPUT and e.m == 41)
    ack = next(e for e in m.events if e.code == Code.EV_GEAR_CHANGED)
    delay = cfg.channel_eng("plc.m_ack_delay")
    assert ack.cycle - out.cycle == round(delay / DT)
    at_out = out.cycle - 21
    # at the change position of the old gear (stage 3: getr_schalt_pos 0), at standstill
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    assert abs((rec[at_out, L.R_P_ACT] + 180) % 360 - 180) <= window
    assert rec[at_out, L.R_V_CMD] == 0.0 and rec[at_out, L.R_STATE] == AxisState.GEAR_CHANGE
    assert np.abs(rec[:at_out, L.R_V_CMD]).max() <= cfg.axis(S).eng("getriebe.vb_eilgang", 3)
    # the new record: kv 10/s and multi_gain of the M41 stage; the plant gain matches it
    assert m.k.pr[s.slot, L.P_MG] == pytest.approx(101.134)
    assert rec[-1, L.R_GEAR] == 2 and rec[-1, L.R_V_CMD] / RPM == pytest.approx(650)
    assert rec[-1, L.R_LAG] == pytest.approx(650 * RPM / 10.0, rel=0.01)
    c0 = m.cycle
    m.submit(Mdi("S950"))  # back to M42 with kv 20/s, via the M41 change position 45°
    rec = record(sim, 6.0)[:, s.slot]
    assert s.gear == 3 and rec[-1, L.R_LAG] == pytest.approx(950 * RPM / 20.0, rel=0.01)
    out = next(e for e in m.events if e.code == Code.EV_M_OUTPUT and e.m == 42)
    assert abs((rec[out.cycle - c0 - 1, L.R_P_ACT] - 45.0 + 180) % 360 - 180) <= window


def test_gear_change_errors_and_plc_timeout() -> None:
    sim, m, _ = make(channel={"spindel[0].autom_range": 0, "plc.m_ack_timeout": 300000})
    s = m.axis(S)
    m.submit(Mdi("M3 S8000"))
    m.submit(Mdi("M40 M3 S750"))
    m.submit(Mdi("M3 S500"))  # manual: S outside the current stage without M4x
    record(sim, 0.1)
    got = codes(m)
    assert Code.GEAR_NO_RANGE not in got  # manual mode: no search, so no "no range"
    assert got.count(Code.GEAR_NOT_PROGRAMMED) == 2 and Code.GEAR_WRONG_STAGE in got
    assert s.state is AxisState.STANDSTILL and s.gear == 3
    m.submit(PlcMode("fault"))
    m.submit(Mdi("M40 M3 S300"))
    record(sim, 3.0)
    assert Code.PLC_ACK_TIMEOUT in codes(m)
    assert s.gear == 3 and m.axis(S).state is AxisState.ERROR
    m.submit(Reset())
    assert s.state is AxisState.STANDSTILL


# --- tool dynamics, feedforward, reset, program end -------------------------------------------
def test_tool_dynamics_take_effect_at_the_next_start_and_default_data_resets() -> None:
    sim, m, cfg = make(channel={"spindel[0].m3_synch": 0, "spindel[0].m5_synch": 0})
    s = m.axis(S)
    m.submit(Mdi("M3 S3000"))
    record(sim, 0.2)
    m.submit(Mdi("D1"))  # 1500 rpm, 1000 °/s² for S1: not while it turns
    rec = record(sim, 7.0)[:, s.slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(3000)
    m.submit(Mdi("M5"))
    record(sim, 7.0)
    m.submit(Mdi("M3 S3000"))
    rec = record(sim, 10.0)[:, s.slot]
    assert rec[:, L.R_V_CMD].max() / RPM == pytest.approx(1500)
    a_tool = cfg.tool_eng("wz[1].a_max")
    assert np.abs(rec[:, L.R_A_CMD]).max() == pytest.approx(a_tool)
    m.submit(Mdi("M3 S700"))
    rec = record(sim, 6.0)[:, s.slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(700)
    m.submit(Mdi("M5"))
    m.submit(Mdi("S[DEFAULT_DYNAMIC_DATA]"))
    record(sim, 6.0)
    m.submit(Mdi("M3 S3000"))
    rec = record(sim, 8.0)[:, s.slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(3000)


def test_tool_minimum_speed_raises_a_lower_s() -> None:
    sim, m, _ = make(channel={"spindel[0].m3_synch": 0})
    m.cfg.tools["wz[3].log_ax_nr_spdl"] = 3
    m.cfg.tools["wz[3].vb_min"] = 6000000  # 1000 rpm
    m.cfg.tools["wz[3].vb_max"] = 18000000
    m.cfg.tools["wz[3].a_max"] = 3000
    m.submit(Mdi("D3"))
    m.submit(Mdi("M3 S800"))
    rec = record(sim, 3.0)[:, m.axis(S).slot]
    assert rec[-1, L.R_V_CMD] / RPM == pytest.approx(1000)


@pytest.mark.parametrize(("block", "weight"), [("", 0.0), ("S[G135]", 1.0), ("S[G136=50]", 0.5)])
def test_feedforward_g135_g136_g137_scale_the_steady_lag(block: str, weight: float) -> None:
    sim, m, cfg = make(channel={"spindel[0].m3_synch": 0})
    s = m.axis(S)
    if block == "S[G136=50]":
        m.submit(Mdi("S[G135]"))
    if block:
        m.submit(Mdi(block))
    m.submit(Mdi("M3 S1000"))
    rec = record(sim, 3.0)[:, s.slot]
    kv = cfg.axis(S).eng("getriebe.kv", 3)
    assert rec[-1, L.R_LAG] == pytest.approx((1 - weight) * 6000 / kv, abs=0.5)
    m.submit(Mdi("S[G137]"))
    rec = record(sim, 2.0)[:, s.slot]
    assert rec[-1, L.R_LAG] == pytest.approx(6000 / kv, rel=0.01)


@pytest.mark.parametrize("keep", [0, 1])
def test_reset_stops_the_spindle_unless_p_axis_00455(keep: int) -> None:
    sim, m, _ = make({S: {"kenngr.spdl_no_stop_at_reset": keep}}, {"spindel[0].m3_synch": 0})
    s = m.axis(S)
    m.submit(Mdi("M3 S1000"))
    record(sim, 3.0)
    m.submit(Reset())
    rec = record(sim, 3.0)[:, s.slot]
    assert (rec[-1, L.R_V_CMD] / RPM) == pytest.approx(1000.0 if keep else 0.0)


@pytest.mark.parametrize("flag", [0, 1])
def test_program_end_stops_only_with_the_hli_flag(flag: int) -> None:
    sim, m, _ = make(channel={"spindel[0].m3_synch": 0})
    s = m.axis(S)
    m.submit(HliWrite("spindle_stop_at_program_end", flag, S))
    m.submit(Mdi("M3 S1000"))
    record(sim, 3.0)
    m.submit(Mdi("M30"))
    rec = record(sim, 3.0)[:, s.slot]
    assert (rec[-1, L.R_V_CMD] / RPM) == pytest.approx(0.0 if flag else 1000.0)


def test_m19_to_the_angle_the_spindle_stands_at_completes_at_once() -> None:
    """A repeated M19 must not hang in POSITIONING: the in-position edge comes again."""
    sim, m, _ = make()
    assert isinstance(m.submit(SpindlePosition("S1", 90.0)), Accepted)
    sim.run(6000)
    ax = m.by_name["S1"]
    assert ax.state is AxisState.STANDSTILL
    c0 = m.cycle
    assert isinstance(m.submit(SpindlePosition("S1", 90.0)), Accepted)
    sim.run(2)
    assert ax.state is AxisState.STANDSTILL
    done = [e for e in m.events if e.code == Code.EV_IN_POSITION]
    assert len(done) == 2 and done[-1].cycle == c0 + 1  # in position in the very next cycle


def test_a_speed_above_the_machine_limit_is_refused_naming_the_limit() -> None:
    """S above the highest gear stage (M45 up to 7000 rpm, P-CHAN-00055) or, without gear
    change, above the gear record's vb_max (P-AXIS-00212: 3500 rpm in M42) is refused."""
    _, m, _ = make()
    err = m.submit(SpindleRun("S", 3, 2_000_000))
    assert isinstance(err, Refused) and err.code == Code.GEAR_NO_RANGE
    assert "7000 rpm" in err.detail and "P-CHAN-00055" in err.detail
    assert "S2000000 rpm" in err.detail
    _, m, _ = make(channel={"main_spindle_gear_change": 0})
    err = m.submit(SpindleRun("S", 3, 3600))
    assert isinstance(err, Refused) and err.code == Code.GEAR_NO_RANGE
    assert "3500 rpm" in err.detail and "P-AXIS-00212" in err.detail
    m.submit(Reset())
    assert isinstance(m.submit(SpindleRun("S", 3, 3500)), Accepted)
    err = m.submit(SpindlePosition("S", 90.0, None, 4000))
    assert isinstance(err, Refused) and "3500 rpm" in err.detail
