"""The demo lathe's main spindle S1 as rotary axis C [003 §2-§4], in simulated time.

The changeover follows 003 Fig. 4-1: activate, internal (brake, speed control, the drive
parameter record P-AXIS-00052), external (ROTMOD/SPMOD out, the PLC's ROTMOD_Q/SPMOD_Q back),
de-activate, position control, the mode signal. The numbers: the demo PLC acknowledges 20 ms
after the request (plc.m_ack_delay), gives up after 5 s (plc.m_ack_timeout); C's exact-stop
window is the spindle's kenngr.exact_stop_window; as the C axis S1 runs in gear stage 1.
"""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from nc_sim.commands import (
    Accepted,
    CycleStart,
    EmergencyStop,
    HliWrite,
    JogStart,
    JogStop,
    Mdi,
    PlcMode,
    PlcSignal,
    ProgramLoad,
    ProgramStop,
    Refused,
    Reset,
    SpindlePosition,
    SpindleRun,
)
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.machine.machine import Machine
from nc_sim.snapshot import AxisState, ChannelState
from nc_sim.spindle.caxis import SpindleMode
from tests.nc_sim.sim_helpers import L, make, mdi, record

C = "C"
ACK_DELAY_CYCLES = 20  # channel.lis plc.m_ack_delay 20000 µs at 1 ms
TIMEOUT_S = 5.0  # plc.m_ack_timeout


def events(m: Machine, since: int = 0) -> list[Event]:
    return m.events.since(since).entries


def sequence(m: Machine, since: int = 0) -> list[tuple[int, str | None]]:
    """The changeover's events in order: (code, signal)."""
    keep = {33, 34, 35, 36, 37, 38, 39, 40, 41, int(Code.PLC_ACK_TIMEOUT)}
    return [(e.code, e.signal) for e in events(m, since) if e.code in keep]


TO_ROTARY = [
    (35, None),  # (1) activated
    (36, None),  # (2) internal: standstill, speed control, parameter record
    (34, "SPMOD"),  # (3) external: the other request reset ...
    (33, "ROTMOD"),  # ... the new one set
    (33, "ROTMOD_Q"),  # the PLC's acknowledgement ...
    (34, "SPMOD_Q"),  # ... and the old mode's withdrawn
    (37, None),  # (4) de-activated
    (38, None),  # (5)+(6) position control, rotary axis mode
]
TO_SPINDLE = [
    (35, None),
    (36, None),
    (34, "ROTMOD"),
    (33, "SPMOD"),
    (33, "SPMOD_Q"),
    (34, "ROTMOD_Q"),
    (37, None),
    (39, None),
]


def mode(m: Machine) -> SpindleMode:
    """The C spindle's mode now (a call, so each check reads it afresh)."""
    assert m.cax is not None
    return m.cax.mode


def state(m: Machine, name: str = "S1") -> AxisState:
    return m.axis(name).state


def c_pos(m: Machine) -> float:
    return float(m.k.st[m.axis(C).slot, L.S_P_ACT])


def test_power_on_adopts_the_mode_the_plc_reports() -> None:
    """003 §2.3: at power-on the NC takes the mode the PLC acknowledges (SPMOD_Q)."""
    _sim, m, _ = make()
    assert m.cax is not None and mode(m) is SpindleMode.SPINDLE
    assert m.cax.display_name == "S1" and m.channel.axes == ("X", "Z", "C")
    assert m.plc.signals == {"ROTMOD_Q": False, "SPMOD_Q": True}


