"""Position loop, monitors and enables of the demo machine, in simulated time."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc_sim.axis.state import Axis
from nc_sim.commands import (
    Accepted,
    EmergencyStop,
    HliWrite,
    JogStart,
    JogStep,
    JogStop,
    Mdi,
    Move,
    Outcome,
    PlcAck,
    PlcMode,
    Refused,
    Reset,
)
from nc_sim.config import MachineConfig
from nc_sim.errors import Code
from nc_sim.machine.machine import Machine
from nc_sim.sim import Simulation
from tests.nc_sim.sim_helpers import L, make, mdi, record


def cruise_lag(
    kv_raw: int, feed: float, ff: int = 0, mg: tuple[int, int] = (10000, 1)
) -> tuple[float, float]:
    """Lag (mm) and velocity (mm/s) of X at constant speed in a long G01 move."""
    sim, m, _ = make(
        {
            "X": {
                "getriebe[0].kv": kv_raw,
                "lr_param.ff_weight": ff,
                "getriebe[0].multi_gain_z": mg[0],
                "getriebe[0].multi_gain_n": mg[1],
                "getriebe[0].lag_max": 10_000_000,
            }
        }
    )
    x = m.axis("X")
    seconds = 2.0 + 8.0 / (kv_raw * 0.01)  # ramp, then settle for 8 time constants
    mdi(m, f"G01 X{50 + feed / 60 * (seconds + 1):.3f} F{feed}")  # limits off: unhomed
    rec = record(sim, seconds)
    assert x.state.name == "MOVING"
    return float(rec[-1, x.slot, L.R_LAG]), float(rec[-1, x.slot, L.R_V_CMD])


@pytest.mark.parametrize("kv_raw", [300, 1000, 4000])
@pytest.mark.parametrize("feed", [200.0, 2000.0, 6000.0])
def test_steady_lag_is_v_over_kv(kv_raw: int, feed: float) -> None:
    lag, v = cruise_lag(kv_raw, feed)
    assert v == pytest.approx(feed / 60)
    assert lag == pytest.approx(v / (kv_raw * 0.01), rel=0.01)  # [004 §3.6]


def test_lag_is_command_minus_actual_of_the_same_sample() -> None:
    """One lag everywhere: every recorded sample has lag = pos_cmd - pos_act, and at constant
    speed that difference is v/(kv·0.01) [004 §3.6], so k from the columns gives kv."""
    sim, m, _ = make({"X": {"getriebe[0].kv": 2000}})  # 20/s
    x = m.axis("X")
    assert isinstance(m.submit(Mdi("G01 X200 F1000")), Accepted)
    rec = record(sim, 3.0)[:, x.slot]
    assert np.array_equal(rec[:, L.R_LAG], rec[:, L.R_P_CMD] - rec[:, L.R_P_ACT])
    v = 1000.0 / 60.0
    assert rec[-1, L.R_V_CMD] == pytest.approx(v)
    diff = rec[-500:, L.R_P_CMD] - rec[-500:, L.R_P_ACT]
    assert diff.mean() == pytest.approx(v / 20.0, rel=1e-4)  # 0.8333 mm, not v/kv - v·dt
    k = rec[-500:, L.R_V_CMD] / diff
    assert k.mean() == pytest.approx(20.0, rel=1e-4)


@pytest.mark.parametrize("target", [40.0, 40.0033, 40.0051])
def test_settled_loop_rests_within_half_an_increment_without_hunting(target: float) -> None:
    """A coarse encoder (0.01 mm per increment) and targets on and off its grid: the P loop
    comes to rest with |lag| at most half an increment and the count stops changing."""
    sim, m, _ = make({"X": {"getriebe[0].wegaufz": 1, "getriebe[0].wegaufn": 100}})
    x = m.axis("X")
    assert isinstance(m.submit(Move("X", target, rapid=False, feed_mm_min=1000)), Accepted)
    rec = record(sim, 6.0)[:, x.slot]
    rest = rec[-1000:]
    assert np.ptp(rest[:, L.R_P_ACT]) == 0.0
    assert np.abs(rest[:, L.R_V_ACT]).max() < 1e-6
    assert np.all(np.abs(rest[:, L.R_LAG]) <= 0.005 + 1e-12)


def test_full_feedforward_removes_the_steady_lag() -> None:
    lag, v = cruise_lag(1000, 3000.0, ff=1000)
    assert abs(lag) < 0.01 * v / 10.0


def test_wrong_multi_gain_changes_the_gain_by_its_factor() -> None:
    # the manual's experiment: f = 2.286 [004 §3.6.2]; drive scaling is 10000 digits per m/min
    lag, v = cruise_lag(400, 200.0, mg=(22860, 1))
    k = v / lag
    assert k == pytest.approx(4.0 * 2.286, rel=0.01)
    # the manual's correction f = (kv/100) / k brings multi_gain back to 10000 digits per m/min
    assert 22860 * (400 / 100) / k == pytest.approx(10000, rel=0.01)


def test_sign_inversion_runs_away_into_lag_monitoring() -> None:
    sim, m, _ = make({"X": {"lr_hw[0].vz_stellgr": 1}})
    x = m.axis("X")
    mdi(m, "G01 X60 F1000")
    rec = record(sim, 2.0)
    errors = [e for e in m.events if e.code == Code.LAG_MONITORING]
    assert len(errors) == 1 and errors[0].axis == "X"
    # the position ran away (positive feedback) before the monitor tripped
    assert np.max(np.abs(rec[:, x.slot, L.R_LAG])) > 5.0
    assert x.state.name == "ERROR"


def test_both_signs_inverted_on_an_inverted_machine_work() -> None:
    sim, m, _ = make({"X": {"lr_hw[0].vz_stellgr": 1, "sim.motor_inverted": 1}})
    mdi(m, "G01 X60 F1000")
    record(sim, 2.0)
    assert not [e for e in m.events if e.error]
    assert m.k.st[m.axis("X").slot, L.S_P_ACT] == pytest.approx(60.0, abs=1e-3)


def test_no_motion_without_enables() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    m.submit(HliWrite("DriveOn", 0, "X"))
    p0 = m.k.st[x.slot, L.S_P_ACT]
    m.submit(Mdi("G00 X100"))
    record(sim, 0.5)
    err = [e for e in m.events if e.error]
    assert len(err) == 1 and err[0].code == Code.NO_ENABLES
    assert "DriveOn" in err[0].message
    assert m.k.st[x.slot, L.S_P_ACT] == p0


def test_power_on_sequence_follows_the_drive_status() -> None:
    """[004 §4]: a SERCOS drive boots (ready_for_power_on), the PLC sets DriveOn, the power
    stage comes up (ready_for_control_loop_on), then TorquePermission and ReleaseFeedhold;
    a terminal drive reports no status and is switched on when the PLC starts."""
    times = {"sim.drive_boot_time": 20000, "sim.drive_power_up_time": 30000}  # 20 ms, 30 ms
    sim, m, _ = make({"X": times, "Z": times}, settle=0)
    x, spindle = m.axis("X"), m.axis("S1")
    assert x.drive.missing() == ["ready_for_power_on", "ready_for_control_loop_on"]
    assert spindle.drive.reported() == {}  # terminal drive [004 §4.2]
    assert isinstance(m.submit(Move("X", 60.0)), Refused)  # nothing moves before the drives are on
    assert m.events[-1].code == Code.NO_ENABLES
    sim.run(19)
    assert not x.units["DriveOn"] and spindle.drive_follows()  # the PLC ran at its start
    sim.run(1)  # 20 ms: booted, the PLC switches the power stage on
    assert x.units["DriveOn"] and x.drive.reported()["ready_for_power_on"]
    assert not x.units["TorquePermission"] and not m.powered
    sim.run(29)
    assert not x.drive.reported()["ready_for_control_loop_on"]
    sim.run(1)  # 30 ms after DriveOn
    assert x.drive.missing() == [] and x.enables_ok() and m.powered
    assert [e.cycle for e in m.events if e.code == Code.EV_POWERED] == [50]
    assert isinstance(m.submit(Move("X", 60.0)), Accepted)


def test_motion_refused_with_90007_while_the_drive_is_not_ready() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    m.submit(HliWrite("DriveOn", 0, "X"))
    record(sim, 0.1)
    m.submit(HliWrite("DriveOn", 1, "X"))  # the power stage needs its power-up time again
    assert x.enables_ok()
    err = m.submit(Move("X", 60.0))
    assert isinstance(err, Refused) and err.code == Code.DRIVE_NOT_READY
    assert "ready_for_control_loop_on" in err.detail
    record(sim, x.cfg.eng("sim.drive_power_up_time"))
    assert isinstance(m.submit(Move("X", 60.0)), Accepted)


def test_enables_lost_during_motion_stop_the_axis_with_an_error() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    m.submit(Mdi("G01 X200 F3000"))
    record(sim, 0.5)
    m.submit(HliWrite("TorquePermission", 0, "X"))
    record(sim, 0.5)
    assert [e.code for e in m.events if e.error] == [Code.ENABLES_LOST]
    assert abs(m.k.st[x.slot, L.S_V_ACT]) < 1e-6


def test_jog_stops_within_the_manual_mode_deceleration_distance() -> None:
    # G200: d_max 2000 mm/s², ramp 20 ms: from v the stop takes v/d + tr, distance v/2 (v/d + tr)
    sim, m, cfg = make()
    x = m.axis("X")
    feed = 6000.0
    assert isinstance(m.submit(JogStart("X", +1, feed)), Accepted)
    record(sim, 1.0)
    v = m.k.st[x.slot, L.S_V_CMD]
    assert v == pytest.approx(feed / 60)
    p_release = m.k.st[x.slot, L.S_P_CMD]
    m.submit(JogStop("X"))
    rec = record(sim, 0.5)
    d = cfg.axis("X").eng("handbetrieb.hb.d_max")
    tr = cfg.axis("X").eng("handbetrieb.hb.tr")
    travelled = m.k.st[x.slot, L.S_P_CMD] - p_release
    assert travelled == pytest.approx(v / 2 * (v / d + tr), rel=1e-6)
    assert x.state.name == "STANDSTILL"
    assert np.min(rec[:, x.slot, L.R_A_CMD]) == pytest.approx(-d)


@pytest.mark.parametrize("kind", ["start", "step"])
def test_a_jog_feed_above_the_manual_mode_maximum_is_refused_naming_it(kind: str) -> None:
    """[002 §2.6.1] G200: handbetrieb.hb.vb_max (P-AXIS-00213) bounds the jog velocity. The
    demo list holds 166666 µm/s = 9999.96 mm/min; a feed above it is refused naming that
    limit in mm/min, a feed at it jogs at it."""
    sim, m, cfg = make()
    x = m.axis("X")
    v_max = cfg.axis("X").eng("handbetrieb.hb.vb_max")
    assert v_max * 60 == pytest.approx(166666 * 60 / 1000)

    def jog(feed: float) -> Outcome:
        return (
            m.submit(JogStart("X", +1, feed))
            if kind == "start"
            else m.submit(JogStep("X", 250.0, feed))
        )

    err = jog(99999999.0)
    assert isinstance(err, Refused) and err.code == Code.JOG_FEED_TOO_HIGH
    assert "jog feed 99999999 mm/min is above the manual-mode maximum 9999.96 mm/min" in err.detail
    assert "P-AXIS-00213" in err.detail
    assert x.state.name == "STANDSTILL"
    assert isinstance(jog(v_max * 60), Accepted)  # the limit itself is allowed
    record(sim, 0.5)
    assert m.k.st[x.slot, L.S_V_CMD] == pytest.approx(v_max)


def test_override_scales_feed_and_is_capped_by_the_channel_limit() -> None:
    sim, m, _cfg = make()
    x = m.axis("X")
    m.submit(HliWrite("override", 500))
    m.submit(Mdi("G01 X250 F1200"))
    record(sim, 1.0)
    assert m.k.st[x.slot, L.S_V_CMD] == pytest.approx(10.0)  # 50 % of 20 mm/s
    m.submit(HliWrite("override", 2000))  # capped by max_vb_override 1200 [P-CHAN-00056]
    record(sim, 1.0)
    assert m.k.st[x.slot, L.S_V_CMD] == pytest.approx(24.0)


def test_homing_sets_the_reference_at_the_cam_edge() -> None:
    sim, m, cfg = make()
    x = m.axis("X")
    mdi(m, "G74 X1")
    record(sim, 8.0)
    ax = cfg.axis("X")
    assert x.homed and x.state.name == "STANDSTILL"
    assert m.k.st[x.slot, L.S_P_ACT] == pytest.approx(ax.eng("kenngr.ref_pos"), abs=1e-3)
    # NC position ref_pos now means the physical cam edge
    assert m.k.st[x.slot, L.S_X_MOTOR] == pytest.approx(ax.eng("sim.ref_cam_pos"), abs=1e-3)
    # software limits are active once homed
    m.submit(Mdi("G00 X400"))
    assert [e.code for e in m.events if e.error] == [Code.SOFTWARE_LIMIT]
    lo, hi = ax.eng("kenngr.swe_neg"), ax.eng("kenngr.swe_pos")  # positions carry their unit
    assert m.events[-1].message.endswith(f"X target 400.0000 mm outside {lo:.4f} … {hi:.4f} mm")


def cruising_x(block: str) -> tuple[Simulation, Machine, MachineConfig, Axis, float, float]:
    """X one second into `block`: the machine, and X's commanded speed and position there."""
    sim, m, cfg = make()
    x = m.axis("X")
    m.submit(Mdi(block))
    record(sim, 1.0)
    return sim, m, cfg, x, m.k.st[x.slot, L.S_V_CMD], m.k.st[x.slot, L.S_P_CMD]


