"""Sequences that must progress or end in a job error: jog, homing order, PLC waits, gear
rule, spindle jog and move, automatic homing on M5, watchdogs and bounds (issue 13)."""

from __future__ import annotations

import numpy as np
import pytest

from nc_sim.commands import (
    Accepted,
    GearChange,
    HliWrite,
    Home,
    Invalid,
    JogStart,
    JogStep,
    JogStop,
    Mdi,
    Move,
    PlcAck,
    PlcMode,
    Refused,
    Reset,
    SpindlePosition,
    SpindleRun,
)
from nc_sim.errors import Code
from nc_sim.machine.machine import Machine
from nc_sim.params import ParamListError
from nc_sim.sim import Simulation
from nc_sim.snapshot import AxisState
from tests.nc_sim.sim_helpers import L, make, record

S = "S1"
RPM = 6.0  # °/s per rpm


def codes(m: Machine) -> list[int]:
    return [e.code for e in m.events]


def home_x(sim: Simulation, m: Machine) -> None:
    assert isinstance(m.submit(Home("X")), Accepted)
    record(sim, 10.0)
    assert m.axis("X").homed and m.axis("X").state is AxisState.STANDSTILL


# --- item 8: a jog renewed at the software limit -----------------------------------------------
@pytest.mark.parametrize("release", ["jog_stop", "reset"])
def test_jog_renewed_at_the_software_limit_then_released_stands_still(release: str) -> None:
    sim, m, cfg = make()
    x = m.axis("X")
    home_x(sim, m)
    swe_pos = cfg.axis("X").eng("kenngr.swe_pos")
    assert isinstance(m.submit(JogStart("X", 1)), Accepted)
    record(sim, 20.0)
    assert m.k.st[x.slot, L.S_P_CMD] == swe_pos and x.state is AxisState.STANDSTILL
    # the HMI renews the held key's lease: a jog towards the limit the axis stands at
    assert isinstance(m.submit(JogStart("X", 1)), Accepted)
    record(sim, 0.05)
    if release == "jog_stop":
        m.submit(JogStop("X"))
    else:
        m.submit(Reset())
    record(sim, 0.05)
    assert x.state is AxisState.STANDSTILL
    assert isinstance(m.submit(JogStep("X", -1.0)), Accepted)  # increments are accepted again
    record(sim, 2.0)
    assert m.k.st[x.slot, L.S_P_CMD] == pytest.approx(swe_pos - 1.0)
    assert Code.AXIS_BUSY not in codes(m)


# --- item 9: timed out means gone --------------------------------------------------------------
def test_a_late_acknowledgement_after_the_timeout_acknowledges_nothing() -> None:
    sim, m, cfg = make(channel={"plc.m_ack_timeout": 300000})
    m.submit(PlcMode("manual"))
    assert isinstance(m.submit(Mdi("M8")), Accepted)
    record(sim, 0.1)
    assert [p.m for p in m.plc.pending] == [8]
    record(sim, cfg.channel_eng("plc.m_ack_timeout"))
    assert Code.PLC_ACK_TIMEOUT in codes(m)
    assert m.plc.pending == [] and m.queued_blocks == 0  # no longer pending anywhere
    assert m.submit(PlcAck(8)) == Accepted(0, m.cycle, acknowledged=0)
    assert m.submit(PlcAck(None)) == Accepted(0, m.cycle, acknowledged=0)
    assert Code.EV_M_ACK not in codes(m)


# --- item 3: G74 order digits and G74 S1 -------------------------------------------------------
def _first_motion(rec: np.ndarray, slot: int) -> int:
    moving = np.flatnonzero(np.abs(rec[:, slot, L.R_V_CMD]) > 0)
    assert moving.size
    return int(moving[0])


def test_g74_homes_in_the_order_of_its_digits() -> None:
    sim, m, _ = make()
    x, z = m.axis("X"), m.axis("Z")
    assert isinstance(m.submit(Mdi("G74 X1 Z2")), Accepted)
    c0 = m.cycle
    rec = record(sim, 30.0)
    x_homed = next(e.cycle for e in m.events if e.code == Code.EV_MOTION_DONE and e.axis == "X")
    # Z starts only after X has finished homing [000 §2.7]
    assert _first_motion(rec, z.slot) + c0 + 1 > x_homed
    assert _first_motion(rec, x.slot) == 0
    assert x.homed and z.homed and m.queued_blocks == 0


