"""Status and telemetry read the machine's bounded event log by cursor: an active job error
keeps its event after the log has dropped it, and a telemetry client learns how many events
it missed. In process: the machine service with its worker on a thread, machines stepped by
request."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Iterator
from pathlib import Path
from typing import cast

import pytest
from fastapi import WebSocket

from api.commands import EmergencyStopCommand
from backend.services.audit import Audit
from backend.services.commands import execute
from backend.services.history import History
from backend.services.machines import MachineProxy, MachineService
from backend.services.status import RECENT_EVENTS, machine_status
from backend.services.telemetry import TelemetryHub
from backend.workers.protocol import Submit
from nc_sim.commands import Mdi
from nc_sim.errors import Code
from nc_sim.events import EVENT_LOG_LEN
from tests.backend.fakews import FakeSocket
from tests.backend.inprocess import INSTRUCTOR, machine_service, paused_demo, step, wait_until


@pytest.fixture
def service(tmp_path: Path) -> Iterator[MachineService]:
    with machine_service(tmp_path) as s:
        yield s


def _flood(m: MachineProxy, n: int) -> None:
    """n refused MDI blocks: one event each, none of them sets a job error."""
    for _ in range(n):
        m.link.call(Submit(m.id, Mdi("G1 X")))


def test_an_active_job_error_keeps_its_event_after_the_log_dropped_it(
    service: MachineService,
) -> None:
    host = paused_demo(service, "m")
    stop = asyncio.run(
        execute(
            INSTRUCTOR,
            host,
            EmergencyStopCommand(),
            Audit(service.store),
            History(service.store, 1.0, 1000),
        )
    )
    step(host, 10)
    _flood(host, EVENT_LOG_LEN + 100)
    step(host, 10)
    wait_until(lambda: host.link.events.cursor >= EVENT_LOG_LEN + 100)
    assert all(e.code == Code.BLOCK_SYNTAX for e in host.link.events)  # E-stop dropped
    st = asyncio.run(machine_status(host))
    assert [(e.code, e.cycle) for e in st.job_errors] == [(int(Code.EMERGENCY_STOP), stop.cycle)]
    assert len(st.recent_events) == RECENT_EVENTS
    assert all(e.code == Code.BLOCK_SYNTAX for e in st.recent_events)


def test_a_telemetry_client_that_fell_behind_learns_how_many_events_it_missed(
    service: MachineService,
) -> None:
    host = paused_demo(service, "m")

    async def run() -> list[dict[str, object]]:
        hub = TelemetryHub(1.0, 1000)  # ticked by hand below
        ws = FakeSocket()
        sub = hub.add(cast(WebSocket, ws), host, INSTRUCTOR)
        start, cursor[0] = host.link.events.cursor, sub.event_cursor
        # more than the log holds before the next frame (blocking calls: off the loop)
        await asyncio.to_thread(_flood, host, EVENT_LOG_LEN + 250)
        wait_until(lambda: host.link.events.cursor == start + EVENT_LOG_LEN + 250)
        hub.tick()
        await asyncio.sleep(0.05)  # let the send task run
        return [json.loads(t) for t in ws.texts]

    cursor = [0]
    texts = asyncio.run(run())
    events = [t for t in texts if t["type"] == "event"]
    assert len(events) == EVENT_LOG_LEN
    # a new viewer starts with the newest RECENT_EVENTS events; the log now holds only the
    # last EVENT_LOG_LEN of the flood, so it missed the first 250 of the flood and what it
    # would have got from before
    start = cast(int, events[-1]["seq"]) + 1 - (EVENT_LOG_LEN + 250)
    assert 0 <= start - cursor[0] <= RECENT_EVENTS
    assert events[0]["missed"] == 250 + start - cursor[0]
    assert all(e["missed"] == 0 for e in events[1:])
    seqs = [cast(int, e["seq"]) for e in events]
    assert seqs == list(range(seqs[0], seqs[0] + EVENT_LOG_LEN))