def test_emergency_stop_brakes_step_shaped_at_a_emergency() -> None:
    sim, m, cfg, x, v, p = cruising_x("G01 X250 F6000")
    m.submit(EmergencyStop())
    record(sim, 0.2)  # braked (20 ms), the loop still settling with the enables on
    a = cfg.axis("X").eng("getriebe.dynamik.a_emergency")
    assert m.k.st[x.slot, L.S_P_CMD] - p == pytest.approx(v * v / (2 * a), rel=1e-6)
    m.submit(Mdi("G00 X10"))
    assert m.events[-1].code == Code.CHANNEL_ERROR_STATE
    # refused "reset first", the motion leaves the emergency stop as X's error: the cause
    assert x.error_event is not None and x.error_event.code == Code.EMERGENCY_STOP
    m.submit(Reset())
    record(sim, 0.02)  # the PLC switches the drives on again: their power-up (10 ms)
    mdi(m, "G00 X10")


def test_plc_acknowledges_after_its_delay_or_times_out_in_fault_mode() -> None:
    sim, m, _ = make(channel={"plc.m_ack_timeout": 500000})
    m.submit(Mdi("M8"))
    record(sim, 0.1)
    out, ack = [e for e in m.events if e.code in (Code.EV_M_OUTPUT, Code.EV_M_ACK)]
    assert round((ack.t_s - out.t_s) * 1000) == 20  # plc.m_ack_delay 20 ms
    m.submit(PlcMode("manual"))
    m.submit(Mdi("M9"))
    record(sim, 0.2)
    assert m.plc.pending and m.submit(PlcAck(9)) == Accepted(0, m.cycle, acknowledged=1)
    m.submit(PlcMode("fault"))
    m.submit(Mdi("M10"))
    record(sim, 0.6)
    timeouts = [e for e in m.events if e.code == Code.PLC_ACK_TIMEOUT]
    assert len(timeouts) == 1


