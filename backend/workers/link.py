"""The gateway's line to the worker that runs one machine: which worker and which build of it
(the epoch), the shared sample ring, the calls, and what the worker last pushed (status,
pacing, events, training faults). What the gateway keeps about the machine besides
(parameters waiting, jogs, captures, notices, control) lives in services of its own.
"""

from __future__ import annotations

import itertools
import threading
from collections import deque
from collections.abc import Callable
from pathlib import Path

import numpy as np

from backend.errors import WORKER_FAILURE, ApiError, Unavailable
from backend.workers.client import CALL_TIMEOUT_S, WorkerClient, WorkerGone, WorkerRefused
from backend.workers.flight import FlightWindow
from backend.workers.protocol import (
    MachineInfo,
    MachineNews,
    MachineSamples,
    Pacing,
    ParamSnapshot,
    Request,
    StatusRead,
    Watch,
)
from backend.workers.ring import SampleRing
from nc_sim.events import Event, EventLog
from nc_sim.faults import FaultState
from nc_sim.scope import Record
from nc_sim.signals import Signal

EARLY_PUSHES = 64  # pushes of a build kept until its AddMachine reply is through

Captured = Callable[[list[tuple[Record, ParamSnapshot]]], None]
# a machine's new events as its worker pushed them: (machine, epoch, events)
EventsTaken = Callable[[str, int, list[Event]], None]
# its job error windows, complete (backend/workers/flight.py): (machine, epoch, windows)
FlightsTaken = Callable[[str, int, list[FlightWindow]], None]


