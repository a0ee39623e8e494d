"""Machine.snapshot() in simulated time: values in engineering units against the parameters'
physics and the geometry of a move; the event behind each active job error."""

from __future__ import annotations

import math
import pickle

import pytest

from nc_sim.commands import (
    EmergencyStop,
    HliWrite,
    Home,
    JogStep,
    PlcMode,
    Refused,
    Reset,
    SpindleRun,
)
from nc_sim.errors import Code
from nc_sim.snapshot import AxisSnapshot, LoopMode, MachineSnapshot
from nc_sim.units import AxisKind
from tests.nc_sim.sim_helpers import make, mdi, record


def _axis(snap: MachineSnapshot, name: str) -> AxisSnapshot:
    return next(a for a in snap.axes if a.name == name)


def test_a_spindle_at_s1000_m3_reaches_its_speed_after_the_ramp_its_parameters_give() -> None:
    """Demo S1 in M42 (getriebe[2]): a_beschl 3000 °/s² with 10 ms jerk ramps, so the command
    rises at 500 rpm/s, v(t) = 3000·(t − 0.005 s) °/s once the jerk ramp is done. Speed reached
    is ±10 % (vb_prozent 100) of 1000 rpm; kv 10/s gives a lag of v/kv = 6000/10 = 600°."""
    sim, m, _ = make()
    assert m.axis("S1").gear == 3
    m.submit(SpindleRun("S1", 3, 1000.0))
    record(sim, 1.7)
    s1 = _axis(m.snapshot(), "S1")
    assert s1.kind is AxisKind.SPINDLE and (s1.pos_unit, s1.vel_unit) == ("deg", "rpm")
    assert s1.vel_cmd == pytest.approx(3000.0 * (1.7 - 0.005) / 6.0, abs=1.0)  # 847.5 rpm
    assert s1.spindle is not None and not s1.spindle.speed_reached  # below 900 rpm
    assert s1.spindle.speed_monitoring_invalid  # the speed is still changing
    record(sim, 1.3)
    snap = m.snapshot()
    s1 = _axis(snap, "S1")
    assert s1.spindle is not None
    assert s1.state == "ENDLESS" and s1.loop is LoopMode.CLOSED
    assert s1.vel_cmd == pytest.approx(1000.0)
    assert s1.vel_act == pytest.approx(1000.0, rel=0.01)
    assert s1.lag == pytest.approx(600.0, rel=0.01)
    assert s1.spindle.speed_prog_rpm == pytest.approx(1000.0) and s1.spindle.gear == 3
    assert s1.spindle.speed_reached and not s1.spindle.stopped
    assert s1.spindle.speed_monitoring_active and not s1.spindle.speed_monitoring_invalid
    assert s1.override_pct == pytest.approx(100.0)
    assert (s1.target_pos, s1.distance_to_go) == (None, None)  # a speed motion has no target
    assert snap.cycle == sim.cycle and snap.t_s == pytest.approx(sim.cycle * 0.001)
    assert m.events[-1].code == Code.EV_SPEED_REACHED
    assert snap.event_cursor == m.events.cursor
    assert pickle.loads(pickle.dumps(snap)) == snap  # plain values: it crosses processes


def test_a_moving_axis_reports_its_target_and_the_distance_to_go() -> None:
    """G91 G01 X20 F600 from the start position: the target is 20 mm on, the distance to go is
    target − commanded position and shrinks at the feed, 600 mm/min = 10 mm/s."""
    sim, m, _ = make()
    x0 = _axis(m.snapshot(), "X").pos_cmd
    mdi(m, "G91 G01 X20 F600")
    record(sim, 1.0)
    a = _axis(m.snapshot(), "X")
    assert (a.pos_unit, a.vel_unit, a.state) == ("mm", "mm/min", "MOVING")
    assert a.target_pos is not None and a.target_pos == pytest.approx(x0 + 20.0)
    assert a.distance_to_go == pytest.approx(a.target_pos - a.pos_cmd)
    assert a.vel_cmd == pytest.approx(600.0)
    record(sim, 0.5)
    b = _axis(m.snapshot(), "X")
    assert a.distance_to_go is not None and b.distance_to_go is not None
    assert a.distance_to_go - b.distance_to_go == pytest.approx(5.0, abs=1e-6)  # 0.5 s × 10 mm/s
    assert not b.in_position
    record(sim, 2.0)
    c = _axis(m.snapshot(), "X")
    assert c.state == "STANDSTILL" and c.in_position
    assert c.target_pos == pytest.approx(x0 + 20.0) and c.distance_to_go == pytest.approx(0.0)
    assert c.pos_act == pytest.approx(x0 + 20.0, abs=1e-3)


def test_active_job_errors_carry_the_event_that_set_them_once_each() -> None:
    sim, m, _ = make()
    m.submit(HliWrite("DriveOn", 0, "X"))
    refused = m.submit(JogStep("X", 1.0))
    snap = m.snapshot()
    (err,) = snap.job_errors
    assert err == m.events[-1] and err.code == Code.NO_ENABLES and err.axis == "X"
    assert _axis(snap, "X").job_error == Code.NO_ENABLES and _axis(snap, "X").enabled is False
    assert "DriveOn" in _axis(snap, "X").missing_enables
    assert isinstance(refused, Refused) and refused.error == err  # the refusal's error
    m.submit(EmergencyStop())
    record(sim, 0.5)
    snap = m.snapshot()
    stop = next(e for e in m.events if e.code == Code.EMERGENCY_STOP)
    # one E-stop for every axis is one error; X's older error was replaced by it
    assert snap.job_errors == (stop,) and snap.emergency_stop
    assert {a.job_error for a in snap.axes} == {Code.EMERGENCY_STOP}
    assert all(a.loop is LoopMode.OPEN for a in snap.axes)  # enables taken (stop category 1)
    m.submit(Reset())
    assert m.snapshot().job_errors == ()