def test_spindle_m3_reaches_speed_with_lag_v_over_kv() -> None:
    sim, m, cfg = make()
    s = m.axis("S")
    mdi(m, "M3 S1000")
    rec = record(sim, 3.5)
    a = cfg.axis("S1").eng("getriebe.slope_profil.a_beschl")
    tr = cfg.axis("S1").eng("getriebe.slope_profil.tr_beschl_zu")
    t_cmd = np.argmax(rec[:, s.slot, L.R_V_CMD] >= 6000.0 - 1e-9) * 0.001
    ack_at = next(e.t_s for e in m.events if e.code == Code.EV_M_OUTPUT) - 0.02
    assert t_cmd - ack_at == pytest.approx(6000.0 / a + tr, abs=0.002)
    assert rec[-1, s.slot, L.R_LAG] == pytest.approx(6000.0 / 10.0, rel=0.01)  # 600°
    assert rec[-1, s.slot, L.R_SPEED_REACHED] == 1
    m.submit(Mdi("M5"))
    rec = record(sim, 3.0)
    assert rec[-1, s.slot, L.R_STOPPED] == 1


def test_same_scenario_same_trace() -> None:
    traces = []
    for _ in range(2):
        sim, m, _ = make()
        m.submit(Mdi("G01 X120 F3000"))
        m.submit(Mdi("M3 S700"))
        traces.append(record(sim, 1.0))
    assert np.array_equal(traces[0], traces[1])


