"""The command surface: every command through `Machine.submit`, answered by its outcome.

Accepted carries the cycle (and the block number or acknowledgement count), Refused the job
error the command raised (an MDI block that fails while starting included), Invalid the
message and column of a malformed command; the caller's serial comes back in each.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from nc_sim.commands import (
    Accepted,
    Command,
    EmergencyStop,
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
from nc_sim.kernel import layout as L
from nc_sim.snapshot import AxisState
from tests.nc_sim.sim_helpers import make, record

X0_MM = 50.0  # demo X stands at 50 mm after power-on

ACCEPTED: list[Command] = [
    Mdi("M3 S1000"),
    SpindleRun("S", 3, 1000.0),
    SpindlePosition("S", 90.0),
    GearChange("S", 41),
    Home("X"),
    JogStart("X", 1),
    JogStop("X"),
    JogStep("X", 1.0),
    Move("X", 60.0),
    HliWrite("override", 500),
    PlcMode("manual"),
    PlcAck(None),
    Reset(),
    EmergencyStop(),
]


@pytest.mark.parametrize("cmd", ACCEPTED, ids=lambda c: type(c).__name__)
def test_every_command_is_accepted_on_a_ready_machine_with_its_serial(cmd: Command) -> None:
    _, m, _ = make()
    sent = replace(cmd, serial=4711)
    out = m.submit(sent)
    assert isinstance(out, Accepted) and out.serial == 4711 and out.cycle == m.cycle
    assert m.outcomes[-1] == out  # kept in the machine's outcome log


def test_the_answer_carries_the_block_number_and_the_acknowledgement_count() -> None:
    sim, m, _ = make()
    first, second = m.submit(Mdi("M8", serial=1)), m.submit(Mdi("M9", serial=2))
    assert isinstance(first, Accepted) and isinstance(second, Accepted)
    assert first.block_id is not None and second.block_id == first.block_id + 1
    record(sim, 0.1)  # the PLC acknowledged M8, then M9 (plc.m_ack_delay 20 ms)
    assert m.queued_blocks == 0
    assert m.submit(PlcMode("manual")) == Accepted(0, m.cycle)
    m.submit(Mdi("M10"))
    record(sim, 0.1)  # M10 waits for the hand
    assert m.submit(PlcAck(10, serial=3)) == Accepted(3, m.cycle, acknowledged=1)
    assert m.submit(PlcAck(10)) == Accepted(0, m.cycle, acknowledged=0)  # nothing pending


def test_a_block_that_fails_while_starting_is_refused_with_its_job_error() -> None:
    """Without DriveOn a motion raises 90001 as it starts: the block is refused, not queued
    (before, the block read as accepted because it parsed)."""
    sim, m, _ = make()
    x = m.axis("X")
    assert isinstance(m.submit(HliWrite("DriveOn", 0, "X")), Accepted)
    out = m.submit(Mdi("G00 X100", serial=7))
    assert isinstance(out, Refused) and out.serial == 7
    assert out.code == Code.NO_ENABLES and out.error.axis == "X" and "DriveOn" in out.detail
    assert out.cycle == m.cycle and out.error in list(m.events)
    assert m.queued_blocks == 0
    record(sim, 0.2)
    assert m.k.st[x.slot, L.S_P_CMD] == X0_MM  # nothing moved


def test_a_speed_above_the_highest_gear_stage_is_refused_naming_the_limit() -> None:
    """M45 reaches 7000 rpm (P-CHAN-00055): S20000 fits no gear stage, 90017."""
    sim, m, _ = make()
    s = m.axis("S")
    out = m.submit(Mdi("M3 S20000"))
    assert isinstance(out, Refused) and out.code == Code.GEAR_NO_RANGE
    assert "7000 rpm" in out.detail and "P-CHAN-00055" in out.detail
    record(sim, 0.2)
    assert s.state is AxisState.STANDSTILL and m.k.st[s.slot, L.S_V_CMD] == 0.0


def test_a_block_with_a_syntax_error_is_invalid_with_its_column() -> None:
    _, m, _ = make()
    block = "G01 X10 F500 &"
    out = m.submit(Mdi(block, serial=9))
    assert isinstance(out, Invalid) and out.serial == 9
    assert out.column == block.index("&") + 1 and out.code == Code.BLOCK_SYNTAX
    assert m.events[-1].code == Code.BLOCK_SYNTAX and m.queued_blocks == 0


def test_a_block_queued_behind_a_running_one_is_refused_and_the_one_before_runs_on() -> None:
    """The look-ahead checks a queued block when it is prepared: 300 m is beyond the SGN32
    position range (±214748.3647 mm), so the second block is refused with 90003 while the
    first still runs, and the first runs to its end."""
    sim, m, _ = make()
    first = m.submit(Mdi("G01 X60 F1000"))  # 10 mm at 1000 mm/min: 0.6 s plus ramps
    queued = m.submit(Mdi("G00 X300000"))
    assert isinstance(first, Accepted) and isinstance(queued, Refused)
    assert queued.code == Code.SOFTWARE_LIMIT and queued.error.axis == "X"
    assert m.queued_blocks == 1
    record(sim, 1.5)
    done = [e for e in m.events if e.code == Code.EV_BLOCK_DONE]
    assert [e.message for e in done] == ["G01 X60 F1000"]
    assert m.queued_blocks == 0 and m.k.st[m.axis("X").slot, L.S_P_CMD] == 60.0


def test_a_queued_block_that_fails_later_names_itself_and_what_follows_it() -> None:
    """A block accepted into the queue can still fail when it starts: M3 S20000 behind M3 S1500
    is beyond the demo's top gear stage (M45 up to 7000 rpm), so it raises 90017 once S1500
    is reached. The log says which blocks that error dropped (the failing one and the one
    queued behind it, by the block ids their commands were answered with, the error's seq as
    value), so the job error can be put down to the command that sent the block; the block
    before them runs to its end."""
    sim, m, _ = make()
    ran, failing, behind = (m.submit(Mdi(b)) for b in ("M3 S1500", "M3 S20000", "G01 X60 F1000"))
    assert all(isinstance(o, Accepted) for o in (ran, failing, behind))
    record(sim, 3.0)
    error = next(e for e in m.events if e.error)
    assert error.code == Code.GEAR_NO_RANGE
    dropped = [e for e in m.events if e.code == Code.EV_BLOCK_DROPPED]
    assert [(e.block, e.value) for e in dropped] == [
        (failing.block_id, error.seq),  # type: ignore[union-attr]
        (behind.block_id, error.seq),  # type: ignore[union-attr]
    ]
    done = [e.block for e in m.events if e.code == Code.EV_BLOCK_DONE]
    assert done == [ran.block_id]  # type: ignore[union-attr]


def test_a_command_refused_by_its_precondition_is_refused() -> None:
    sim, m, _ = make()
    assert isinstance(m.submit(JogStart("X", 1)), Accepted)
    record(sim, 0.1)
    out = m.submit(JogStep("X", 1.0, serial=5))  # an increment only from standstill
    assert isinstance(out, Refused) and out.code == Code.AXIS_BUSY and out.serial == 5


@pytest.mark.parametrize(
    ("cmd", "says"),
    [
        (Home("Q"), "no axis or spindle 'Q'"),
        (SpindleRun("X", 3, 100.0), "X is not a spindle"),
        (HliWrite("bogus", 1, "X"), "unknown axis control unit 'bogus'"),
        (HliWrite("DriveOn", 1), "unknown channel control unit 'DriveOn'"),
        (GearChange("S", 46), "M40..M45"),
        (PlcMode("sometimes"), "unknown PLC mode 'sometimes'"),
        (SpindleRun("S", 3, -1000.0), "negative"),
    ],
    ids=lambda v: type(v).__name__ if not isinstance(v, str) else "",
)
def test_misuse_is_invalid_not_an_exception(cmd: Command, says: str) -> None:
    """A process boundary carries answers, not exceptions: misuse is an Invalid outcome."""
    _, m, _ = make()
    before = m.events.cursor
    out = m.submit(replace(cmd, serial=3))
    assert isinstance(out, Invalid) and out.serial == 3 and says in out.message
    assert out.column is None and out.code is None
    assert m.events.cursor == before  # nothing happened on the machine