def test_g74_s1_homes_the_spindle_with_its_group_and_is_no_speed() -> None:
    sim, m, cfg = make()
    s, x = m.axis(S), m.axis("X")
    assert isinstance(m.submit(Mdi("G74 X2 S1")), Accepted)
    c0 = m.cycle
    rec = record(sim, 15.0)
    assert Code.GEAR_NO_RANGE not in codes(m) and Code.GEAR_WRONG_STAGE not in codes(m)
    assert s.homed and x.homed and m.queued_blocks == 0
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    ref = cfg.axis(S).eng("kenngr.ref_pos")
    assert abs((m.k.st[s.slot, L.S_P_ACT] - ref + 180) % 360 - 180) <= window
    # the spindle is not synchronised with the axes: X (order 2) need not wait for it
    s_homed = next(e.cycle for e in m.events if e.code == Code.EV_IN_POSITION and e.axis == S)
    assert _first_motion(rec, x.slot) + c0 + 1 < s_homed


# --- item 11: a negative S is refused everywhere -----------------------------------------------
def test_negative_speed_is_refused_by_mdi_and_by_the_command_api() -> None:
    sim, m, _ = make()
    s = m.axis(S)
    for block in ("M3 S-1000", "S[M4 REV-500]", "M19 S.POS=90 S-100"):
        bad = m.submit(Mdi(block))
        assert isinstance(bad, Invalid) and bad.code == Code.BLOCK_SYNTAX
        assert "negative" in bad.message
    for cmd in (SpindleRun("S", 3, -1000.0), SpindlePosition("S", 90.0, None, -100.0)):
        bad = m.submit(cmd)
        assert isinstance(bad, Invalid) and "negative" in bad.message
    record(sim, 0.5)
    assert s.state is AxisState.STANDSTILL and m.k.st[s.slot, L.S_V_CMD] == 0.0


# --- item 6: M40-M45 without gear change are free M functions ----------------------------------
def test_m40_to_m45_are_free_m_functions_when_gear_change_is_off() -> None:
    sim, m, _ = make(channel={"main_spindle_gear_change": 0, "spindel[0].m3_synch": 0})
    s = m.axis(S)
    gear = s.gear
    assert isinstance(m.submit(Mdi("M41")), Accepted)
    # S500 runs in the current stage, M43 goes to the PLC
    assert isinstance(m.submit(Mdi("M3 S500 M43")), Accepted)
    # the gear buttons send the same M function
    assert isinstance(m.submit(GearChange("S", 44)), Accepted)
    record(sim, 3.0)
    outputs = [e for e in m.events if e.code == Code.EV_M_OUTPUT]
    assert sorted(e.m or 0 for e in outputs) == [41, 43, 44]
    assert all(e.gear is None for e in outputs)  # free M functions: no gear stage
    assert codes(m).count(Code.EV_M_ACK) == 3 and m.queued_blocks == 0
    assert Code.GEAR_CHANGE_OFF not in codes(m)
    assert s.gear == gear and s.state is AxisState.ENDLESS
    assert m.k.st[s.slot, L.S_V_CMD] == pytest.approx(500 * RPM)


# --- item 10: gear buttons and MDI follow one rule ---------------------------------------------
def test_a_gear_stage_is_checked_against_the_running_speed_by_buttons_and_mdi() -> None:
    """M43 while S500 runs is M43 with S500: outside 3501-4000 rpm, refused as M41 S2000 is."""
    sim, m, _ = make(channel={"spindel[0].m3_synch": 0})
    s = m.axis(S)
    assert isinstance(m.submit(Mdi("M3 S500")), Accepted)
    record(sim, 4.0)
    assert s.gear == 1 and s.state is AxisState.ENDLESS
    err = m.submit(GearChange("S", 43))
    assert isinstance(err, Refused) and err.code == Code.GEAR_WRONG_STAGE
    for block in ("M43", "M41 S2000"):  # refused while starting, as the button is
        err = m.submit(Mdi(block))
        assert isinstance(err, Refused) and err.code == Code.GEAR_WRONG_STAGE
    record(sim, 4.0)
    assert codes(m).count(Code.GEAR_WRONG_STAGE) == 3
    assert s.gear == 1 and s.state is AxisState.ENDLESS  # no change to M43 and back
    # M41 (400-800 rpm) holds S500: changes, stays
    assert isinstance(m.submit(GearChange("S", 41)), Accepted)
    record(sim, 6.0)
    assert s.gear == 2 and s.state is AxisState.ENDLESS
    assert m.k.st[s.slot, L.S_V_CMD] == pytest.approx(500 * RPM)
    assert codes(m).count(Code.EV_GEAR_CHANGED) == 2  # M40 for S500, then M41