def test_feedhold_brakes_with_the_feedhold_set_and_resumes_to_the_target() -> None:
    # use_drive_curr_limit = 1: a_feedh 4000 mm/s², tr_feedh 10 ms [002 P-CHAN-00097, 00053/81]
    sim, m, cfg, x, v, p = cruising_x("G01 X200 F6000")
    m.submit(HliWrite("feedhold", 1))
    record(sim, 0.5)
    a = cfg.axis("X").eng("getriebe.slope_profil.a_feedh")
    tr = cfg.axis("X").eng("getriebe.slope_profil.tr_feedh")
    assert m.k.st[x.slot, L.S_V_CMD] == 0.0
    assert m.k.st[x.slot, L.S_P_CMD] - p == pytest.approx(v / 2 * (v / a + tr), rel=1e-6)
    m.submit(HliWrite("feedhold", 0))
    record(sim, 3.0)
    assert m.k.st[x.slot, L.S_P_CMD] == 200.0 and x.state.name == "STANDSTILL"


def test_override_zero_holds_the_move_and_it_resumes() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    m.submit(Mdi("G01 X100 F3000"))
    record(sim, 0.5)
    m.submit(HliWrite("override", 0))
    record(sim, 1.0)
    assert m.k.st[x.slot, L.S_V_CMD] == 0.0 and x.state.name == "MOVING"
    m.submit(HliWrite("override", 1000))
    record(sim, 3.0)
    assert m.k.st[x.slot, L.S_P_CMD] == 100.0 and x.state.name == "STANDSTILL"