class MachineLink:
    """One machine's worker link. Request threads and the event loop share it: pushed news is
    swapped in whole or appended under `_news`; completed scope records go to `captured`."""

    def __init__(self, mid: str, cycle_s: float, captured: Captured) -> None:
        self.mid = mid
        self.worker: WorkerClient | None = None
        self.info: MachineInfo | None = None
        self.ring: SampleRing | None = None
        self.epoch = 0
        self.status: StatusRead | None = None  # the newest pushed status
        self.status_seq = 0
        self.pacing: Pacing | None = None
        self.events: EventLog[Event] = EventLog()
        self.signal_by_name: dict[str, Signal] = {}
        self.drive_signal_by_name: dict[str, Signal] = {}
        # the faults injected (by id, as its worker last told): they go with every rebuild
        self.faults: dict[int, FaultState] = {}
        self.watchers = 0  # viewers and consoles that need its status pushed (see `watch`)
        self._watching = threading.Lock()
        self._news = threading.Lock()
        # pushes of a newer build that came before its AddMachine reply was taken in
        self._early: deque[MachineNews | MachineSamples] = deque(maxlen=EARLY_PUSHES)
        self._serials = itertools.count(1)  # commands to this machine, numbered
        self._cycle_s = cycle_s  # until a build says its own
        self._captured = captured
        self.on_events: EventsTaken | None = None  # the machine's history takes them too
        self.on_flights: FlightsTaken | None = None  # the flight recorder's windows

    def watch(self, on: bool) -> None:
        """One more (or one fewer) watcher: the worker pushes the status while there is any.
        Telemetry's event loop and the console's thread both count, hence the lock."""
        with self._watching:
            self.watchers += 1 if on else -1
            if self.watchers == (1 if on else 0):
                self.post(Watch(self.mid, on))

    def next_serial(self) -> int:
        """The number of the next command to this machine."""
        return next(self._serials)

    # --- where it runs ------------------------------------------------------------------------
    def attach(self, worker: WorkerClient | None, info: MachineInfo) -> None:
        """The machine now runs on `worker` as built in `info` (a new epoch)."""
        old = self.ring
        ring = SampleRing.attach(Path(info.ring_path)) if info.ring_path else None
        if ring is None:
            ring = SampleRing.create(None, info.slots)
        with self._news:
            self.worker, self.info, self.ring, self.epoch = worker, info, ring, info.epoch
            self.events = EventLog()
            self.signal_by_name = {s.name: s for s in info.signals}
            self.drive_signal_by_name = {s.name: s for s in info.drive_signals}
            self.status, self.pacing = None, info.pacing
            # the build's faults with their ids, as the build answered: known from the
            # first moment (a first status may come much later, or never while unwatched)
            self.faults = {f.id: f for f in info.faults}
            early = [p for p in self._early if p.epoch == info.epoch]
            self._early.clear()
        if old is not None:
            old.close()
        for push in early:
            self.take(push)

    @property
    def live_worker(self) -> WorkerClient | None:
        """The worker, while it is alive."""
        worker = self.worker
        return worker if worker is not None and worker.alive else None

    @property
    def axes(self) -> list[str]:
        return self.info.axes if self.info else []

    @property
    def signals(self) -> list[Signal]:
        return self.info.signals if self.info else []

    @property
    def cycle(self) -> int:
        """The newest cycle stepped (from the sample ring)."""
        return self.ring.head if self.ring else 0

    @property
    def cycle_s(self) -> float:
        return self.info.cycle_s if self.info else self._cycle_s

    # --- calls ----------------------------------------------------------------------------------
    def call(self, request: Request) -> object:
        """A request to the machine's worker; 503 while it has none, 404/409/422 as refused."""
        try:
            return self._worker().call(request)
        except (WorkerGone, WorkerRefused) as e:
            raise self._answer(e) from None

    async def acall(self, request: Request, timeout_s: float = CALL_TIMEOUT_S) -> object:
        """`call` from the event loop (no thread waits for the worker)."""
        try:
            return await self._worker().acall(request, timeout_s)
        except (WorkerGone, WorkerRefused) as e:
            raise self._answer(e) from None

    def _worker(self) -> WorkerClient:
        worker = self.live_worker
        if worker is None:
            raise Unavailable(f"machine '{self.mid}' is being rebuilt: try again")
        return worker

    def _answer(self, e: WorkerGone | WorkerRefused) -> ApiError:
        """A worker's failure as the API answers it."""
        if isinstance(e, WorkerGone):
            return Unavailable(f"machine '{self.mid}': {e}; it is rebuilt")
        return WORKER_FAILURE[e.failure.kind](e.failure.message)

    def post(self, request: Request) -> None:
        """A request whose answer nobody waits for (watching)."""
        worker = self.live_worker
        if worker is not None:
            worker.post(request)

    def samples(
        self, signals: list[Signal], first: int, last: int, stride: int
    ) -> tuple[np.ndarray, int]:
        assert self.ring is not None
        return self.ring.read(signals, first, last, stride)

    # --- what the worker pushed -----------------------------------------------------------------
    def take(self, push: MachineNews | MachineSamples) -> None:
        """News or samples of this machine (kept for later when from a build not attached
        yet, dropped when from a build that was replaced)."""
        with self._news:
            if push.epoch > self.epoch:
                self._early.append(push)
                return
            if push.epoch < self.epoch:
                return
            if isinstance(push, MachineSamples):
                assert self.ring is not None
                self.ring.put(push.first, push.rows)  # type: ignore[arg-type]
                return
        self.news(push)

    def news(self, n: MachineNews) -> None:
        with self._news:
            if n.epoch != self.epoch:
                return  # from a build that was replaced
            for e in n.events:
                self.events.append(e)
            if n.status is not None:
                self.status = n.status
                self.status_seq += 1
                self.faults = {f.id: f for f in n.status.faults}
        if n.events and self.on_events is not None:
            self.on_events(self.mid, n.epoch, list(n.events))
        if n.captures:
            self._captured(list(n.captures))
        if n.flights and self.on_flights is not None:
            self.on_flights(self.mid, n.epoch, list(n.flights))

    def recent_events(self, n: int) -> list[Event]:
        """The newest n events of the gateway's copy, oldest first."""
        with self._news:
            return self.events.tail(n)

    def events_since(self, cursor: int) -> tuple[list[Event], int, int, int]:
        """(events, seq of the first, next cursor, missed) from the gateway's copy."""
        with self._news:
            read = self.events.since(cursor)
        return read.entries, read.first_seq, read.cursor, read.dropped