# --- item 4: a spindle jogs and moves like a rotary axis ---------------------------------------
def test_spindle_incremental_jog_turns_by_the_step_and_ends() -> None:
    sim, m, cfg = make()
    s = m.axis(S)
    p0 = m.k.st[s.slot, L.S_P_CMD]
    assert isinstance(m.submit(JogStep(S, 90.0)), Accepted)
    rec = record(sim, 3.0)[:, s.slot]
    assert s.state is AxisState.STANDSTILL and m.k.st[s.slot, L.S_P_CMD] == p0 + 90.0
    v_jog = cfg.axis(S).eng("handbetrieb.hb.vb_max")  # G200 dynamics, as a rotary axis
    assert 0 < rec[:, L.R_V_CMD].max() <= v_jog + 1e-9
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    assert abs(rec[-1, L.R_P_ACT] - (p0 + 90.0)) <= window


def test_spindle_continuous_jog_turns_at_jog_speed_until_released() -> None:
    sim, m, cfg = make()
    s = m.axis(S)
    assert isinstance(m.submit(JogStart(S, -1)), Accepted)
    rec = record(sim, 2.0)[:, s.slot]
    v_jog = cfg.axis(S).eng("handbetrieb.hb.vb_max")
    assert s.state is AxisState.JOG and rec[-1, L.R_V_CMD] == pytest.approx(-v_jog)
    m.submit(JogStop(S))
    record(sim, 2.0)
    assert m.axis(S).state is AxisState.STANDSTILL and m.k.st[s.slot, L.S_V_CMD] == 0.0


def test_spindle_move_goes_to_the_angle_the_shortest_way_and_ends() -> None:
    sim, m, _ = make()
    s = m.axis(S)
    p0 = m.k.st[s.slot, L.S_P_CMD]
    target = (p0 + 100.0) % 360.0
    assert isinstance(m.submit(Move(S, target)), Accepted)
    record(sim, 5.0)
    assert s.state is AxisState.STANDSTILL
    assert m.k.st[s.slot, L.S_P_CMD] == pytest.approx(p0 + 100.0)
    assert Code.EV_MOTION_DONE in codes(m)
    assert isinstance(m.submit(Mdi("M3 S500")), Accepted)  # still a spindle afterwards
    record(sim, 3.0)
    assert m.axis(S).state is AxisState.ENDLESS
    assert isinstance(m.submit(JogStep(S, 10.0)), Refused)  # not while it rotates: 90006
    assert codes(m)[-1] == Code.AXIS_BUSY


# --- item 7: M5 after the control limit homes on the way (analogue drives) ---------------------
def _over_the_control_limit(achs_mode: int) -> tuple[Simulation, Machine, float]:
    limit_rpm = 2000
    sim, m, _ = make(
        {S: {"getriebe[2].vb_regelgrenze": limit_rpm * 6000, "kenngr.achs_mode": achs_mode}},
        {"spindel[0].m3_synch": 0, "spindel[0].m5_synch": 0},
    )
    assert isinstance(m.submit(Mdi("M3 S3000")), Accepted)
    record(sim, 8.0)
    assert Code.EV_REFERENCE_LOST in codes(m) and not m.axis(S).homed
    return sim, m, limit_rpm * RPM