def test_emergency_stop_takes_the_enables_once_braked_and_reset_gives_them_back() -> None:
    """Stop category 1: brake under control, then the PLC removes DriveOn/TorquePermission."""
    sim, m, cfg, x, v, _ = cruising_x("G01 X250 F6000")
    z = m.axis("Z")  # at rest: its enables go at once
    m.submit(EmergencyStop())
    assert z.missing_enables() and not z.enables_ok()
    assert not m.powered  # Z's drive is off: the machine's drives are no longer all powered
    assert x.enables_ok()  # X still brakes under position control
    a = cfg.axis("X").eng("getriebe.dynamik.a_emergency")
    record(sim, 0.9 * v / a)
    assert x.enables_ok() and m.k.st[x.slot, L.S_V_CMD] > 0
    record(sim, 0.2 * v / a)
    assert m.k.st[x.slot, L.S_V_CMD] == 0.0 and x.enables_ok()  # braked, lag still settling
    kv = cfg.axis("X").eng("getriebe.kv", 1)
    window = cfg.axis("X").eng("kenngr.exact_stop_window")
    lag = abs(m.k.st[x.slot, L.S_LAG])
    record(sim, math.log(lag / window) / kv + 0.05)  # the lag decays as e^(-kv t)
    assert abs(m.k.st[x.slot, L.S_LAG]) <= window
    assert set(x.missing_enables()) >= {"DriveOn", "TorquePermission"}
    assert not [e for e in m.events if e.code == Code.ENABLES_LOST]  # no error of its own
    m.submit(Reset())  # the PLC's start-up again: DriveOn, the drive's power-up, the other enables
    assert not x.enables_ok()
    record(sim, cfg.axis("X").eng("sim.drive_power_up_time") + 0.005)
    assert x.enables_ok() and z.enables_ok() and m.powered
    assert m.events[-1].code == Code.EV_POWERED
    mdi(m, "G00 X10")


def test_an_emergency_stop_during_power_up_holds_the_start_up_until_reset() -> None:
    sim, m, _ = make(settle=0)
    m.submit(EmergencyStop())  # before the PLC has switched anything on
    record(sim, 0.2)
    assert not any(ax.enables_ok() for ax in m.axes)
    assert not m.powered
    m.submit(Reset())
    record(sim, 0.2)
    assert m.powered and all(ax.enables_ok() for ax in m.axes)
