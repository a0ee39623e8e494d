"""The bounded event log: sequence numbers, cursors, drops; the machine's logs stay bounded."""

from __future__ import annotations

import pytest

from nc_sim.commands import Mdi
from nc_sim.config import demo_machine
from nc_sim.errors import Code
from nc_sim.events import EVENT_LOG_LEN, OUTCOME_LOG_LEN, EventLog
from nc_sim.scenario import run_scenario
from tests.nc_sim.sim_helpers import make


def test_entries_are_numbered_and_read_from_a_cursor() -> None:
    log: EventLog[str] = EventLog(maxlen=5)
    assert [log.append(x) for x in "abc"] == [0, 1, 2]
    read = log.since(1)
    assert (read.entries, read.first_seq, read.cursor, read.dropped) == (["b", "c"], 1, 3, 0)
    assert log.since(read.cursor).entries == []  # nothing new
    log.append("d")
    assert log.since(read.cursor).entries == ["d"]
    assert (len(log), log[-1], list(log), log.tail(2)) == (4, "d", list("abcd"), ["c", "d"])


def test_a_full_log_drops_the_oldest_and_tells_a_reader_that_fell_behind() -> None:
    log: EventLog[int] = EventLog(maxlen=3)
    for i in range(10):
        log.append(i)
    assert list(log) == [7, 8, 9] and len(log) == 3
    assert (log.first_seq, log.cursor) == (7, 10)
    read = log.since(4)  # a reader that has seen 0..3: 4, 5, 6 are gone
    assert (read.entries, read.first_seq, read.dropped, read.cursor) == ([7, 8, 9], 7, 3, 10)
    assert log.since(8).dropped == 0 and log.since(8).entries == [8, 9]
    assert log.tail(100) == [7, 8, 9]


def test_an_empty_log_is_refused() -> None:
    with pytest.raises(ValueError, match="at least one"):
        EventLog(maxlen=0)


def test_machine_events_and_acknowledgements_stay_bounded() -> None:
    """A command per block for longer than the logs hold: memory stays bounded, the cursor
    counts every event, and a reader from the start learns how many it missed."""
    _, m, _ = make()
    start = m.events.cursor
    n = EVENT_LOG_LEN + 500
    for _ in range(n):
        # invalid at once: one BLOCK_SYNTAX event and one outcome each
        m.submit(Mdi("G1 X"))
    assert len(m.events) == EVENT_LOG_LEN
    assert m.events.cursor == start + n
    assert len(m.outcomes) == OUTCOME_LOG_LEN and m.outcomes.cursor >= n
    read = m.events.since(start)
    assert read.dropped == 500 and len(read.entries) == EVENT_LOG_LEN
    # each event keeps the number the log gave it, also after the log dropped older ones
    assert [e.seq for e in read.entries] == list(range(read.first_seq, read.cursor))
    assert all(e.code == Code.BLOCK_SYNTAX for e in read.entries)


def test_a_scenario_result_keeps_every_event_the_machine_log_dropped() -> None:
    """The headless runner collects events as it goes: a run with more events than the
    machine's log holds returns all of them, in order."""
    n = EVENT_LOG_LEN + 300
    actions = [{"t_s": 0.001 * (i // 100), "mdi": "G1 X"} for i in range(n)]  # refused each
    result = run_scenario(demo_machine(), {"duration_s": 0.2, "actions": actions})
    refused = [e for e in result.events if e.code == Code.BLOCK_SYNTAX]
    assert len(refused) == n
    assert [e.cycle for e in result.events] == sorted(e.cycle for e in result.events)
    assert len(result.machine.events) == EVENT_LOG_LEN  # the machine itself stayed bounded