def test_m5_after_the_control_limit_homes_an_analogue_spindle_on_the_way() -> None:
    sim, m, v_limit = _over_the_control_limit(0)
    s = m.axis(S)
    c0 = m.cycle
    assert isinstance(m.submit(Mdi("M5")), Accepted)
    rec = record(sim, 8.0)[:, s.slot]
    homed = [e for e in m.events if e.code == Code.EV_HOMED and e.cycle > c0]
    assert len(homed) == 1 and s.homed
    # the zero mark is taken with the loop closed, below the control limit [000 §2.4.2, §2.7]
    i = homed[0].cycle - c0 - 1
    assert rec[i, L.R_OPEN_LOOP] == L.LOOP_CLOSED and abs(rec[i, L.R_V_CMD]) <= v_limit
    assert s.state is AxisState.STANDSTILL and rec[-1, L.R_V_CMD] == 0.0


def test_m5_after_the_control_limit_does_not_home_a_digital_spindle() -> None:
    sim, m, _ = _over_the_control_limit(0x101)  # ACHSMODE_KEINE_AUTO_RPF: G74 only
    s = m.axis(S)
    assert isinstance(m.submit(Mdi("M5")), Accepted)
    record(sim, 8.0)
    assert not s.homed and s.state is AxisState.STANDSTILL


# --- item 13: bounds and watchdogs -------------------------------------------------------------
def test_a_curve_without_acceleration_is_refused_with_the_list() -> None:
    """Polynomial with b1..b3 = 1e308 and the defaults a_konst = n_grenz = 0: a(0) = 0, the
    spindle could never start; every value is in its manual range, the curve is meaningless."""
    curve = {f"getriebe[2].beschl_kennlinie.{k}": 1e308 for k in ("b1", "b2", "b3")}
    with pytest.raises(ParamListError) as exc:
        make({S: {"getriebe[2].beschl_kennlinie.typ": 2, **curve}})
    (err,) = exc.value.errors
    assert err.name == "getriebe[2].beschl_kennlinie.typ" and "at 0 rpm" in err.detail


def test_a_hyperbola_that_dies_above_n_grenz_is_refused_naming_the_speed() -> None:
    """The manual's hyperbola [000 §2.8.4] with b2 = 1e308: no acceleration above n_grenz."""
    params = {
        "typ": 1,
        "n_grenz": 12000000,  # 2000 rpm
        "a_konst": 16000,
        "b1": 2.285714e4,
        "b2": 1e308,
        "b3": 2.857142e-2,
    }
    _, _, cfg = make()
    vb_max_rpm = cfg.axis(S).eng("getriebe.dynamik.vb_max", 3) / RPM
    with pytest.raises(ParamListError) as exc:
        make({S: {f"getriebe[2].beschl_kennlinie.{k}": v for k, v in params.items()}})
    rpm = float(exc.value.errors[0].detail.split(" at ")[1].split(" rpm")[0])
    assert 2000 < rpm <= 2000 + vb_max_rpm / 256  # the first speed checked above n_grenz
    params["b2"] = 4.166666e-1  # the manual's own value accelerates everywhere
    make({S: {f"getriebe[2].beschl_kennlinie.{k}": v for k, v in params.items()}})


def test_the_nc_refuses_a_dead_curve_even_past_the_list_check() -> None:
    """The kernel's copy of the curve is checked at every speed change too (90024), so a
    curve that got in some other way ends in a job error, never in rotation at 0 rpm."""
    sim, m, cfg = make()
    values = cfg.axis(S).values
    values["getriebe[2].beschl_kennlinie.typ"] = 2  # written around the validation
    m.refresh_params()
    assert isinstance(m.submit(Mdi("M3 S1000")), Accepted)
    record(sim, 1.0)
    err = next(e for e in m.events if e.code == Code.CURVE_NO_ACCELERATION)
    assert "at 0 rpm" in err.message
    assert m.axis(S).state is AxisState.ERROR and m.queued_blocks == 0


def test_unhomed_axis_refuses_a_target_beyond_the_position_range() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    err = m.submit(Move("X", 1e249))
    assert isinstance(err, Refused) and err.code == Code.SOFTWARE_LIMIT
    err = m.submit(Mdi("G00 X300000"))  # 300 m: beyond SGN32 in 0.1 µm (±214748.3647 mm)
    assert isinstance(err, Refused) and err.code == Code.SOFTWARE_LIMIT
    record(sim, 1.0)
    assert codes(m).count(Code.SOFTWARE_LIMIT) == 2 and m.queued_blocks == 0
    assert x.state is AxisState.STANDSTILL and m.k.st[x.slot, L.S_V_CMD] == 0.0
    # within the range (SGN32 in 0.1 µm: ±214748.3647 mm) an unhomed axis still moves
    assert isinstance(m.submit(Move("X", 60.0)), Accepted)


