"""Typed events: sequence numbers from the event log, the M function and gear stage as
fields, and triggers that match on fields, never on message text."""

from __future__ import annotations

import pytest

from nc_sim.commands import Accepted, Home, SpindlePosition, SpindleRun
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.scope import EventKind, EventTrigger
from tests.nc_sim.sim_helpers import L, make, mdi, record


def _event(code: Code, message: str, m: int | None = None, axis: str = "S1") -> Event:
    return Event(seq=0, cycle=100, t_s=0.1, axis=axis, code=int(code), message=message, m=m)


def test_sequence_numbers_are_the_event_log_positions_and_count_up_by_one() -> None:
    sim, m, _ = make()
    mdi(m, "G91 G01 X5 F3000 M3 S1000")
    record(sim, 2.0)
    mdi(m, "M19 S.POS=90")
    record(sim, 6.0)
    read = m.events.since(0)
    assert read.dropped == 0 and len(read.entries) > 10
    seqs = [e.seq for e in read.entries]
    assert seqs == list(range(read.first_seq, read.cursor))
    assert all(m.events[i].seq == m.events.first_seq + i for i in range(len(m.events)))


def test_an_m19_positioning_ends_in_an_in_position_event_with_m_19() -> None:
    sim, m, _ = make()
    s = m.axis("S1")
    start = m.events.cursor
    assert isinstance(m.submit(SpindlePosition("S1", 90.0)), Accepted)
    record(sim, 6.0)
    new = m.events.since(start).entries
    started = [e for e in new if e.code == Code.EV_M_START]
    assert [(e.axis, e.m) for e in started] == [("S1", 19)]
    (done,) = [e for e in new if e.code == Code.EV_IN_POSITION]
    assert (done.axis, done.m) == ("S1", 19)
    # it ends the positioning: the spindle stands within its exact-stop window of 90°
    window = m.k.pr[s.slot, L.P_INPOS_WIN]
    assert abs((m.k.st[s.slot, L.S_P_ACT] - 90.0 + 180.0) % 360.0 - 180.0) <= window
    assert EventTrigger(EventKind.M19_DONE, "S1").cycle_of(done) == done.cycle


def test_homing_a_spindle_ends_in_position_without_an_m_function() -> None:
    sim, m, _ = make()
    start = m.events.cursor
    assert isinstance(m.submit(Home("S1")), Accepted)
    record(sim, 6.0)
    (done,) = [e for e in m.events.since(start).entries if e.code == Code.EV_IN_POSITION]
    assert done.m is None  # G74 is no M function: it is no "M19 done"
    assert EventTrigger(EventKind.M19_DONE).cycle_of(done) is None


def test_a_spindle_start_carries_its_m_function() -> None:
    sim, m, _ = make()
    start = m.events.cursor
    assert isinstance(m.submit(SpindleRun("S1", 3, 1000.0)), Accepted)
    record(sim, 0.1)
    assert isinstance(m.submit(SpindleRun("S1", 5)), Accepted)
    record(sim, 0.1)
    started = [e for e in m.events.since(start).entries if e.code == Code.EV_M_START]
    assert [e.m for e in started] == [3, 5]


def test_a_gear_change_carries_its_gear_stage() -> None:
    """The demo starts in M42 (gear stage 3, range_table[2] 700-3500 rpm); S300 lies only in
    range_table[0] (50-560 rpm): stage 1, selected by M40 [000 §2.8.2]."""
    sim, m, _ = make()
    start = m.events.cursor
    assert m.axis("S1").gear == 3
    assert isinstance(m.submit(SpindleRun("S1", 3, 300.0)), Accepted)
    record(sim, 6.0)
    new = m.events.since(start).entries
    (began,) = [e for e in new if e.code == Code.EV_GEAR_CHANGE_START]
    (changed,) = [e for e in new if e.code == Code.EV_GEAR_CHANGED]
    assert (began.gear, changed.gear) == (1, 1) and began.seq < changed.seq
    output = [(e.m, e.gear) for e in new if e.code == Code.EV_M_OUTPUT]
    acked = [e.m for e in new if e.code == Code.EV_M_ACK]
    assert (40, 1) in output and 40 in acked
    # M3 first, the gear change's M40, then M3 again in the new stage
    assert [e.m for e in new if e.code == Code.EV_M_START] == [3, 40, 3]
    assert m.axis("S1").gear == 1


@pytest.mark.parametrize(
    ("message", "m", "fires"),
    [
        ("S1 at 0° (G74)", 19, True),  # the fields say M19: the text is only for people
        ("S1 at 90° (M19)", None, False),  # the text says M19, the fields do not
        ("M19 done", 3, False),
    ],
)
def test_m19_done_matches_fields_not_text(message: str, m: int | None, fires: bool) -> None:
    ev = _event(Code.EV_IN_POSITION, message, m)
    assert EventTrigger(EventKind.M19_DONE, "S1").cycle_of(ev) == (100 if fires else None)


@pytest.mark.parametrize(
    ("message", "m", "fires"),
    [("M4 S1000", 3, True), ("M3 S1000", 4, False), ("", 3, True)],
)
def test_m_start_matches_the_m_field_not_text(message: str, m: int, fires: bool) -> None:
    ev = _event(Code.EV_M_START, message, m)
    # an M function start shows from the cycle after it was raised
    assert EventTrigger(EventKind.M_START, "S1", 3).cycle_of(ev) == (101 if fires else None)
    assert EventTrigger(EventKind.M_START, "S2", 3).cycle_of(ev) is None  # another spindle