def test_c_from_a_turning_spindle_in_the_manuals_order_then_to_its_exact_stop() -> None:
    """M3 S1000 (gear stage 3), then G00 C90: brake, parameter record 1, ROTMOD → ROTMOD_Q
    after the PLC's 20 ms, position control, then C positions to 90° and ends inside its
    exact-stop window. C does not move between the request and the acknowledgement."""
    sim, m, _ = make()
    mdi(m, "M3 S1000")
    record(sim, 2.0)
    s1 = m.axis("S1")
    assert state(m) is AxisState.ENDLESS and s1.gear == 3
    seen = m.events.cursor
    mdi(m, "G00 C90")
    rec = record(sim, 4.0)
    assert sequence(m, seen) == TO_ROTARY
    evs = {e.code: e for e in events(m, seen)}
    assert evs[36].gear == 1  # kenngr.cax_getriebe_stufe (P-AXIS-00052)
    out = next(e for e in events(m, seen) if e.code == 33 and e.signal == "ROTMOD")
    ack = next(e for e in events(m, seen) if e.code == 33 and e.signal == "ROTMOD_Q")
    assert ack.cycle - out.cycle == ACK_DELAY_CYCLES
    # the drive stands still from the request until the acknowledgement
    v = rec[:, s1.slot, L.R_V_CMD]
    first = m.cycle - rec.shape[0] + 1  # the cycle of the record's first row
    assert np.all(v[out.cycle - first : ack.cycle - first] == 0.0)
    assert m.cax is not None and mode(m) is SpindleMode.ROTARY
    assert m.cax.display_name == C and s1.gear == 1
    win = float(m.k.pr[s1.slot, L.P_INPOS_WIN])
    assert abs(c_pos(m) - 90.0) <= win
    assert state(m) is AxisState.STANDSTILL and m.channel.state is not ChannelState.ERROR


def test_the_position_is_rebased_into_one_turn_at_the_changeover() -> None:
    """After endless rotation the spindle stands thousands of degrees out; as the C axis its
    position is the same angle within 0..360° (003 §4.2 (5): the command value is updated)."""
    sim, m, _ = make()
    mdi(m, "M3 S400")
    record(sim, 3.0)
    mdi(m, "M5")
    record(sim, 2.0)
    s1 = m.axis("S1")
    p = float(m.k.st[s1.slot, L.S_P_CMD])
    assert p > 720.0
    mdi(m, "#CAX")
    record(sim, 0.5)
    q = float(m.k.st[s1.slot, L.S_P_CMD])
    assert 0.0 <= q < 360.0 and q == pytest.approx(p % 360.0, abs=1e-6)
    assert abs(float(m.k.st[s1.slot, L.S_LAG])) < 1.0  # actual moved with the command


def test_manual_plc_the_block_waits_for_rotmod_q_then_goes_on() -> None:
    sim, m, _ = make()
    m.submit(PlcMode("manual"))
    mdi(m, "G00 C45")
    record(sim, 1.0)
    assert m.channel.progress.waiting_for == "changeover to rotary axis mode (the PLC's ROTMOD_Q)"
    assert [p.signal for p in m.plc.pending] == ["ROTMOD"]
    assert state(m) is AxisState.CHANGEOVER and m.cax is not None
    assert mode(m) is SpindleMode.NONE and m.cax.phase == "external"
    assert isinstance(m.submit(PlcSignal("ROTMOD_Q", True)), Accepted)
    record(sim, 2.0)
    assert mode(m) is SpindleMode.ROTARY and abs(c_pos(m) - 45.0) < 0.01


def test_fault_plc_the_changeover_times_out_and_a_reset_adopts_the_spindle() -> None:
    sim, m, _ = make()
    m.submit(PlcMode("fault"))
    seen = m.events.cursor
    mdi(m, "G00 C45")
    record(sim, TIMEOUT_S + 0.2)
    err = next(e for e in events(m, seen) if e.code == Code.PLC_ACK_TIMEOUT)
    assert err.signal == "ROTMOD" and err.axis == "S1"
    assert state(m) is AxisState.ERROR and m.cax is not None
    assert mode(m) is SpindleMode.NONE and m.plc.pending == []
    m.submit(Reset())
    record(sim, 0.1)
    assert mode(m) is SpindleMode.SPINDLE  # the PLC still holds SPMOD_Q
    assert m.cax.requests == {"ROTMOD": False, "SPMOD": True}