def test_p_axis_00277_refuses_programmed_motion_of_an_unhomed_axis_with_90013() -> None:
    sim, m, _ = make({"X": {"kenngr.prog_move_requires_homing": 1}})
    x = m.axis("X")
    err = m.submit(Move("X", 100.0))
    assert isinstance(err, Refused) and err.code == Code.NOT_HOMED
    err = m.submit(Mdi("G01 X100 F1000"))
    assert isinstance(err, Refused) and err.code == Code.NOT_HOMED
    record(sim, 0.1)
    assert codes(m).count(Code.NOT_HOMED) == 2 and m.queued_blocks == 0
    assert isinstance(m.submit(JogStep("X", 1.0)), Accepted)  # jogging stays possible
    record(sim, 2.0)
    assert isinstance(m.submit(Mdi("G74 X1")), Accepted)
    record(sim, 10.0)
    assert x.homed and isinstance(m.submit(Move("X", 100.0)), Accepted)


def test_homing_that_never_finds_its_cam_ends_in_the_watchdog_error() -> None:
    """The cam lies far beyond the travel: the search runs away, bounded by travel / vb_refmax."""
    sim, m, cfg = make({"X": {"sim.ref_cam_pos": 2000000000}})  # 200 m
    x = m.axis("X")
    assert isinstance(m.submit(Home("X")), Accepted)
    c0 = m.cycle
    record(sim, 30.0)
    err = next(e for e in m.events if e.code == Code.SEQUENCE_WATCHDOG)
    travel = cfg.axis("X").eng("kenngr.swe_pos") - cfg.axis("X").eng("kenngr.swe_neg")
    search_s = travel / cfg.axis("X").eng("getriebe.vb_refmax")
    after_s = (err.cycle - c0) * sim.kernel.cycle_s
    # not before the whole travel was searched; at most twice the search and its ramp (shorter
    # than the search here) plus a second
    assert search_s < after_s < 4 * search_s + 1.0
    assert x.state is AxisState.ERROR and not x.homed
    record(sim, 2.0)
    assert m.k.st[x.slot, L.S_V_CMD] == 0.0  # braked
    m.submit(Reset())
    assert m.axis("X").state is AxisState.STANDSTILL


def test_healthy_long_sequences_never_meet_their_bounds() -> None:
    sim, m, _ = make(channel={"spindel[0].m3_synch": 0})
    x, s = m.axis("X"), m.axis(S)
    # endless rotation lasts until the next command
    assert isinstance(m.submit(Mdi("M3 S1000")), Accepted)
    assert isinstance(m.submit(Mdi("G01 X200 F3000")), Accepted)
    record(sim, 1.0)
    m.submit(HliWrite("feedhold", 1))  # the operator holds the move for a minute
    record(sim, 60.0)
    m.submit(HliWrite("feedhold", 0))
    record(sim, 5.0)
    assert Code.SEQUENCE_WATCHDOG not in codes(m)
    assert m.k.st[x.slot, L.S_P_CMD] == 200.0 and s.state is AxisState.ENDLESS


def test_homing_held_by_feedhold_resumes_its_search_on_release() -> None:
    """A search has no target to re-plan to: it resumes at vb_refmax and homes."""
    sim, m, cfg = make()
    x = m.axis("X")
    assert isinstance(m.submit(Home("X")), Accepted)
    record(sim, 1.0)
    m.submit(HliWrite("feedhold", 1))
    record(sim, 1.0)
    assert m.k.st[x.slot, L.S_V_CMD] == 0.0 and x.state is AxisState.HOMING
    m.submit(HliWrite("feedhold", 0))
    record(sim, 1.0)
    assert m.k.st[x.slot, L.S_V_CMD] == pytest.approx(cfg.axis("X").eng("getriebe.vb_refmax"))
    record(sim, 10.0)
    assert x.homed and m.axis("X").state is AxisState.STANDSTILL
    assert m.k.st[x.slot, L.S_P_CMD] == pytest.approx(cfg.axis("X").eng("kenngr.ref_pos"))
    assert not any(e.error for e in m.events)