def test_the_plc_snapshot_shows_a_pending_m_function_in_manual_mode() -> None:
    _, m, _ = make()
    m.submit(PlcMode("manual"))
    mdi(m, "M8")
    snap = m.snapshot()
    assert snap.plc.mode.value == "manual" and snap.plc.drives_powered
    assert [(p.m, p.axis) for p in snap.plc.pending] == [(8, "")]
    assert snap.queued_blocks == 1  # the block waits for the acknowledgement


def test_a_pending_m_function_says_when_the_nc_gives_up_on_it() -> None:
    """P-CHAN plc.m_ack_timeout 2 s (µs) after the output: the snapshot's timeout cycle is the
    one the NC raises 90004 in, not a cycle before."""
    sim, m, cfg = make(channel={"plc.m_ack_timeout": 2_000_000})
    m.submit(PlcMode("manual"))
    mdi(m, "M8")
    (p,) = m.snapshot().plc.pending
    assert p.timeout_cycle is not None
    assert (p.timeout_cycle - p.out_cycle) * cfg.cycle_s == pytest.approx(2.0)
    sim.run(p.timeout_cycle - m.cycle - 1)
    assert Code.PLC_ACK_TIMEOUT not in [e.code for e in m.events]
    sim.run(2)
    timeout = next(e for e in m.events if e.code == Code.PLC_ACK_TIMEOUT)
    assert timeout.cycle == p.timeout_cycle and m.snapshot().plc.pending == ()


def test_homing_reports_its_phases_distance_and_speed() -> None:
    """Demo X homes towards + from 50 mm: to the cam (at 280 mm) at vb_refmax 5 m/min, off it
    at vb_reflow 1 m/min, then to ref_pos 280 mm, the cam's edge [002 §2.7]: it ends 230 mm
    from where it began; the last phase knows what is left to ref_pos."""
    sim, m, cfg = make()
    x_cfg = cfg.axis("X")
    start = _axis(m.snapshot(), "X").pos_act
    assert start == pytest.approx(50.0) and _axis(m.snapshot(), "X").homing is None
    m.submit(Home("X"))
    seen: dict[str, float] = {}
    moved_and_to_go = 0.0
    while True:
        record(sim, 0.05)
        x = _axis(m.snapshot(), "X")
        if x.homing is None:
            break
        h = x.homing
        seen.setdefault(h.phase, h.speed)
        if h.phase == "search for the cam":
            assert h.to_go is None and h.moved == pytest.approx(x.pos_act - start, abs=1e-9)
        if h.phase == "to the reference position":
            assert h.to_go == pytest.approx(x_cfg.eng("kenngr.ref_pos") - x.pos_act, abs=1e-9)
            moved_and_to_go = h.moved + (h.to_go or 0.0)
    assert list(seen) == ["search for the cam", "leaving the cam", "to the reference position"]
    assert seen["search for the cam"] == pytest.approx(5000.0, rel=1e-4)
    assert seen["leaving the cam"] == pytest.approx(1000.0, rel=1e-4)
    assert seen["to the reference position"] == pytest.approx(1000.0, rel=1e-4)
    assert m.axis("X").homed
    # where it will end (the cam's edge) is 230 mm from where it began
    assert moved_and_to_go == pytest.approx(280.0 - 50.0, abs=1e-3)


def test_the_shown_state_follows_the_axis_not_only_its_set_point() -> None:
    """G01 X50 → X100 at 1 m/min on the demo X (kv 20/s, no feedforward): the lag at
    constant speed is v/kv = 16.67/20 = 0.833 mm. While X moves, Z (not in the block) stands
    still. When the set-point arrives the NC's motion is done, but X still closes its lag:
    SETTLING, until its lag is inside the exact-stop window (kenngr.exact_stop_window 100:
    10 µm), ln(lag/0.010)/kv later (a first-order decay)."""
    sim, m, cfg = make()
    window = cfg.axis("X").eng("kenngr.exact_stop_window")
    assert window == pytest.approx(0.010)
    mdi(m, "G01 X100 F1000")
    record(sim, 1.0)
    snap = m.snapshot()
    assert _axis(snap, "X").state == "MOVING"
    assert _axis(snap, "Z").state == "STANDSTILL"  # the path's, but not moved by this block
    assert _axis(snap, "X").lag == pytest.approx(1000.0 / 60.0 / 20.0, rel=0.02)
    while not any(e.code == Code.EV_MOTION_DONE and e.axis == "X" for e in m.events):
        record(sim, 0.001)
    x = _axis(m.snapshot(), "X")
    assert x.state == "SETTLING" and abs(x.lag) > window
    settle_s = math.log(abs(x.lag) / window) / 20.0
    record(sim, 0.8 * settle_s)
    assert _axis(m.snapshot(), "X").state == "SETTLING"
    record(sim, 0.4 * settle_s + 0.05)
    x = _axis(m.snapshot(), "X")
    assert x.state == "STANDSTILL" and abs(x.lag) <= window