def test_withdrawing_rotmod_q_in_rotary_mode_is_a_process_error() -> None:
    """003 §4.1: cancelling the acknowledgement during rotary axis operation; C moving on the
    path brakes, the block stops. Reset then finds neither acknowledgement: no mode, and the
    next spindle function changes over to spindle mode first."""
    sim, m, _ = make()
    mdi(m, "#CAX")
    record(sim, 0.5)
    mdi(m, "G01 C3000 F20000")
    record(sim, 0.5)
    s1 = m.axis("S1")
    assert state(m) is AxisState.MOVING
    seen = m.events.cursor
    m.submit(PlcSignal("ROTMOD_Q", False))
    record(sim, 2.0)
    codes = [e.code for e in events(m, seen)]
    assert codes[:2] == [34, Code.MODE_ACK_WITHDRAWN]
    assert state(m) is AxisState.ERROR and abs(float(m.k.st[s1.slot, L.S_V_CMD])) == 0.0
    assert m.cax is not None and mode(m) is SpindleMode.NONE
    m.submit(Reset())
    record(sim, 0.1)
    assert mode(m) is SpindleMode.NONE
    seen = m.events.cursor
    mdi(m, "M3 S300")
    record(sim, 3.0)
    assert [c for c, _s in sequence(m, seen)][-1] == 39
    assert state(m) is AxisState.ENDLESS


def test_estop_interrupts_the_changeover_and_reset_adopts_what_the_plc_answered() -> None:
    """003 §2.3: an immediate stop leaves the changeover pending; the PLC's answer does not
    complete it; Control-Reset aborts it and adopts the PLC's mode (here ROTMOD_Q)."""
    sim, m, _ = make()
    m.submit(PlcMode("manual"))
    mdi(m, "G00 C45")
    record(sim, 0.2)
    seen = m.events.cursor
    m.submit(EmergencyStop())
    record(sim, 0.5)
    assert 40 in [e.code for e in events(m, seen)]
    m.submit(PlcSignal("ROTMOD_Q", True))
    record(sim, 0.1)
    assert m.cax is not None and mode(m) is SpindleMode.NONE
    m.submit(Reset())
    record(sim, 1.0)
    assert [c for c, _s in sequence(m, seen)][-2:] == [41, 38]
    assert mode(m) is SpindleMode.ROTARY


def test_program_stop_interrupts_and_a_jog_key_aborts_then_changes_over_itself() -> None:
    """003 §2.3 "Jogging movements": jog of C aborts the interrupted changeover and commands
    a new one; the jog starts when the PLC acknowledges it."""
    sim, m, _ = make()
    m.submit(PlcMode("manual"))
    assert isinstance(m.submit(ProgramLoad("c", "G00 C45\nM30")), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    record(sim, 0.2)
    seen = m.events.cursor
    m.submit(ProgramStop())
    record(sim, 0.1)
    assert m.submit(JogStart(C, 1)) == Accepted(0, m.cycle)
    record(sim, 0.1)
    assert [c for c, _s in sequence(m, seen)] == [40, 41, 35, 36]
    assert [p.signal for p in m.plc.pending] == ["ROTMOD"]
    p0 = c_pos(m)
    m.submit(PlcSignal("ROTMOD_Q", True))
    record(sim, 1.0)
    assert state(m, C) is AxisState.JOG and c_pos(m) > p0 + 1.0
    m.submit(JogStop(C))
    record(sim, 1.0)
    assert state(m, C) is AxisState.STANDSTILL


def test_spindle_key_in_rotary_mode_changes_over_then_turns_with_spindle_override() -> None:
    """The M3 key in rotary mode: spindle mode first (its gear stage 3 again), then M3; in
    spindle mode the spindle override acts (50 % -> 500 rpm of 1000), the feed override
    does not."""
    sim, m, _ = make()
    mdi(m, "G00 C10")
    record(sim, 1.0)
    assert m.cax is not None and m.cax.rotary
    seen = m.events.cursor
    m.submit(HliWrite("override", 500, axis="S1"))
    m.submit(HliWrite("override", 300))  # the channel's feed override: not the spindle's
    assert isinstance(m.submit(SpindleRun("S1", 3, 1000.0)), Accepted)
    rec = record(sim, 4.0)
    assert [c for c, _s in sequence(m, seen)] == [c for c, _s in TO_SPINDLE]
    s1 = m.axis("S1")
    assert state(m) is AxisState.ENDLESS and s1.gear == 3
    assert rec[-1, s1.slot, L.R_V_ACT] / 6.0 == pytest.approx(500.0, rel=0.01)


def test_a_jog_key_does_not_stop_a_turning_spindle() -> None:
    sim, m, _ = make()
    mdi(m, "M3 S1000")
    record(sim, 1.0)
    out = m.submit(JogStart(C, 1))
    assert isinstance(out, Refused) and out.code == Code.AXIS_BUSY
    assert state(m) is AxisState.ENDLESS


def test_feed_is_over_x_and_c_follows_with_the_feed_override() -> None:
    """003 §1.2's spiral in G91: X40 C-270 F1200: the path is 40 mm of X at 1200 mm/min, C
    turns 270° in the same time (6.75°/mm); with C alone F is °/min (C90 F3600 from -270°:
    360° in 6 s)."""
    sim, m, _ = make()
    mdi(m, "#CAX")
    record(sim, 0.5)
    mdi(m, "G00 X0 C0")
    record(sim, 3.0)
    s1, x = m.axis("S1"), m.axis("X")
    mdi(m, "G01 G91 X40 C-270 F1200")
    rec = record(sim, 4.0)
    px, pc = rec[:, x.slot, L.R_P_CMD], rec[:, s1.slot, L.R_P_CMD]
    assert px[-1] == pytest.approx(40.0) and pc[-1] == pytest.approx(-270.0)
    moving = np.abs(np.diff(px)) > 1e-9
    steady = np.max(np.diff(px)) / 0.001 * 60.0
    assert steady == pytest.approx(1200.0, rel=1e-3)
    assert np.allclose(np.diff(pc)[moving], -6.75 * np.diff(px)[moving], atol=1e-9)
    mdi(m, "G90 C90 F3600")
    rec = record(sim, 8.0)
    pc = rec[:, s1.slot, L.R_P_CMD]
    dt = np.count_nonzero(np.abs(np.diff(pc)) > 1e-12) * 0.001
    assert pc[-1] == pytest.approx(90.0)
    assert dt == pytest.approx(360.0 / 3600.0 * 60.0, abs=0.5)  # 360° at 3600°/min (+ ramps)


def test_g63_after_c_changes_back_to_the_spindle_first() -> None:
    sim, m, _ = make()
    mdi(m, "G00 C0")
    record(sim, 1.0)
    seen = m.events.cursor
    mdi(m, "G00 Z5")
    record(sim, 1.0)
    mdi(m, "G63 Z-5 F250 S200")
    record(sim, 6.0)
    assert [c for c, _s in sequence(m, seen)] == [c for c, _s in TO_SPINDLE]
    assert abs(float(m.k.st[m.axis("Z").slot, L.S_P_ACT]) + 5.0) < 0.01


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_sessions_mixing_spindle_and_c(seed: int) -> None:
    """Seeded sessions of spindle and C commands, PLC modes, manual answers, withdrawals,
    E-stops and resets. Invariants every 10 ms: never both requests nor both modes, the
    drive does not move while the NC waits for the PLC (no motion without the
    acknowledgement), C is on the path only in rotary mode, no NaN anywhere."""
    rng = random.Random(seed)
    sim, m, _ = make()
    cax = m.cax
    assert cax is not None
    s1 = m.axis("S1")
    blocks = ["G00 C90", "G01 C-45 F3000", "#CAX", "#CAX OFF", "M3 S300", "M4 S500", "M5",
              "M19 S.POS=90", "G00 X20 C180", "G01 X10 Z-5 F2000", "G00 Z5"]  # fmt: skip
    for _ in range(60):
        r = rng.random()
        if r < 0.55:
            m.submit(Mdi(rng.choice(blocks)))
        elif r < 0.65:
            m.submit(PlcMode(rng.choice(["auto", "manual", "auto", "fault"])))
        elif r < 0.75:
            m.submit(PlcSignal(rng.choice(["ROTMOD_Q", "SPMOD_Q"]), rng.random() < 0.7))
        elif r < 0.82:
            m.submit(JogStart(C, rng.choice([1, -1])))
        elif r < 0.86:
            m.submit(JogStop(C))
        elif r < 0.9:
            m.submit(SpindleRun("S1", rng.choice([3, 5]), 250.0))
        elif r < 0.93:
            m.submit(EmergencyStop())
        else:
            m.submit(Reset())
        for _ in range(rng.randint(1, 40)):
            sim.run(10)
            assert not (cax.requests["ROTMOD"] and cax.requests["SPMOD"])
            if cax.mode is not SpindleMode.NONE:  # one mode, requested as that one
                assert cax.requests["ROTMOD"] == cax.rotary != cax.requests["SPMOD"]
            if s1.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
                assert cax.mode is SpindleMode.SPINDLE
            if cax.phase == "external":
                assert float(m.k.st[s1.slot, L.S_V_CMD]) == 0.0
            on_path = m.k.ist[s1.slot, L.I_ROLE] == L.ROLE_PATH_AXIS
            assert not on_path or cax.mode is SpindleMode.ROTARY
            assert np.all(np.isfinite(m.k.st[s1.slot, [L.S_P_CMD, L.S_P_ACT, L.S_V_CMD]]))
            assert not math.isnan(float(m.k.st[m.axis("X").slot, L.S_P_CMD]))


def test_g74_homes_c_on_its_zero_mark() -> None:
    """003 §2.3: homing by G74 (or by M19 automatically); as the C axis too. C ends on its
    reference position kenngr.ref_pos, homed."""
    sim, m, cfg = make()
    mdi(m, "G00 C100")
    record(sim, 2.0)
    assert not m.axis(C).homed
    mdi(m, "G74 C1")
    record(sim, 5.0)
    s1 = m.axis("S1")
    assert s1.homed and mode(m) is SpindleMode.ROTARY
    ref = cfg.axis("S1").eng("kenngr.ref_pos") % 360.0
    assert float(m.k.st[s1.slot, L.S_P_ACT]) % 360.0 == pytest.approx(ref, abs=0.01)


@pytest.mark.parametrize(
    ("key", "request_"),
    [
        (JogStart(C, 1), "ROTMOD"),
        (JogStart(C, -1), "ROTMOD"),
        (SpindleRun("S1", 3, 1000.0), "SPMOD"),
        (SpindleRun("S1", 4, 1000.0), "SPMOD"),
        (SpindleRun("S1", 5), "SPMOD"),
        (SpindlePosition("S1", 90.0), "SPMOD"),
    ],
    ids=["JGPOS", "JGNEG", "M3", "M4", "M5", "M19"],
)
def test_each_key_of_003_aborts_an_interrupted_changeover_and_commands_its_own(
    key: JogStart | SpindleRun | SpindlePosition, request_: str
) -> None:
    """003 §2.3 "Jogging movements": AxxCJGPOS/JGNEG, AxxCM3/M4/M5/M19 abort an interrupted
    changeover before the NC commands the one the key needs (here the interrupted one was to
    rotary axis mode, and the manual PLC had not answered it)."""
    sim, m, _ = make()
    m.submit(PlcMode("manual"))
    assert isinstance(m.submit(ProgramLoad("c", "G00 C45\nM30")), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    record(sim, 0.2)
    m.submit(ProgramStop())
    record(sim, 0.1)
    seen = m.events.cursor
    assert isinstance(m.submit(key), Accepted)
    record(sim, 0.2)
    assert [c for c, _s in sequence(m, seen)][:2] == [41, 35]
    if request_ == "ROTMOD":
        assert [p.signal for p in m.plc.pending] == ["ROTMOD"]
    else:  # the PLC never left spindle mode: its levels (SPMOD_Q) answer SPMOD at once
        assert m.plc.pending == [] and mode(m) is SpindleMode.SPINDLE


def test_removing_the_drive_enables_while_waiting_for_the_plc_does_not_stop_it() -> None:
    """003 §2.3 "Axis enabling signal": no immediate effect on the changeover."""
    sim, m, _ = make()
    m.submit(PlcMode("manual"))
    mdi(m, "#CAX")
    record(sim, 0.2)
    m.submit(HliWrite("TorquePermission", 0, axis="S1"))
    record(sim, 0.1)
    assert state(m) is AxisState.CHANGEOVER
    m.submit(HliWrite("TorquePermission", 1, axis="S1"))
    m.submit(PlcSignal("ROTMOD_Q", True))
    record(sim, 0.2)
    assert mode(m) is SpindleMode.ROTARY and state(m) is AxisState.STANDSTILL


def test_as_the_c_axis_its_speed_reads_in_degrees_per_minute() -> None:
    """The position indication of a rotary axis [003 §2.4]: C at F3600 shows 3600 °/min, the
    spindle S1 shows rpm."""
    sim, m, _ = make()
    mdi(m, "#CAX")
    record(sim, 0.5)
    mdi(m, "G01 C360 F3600")  # 6 s
    record(sim, 3.0)
    c = next(a for a in m.snapshot().axes if a.name == "S1")
    assert c.display_name == C and c.vel_unit == "°/min"
    assert c.vel_cmd == pytest.approx(3600.0, rel=1e-6)
    record(sim, 4.0)
    mdi(m, "M3 S1000")
    record(sim, 3.0)
    s = next(a for a in m.snapshot().axes if a.name == "S1")
    assert s.display_name == "S1" and s.vel_unit == "rpm"
    assert s.vel_cmd == pytest.approx(1000.0, rel=1e-6)


@pytest.mark.parametrize("plc", ["auto", "manual"])
@pytest.mark.parametrize("rotary", [True, False])
def test_the_changeover_runs_in_the_manuals_order_in_each_plc_mode(plc: str, rotary: bool) -> None:
    """003 Fig. 4-1 (1)-(6), both ways, whether the PLC answers by itself or by hand."""
    sim, m, _ = make()
    if not rotary:
        mdi(m, "#CAX")
        record(sim, 0.5)
    m.submit(PlcMode(plc))
    seen = m.events.cursor
    mdi(m, "#CAX" if rotary else "#CAX OFF")
    record(sim, 0.5)
    if plc == "manual":
        assert mode(m) is SpindleMode.NONE
        m.submit(PlcSignal("ROTMOD_Q" if rotary else "SPMOD_Q", True))
        record(sim, 0.1)
    assert sequence(m, seen) == (TO_ROTARY if rotary else TO_SPINDLE)
    assert mode(m) is (SpindleMode.ROTARY if rotary else SpindleMode.SPINDLE)


def test_feed_override_acts_on_c_in_rotary_mode() -> None:
    """003 §2.4: in rotary axis mode the feed override acts on C (50 %: 360° at F3600 takes
    12 s instead of 6); the spindle override does not."""
    sim, m, _ = make()
    mdi(m, "#CAX")
    record(sim, 0.5)
    m.submit(HliWrite("override", 500))
    m.submit(HliWrite("override", 1000, axis="S1"))
    mdi(m, "G01 C360 F3600")
    rec = record(sim, 14.0)
    pc = rec[:, m.axis(C).slot, L.R_P_CMD]
    moving_s = np.count_nonzero(np.abs(np.diff(pc)) > 1e-12) * 0.001
    assert pc[-1] == pytest.approx(360.0)
    assert moving_s == pytest.approx(12.0, abs=0.5)


def test_the_acknowledgements_are_levels_a_request_they_already_answer_goes_on() -> None:
    """003 §4.1: ROTMOD_Q/SPMOD_Q report the PLC's state continually. The PLC holds both
    (its mistake): #CAX waits; once SPMOD_Q goes (no process error: the NC is changing over),
    the levels read rotary axis mode and the changeover completes without another edge."""
    sim, m, _ = make()
    m.submit(PlcMode("manual"))
    m.submit(PlcSignal("ROTMOD_Q", True))
    assert mode(m) is SpindleMode.SPINDLE
    mdi(m, "#CAX")
    record(sim, 0.5)
    assert mode(m) is SpindleMode.NONE and [p.signal for p in m.plc.pending] == ["ROTMOD"]
    seen = m.events.cursor
    assert m.submit(PlcSignal("SPMOD_Q", False)) == Accepted(0, m.cycle, acknowledged=1)
    record(sim, 0.1)
    assert mode(m) is SpindleMode.ROTARY and Code.MODE_ACK_WITHDRAWN not in [
        e.code for e in events(m, seen)
    ]


def test_as_the_c_axis_at_rest_it_is_in_position() -> None:
    """Position control holds where the changeover left it: INPOS (003 §4.2) at once."""
    sim, m, _ = make()
    mdi(m, "#CAX")
    record(sim, 0.5)
    assert m.k.ist[m.axis(C).slot, L.I_IN_POS] == 1
