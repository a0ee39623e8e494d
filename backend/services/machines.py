"""The machines of the service as the gateway knows them: identity and parameter lists (kept in
SQLite), which worker runs each, and what that worker last pushed.

A machine runs on exactly one worker. When a worker dies a replacement is started, then its
machines are rebuilt from their stored parameters on the least loaded live workers, the
replacement among them (a power cycle: cycle 0, new epoch), and their viewers are told;
machines on other workers never notice.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import threading
import time
import uuid
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from api.machines import MachineCreate
from api.telemetry import NoticeKind
from backend.errors import WORKER_FAILURE, ApiError, Conflict, Invalid, Unavailable, not_found
from backend.services.control import MachineControl
from backend.services.store import Store, StoredMachine
from backend.workers.client import CALL_TIMEOUT_S, WorkerClient, WorkerGone, WorkerRefused
from backend.workers.pool import NoLiveWorker, WorkerPool
from backend.workers.protocol import (
    AddMachine,
    MachineInfo,
    MachineNews,
    MachineSamples,
    Mode,
    Pacing,
    ParamSnapshot,
    Push,
    RemoveMachine,
    Request,
    StatusRead,
    Values,
    Watch,
    WorkerNews,
)
from backend.workers.ring import SampleRing
from nc_sim.config import MachineConfig, apply_values, demo_machine, machine_from_lists
from nc_sim.errors import NcUsageError
from nc_sim.events import Event, EventLog
from nc_sim.faults import NOW, Fault, FaultState, Trigger
from nc_sim.params import ParamListError, Scope, Value
from nc_sim.scope import Record
from nc_sim.signals import Signal

log = logging.getLogger(__name__)

RECENT_CAPTURES = 16  # completed captures kept in memory until saved to the library
EARLY_PUSHES = 64  # pushes of a build kept until its AddMachine reply is through


@dataclass
class Pending:
    """An accepted value that waits for reset or restart."""

    value: Value
    effect: str


@dataclass
class Capture:
    """A completed scope record with what the machine was at the time."""

    id: str
    record: Record
    params: ParamSnapshot
    created_unix: float


@dataclass(frozen=True)
class Notice:
    """Something every viewer of a machine must see (a banner), numbered per machine."""

    seq: int
    kind: NoticeKind
    message: str
    time_unix: float


class MachineProxy:
    """One machine in the gateway. Request threads share it: `lock` guards the lists and
    pending values; pushed news is swapped in whole or appended under `_news`."""

    def __init__(self, sm: StoredMachine, cfg: MachineConfig) -> None:
        self.id = sm.id
        self.name = sm.name
        self.source = sm.source
        self.cfg = cfg  # the written lists the worker runs with (the gateway's copy)
        self.pending: dict[tuple[str, str, str], Pending] = {}
        self.lock = threading.RLock()
        self.worker: WorkerClient | None = None
        self.info: MachineInfo | None = None
        self.ring: SampleRing | None = None
        self.epoch = 0
        self.deleted = False  # telemetry closes its subscribers
        self.watchers = 0  # viewers and consoles that need its status pushed (see `watch`)
        self._watching = threading.Lock()
        self.control = MachineControl()  # who holds it (backend/services/control.py)
        # jogs whose start is audited: (axis, session, client) -> (direction, feed, when)
        self.jogs_audited: dict[tuple[str, str, str], tuple[int, float | None, float]] = {}
        self.scope_setup: object | None = None  # the ScopeSetupModel as the client asked
        self.captures: deque[Capture] = deque(maxlen=RECENT_CAPTURES)  # newest last
        self.notices: deque[Notice] = deque(maxlen=16)
        self.status: StatusRead | None = None  # the newest pushed status
        self.status_seq = 0
        self.pacing: Pacing | None = None
        self._news = threading.Lock()
        self.events: EventLog[Event] = EventLog()
        # pushes of a newer build that came before its AddMachine reply was taken in
        self._early: deque[MachineNews | MachineSamples] = deque(maxlen=EARLY_PUSHES)
        self._serials = itertools.count(1)  # commands to this machine, numbered
        # training: the faults injected (by id, as its worker last told), the exercise whose
        # checks its worker evaluates; both go with every rebuild
        self.faults: dict[int, FaultState] = {}
        self.exercise: object | None = None

    def watch(self, on: bool) -> None:
        """One more (or one fewer) watcher: the worker pushes the status while there is any.
        Telemetry's event loop and the console's thread both count, hence the lock."""
        with self._watching:
            self.watchers += 1 if on else -1
            if self.watchers == (1 if on else 0):
                self.post(Watch(self.id, on))

    def next_serial(self) -> int:
        """The number of the next command to this machine."""
        return next(self._serials)

    # --- where it runs --------------------------------------------------------------------
    def attach(self, worker: WorkerClient | None, info: MachineInfo) -> None:
        """The machine now runs on `worker` as built in `info` (a new epoch)."""
        old = self.ring
        ring = SampleRing.attach(Path(info.ring_path)) if info.ring_path else None
        if ring is None:
            ring = SampleRing.create(None, info.slots)
        with self._news:
            self.worker, self.info, self.ring, self.epoch = worker, info, ring, info.epoch
            self.events = EventLog()
            self.signal_by_name: dict[str, Signal] = {s.name: s for s in info.signals}
            self.status, self.pacing = None, None
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
        return self.info.cycle_s if self.info else self.cfg.cycle_s

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
        worker = self.worker
        if worker is None or not worker.alive:
            raise Unavailable(f"machine '{self.id}' is being rebuilt: try again")
        return worker

    def _answer(self, e: WorkerGone | WorkerRefused) -> ApiError:
        """A worker's failure as the API answers it."""
        if isinstance(e, WorkerGone):
            return Unavailable(f"machine '{self.id}': {e}; it is rebuilt")
        return WORKER_FAILURE[e.failure.kind](e.failure.message)

    def post(self, request: Request) -> None:
        """A request whose answer nobody waits for (watching)."""
        worker = self.worker
        if worker is not None and worker.alive:
            worker.post(request)

    def samples(
        self, signals: list[Signal], first: int, last: int, stride: int
    ) -> tuple[np.ndarray, int]:
        assert self.ring is not None
        return self.ring.read(signals, first, last, stride)

    # --- what the worker pushed -------------------------------------------------------------
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
        for rec, params in n.captures:
            self.captures.append(Capture(uuid.uuid4().hex[:12], rec, params, time.time()))

    def recent_events(self, n: int) -> list[Event]:
        """The newest n events of the gateway's copy, oldest first."""
        with self._news:
            return self.events.tail(n)

    def events_since(self, cursor: int) -> tuple[list[Event], int, int, int]:
        """(events, seq of the first, next cursor, missed) from the gateway's copy."""
        with self._news:
            read = self.events.since(cursor)
        return read.entries, read.first_seq, read.cursor, read.dropped

    def notice(self, kind: NoticeKind, message: str) -> None:
        seq = self.notices[-1].seq + 1 if self.notices else 1
        self.notices.append(Notice(seq, kind, message, time.time()))


class MachineService:
    """Owns the proxies; places machines on workers and rebuilds them when a worker dies."""

    def __init__(self, store: Store, pool: WorkerPool) -> None:
        self.store = store
        self.pool = pool
        self._proxies: dict[str, MachineProxy] = {}
        # machines being built and where: their pushes may come before the reply, and they
        # count as load, so machines created at once spread over the workers
        self._building: dict[str, tuple[MachineProxy, WorkerClient]] = {}
        self._placing = threading.Lock()
        self._lock = threading.Lock()
        self.rebuilt = 0  # machines rebuilt after their worker died
        # class seats' exercises and starting faults, by machine: `load` builds them so
        self.seats: dict[str, tuple[object, list[tuple[Fault, Trigger]]]] = {}

    def proxies(self) -> list[MachineProxy]:
        with self._lock:
            return list(self._proxies.values())

    def get(self, mid: str) -> MachineProxy:
        proxy = self._proxies.get(mid)
        if proxy is None:
            raise not_found(f"machine '{mid}'")
        return proxy

    def on_machine(self, worker: WorkerClient) -> list[MachineProxy]:
        return [p for p in self.proxies() if p.worker is worker]

    def _load(self, worker: WorkerClient) -> set[str]:
        """The machines a worker runs or is building."""
        building = {mid for mid, (_p, w) in self._building.items() if w is worker}
        return {p.id for p in self.on_machine(worker)} | building

    def _config(self, sm: StoredMachine) -> MachineConfig:
        if sm.source == "demo":
            cfg = demo_machine()
        else:
            cfg = machine_from_lists(sm.name, sm.channel_list, sm.axis_lists or {}, sm.tool_list)
        apply_values(cfg, self.store.values(sm.id), skip_missing_axes=True)
        return cfg

    def _place(
        self,
        proxy: MachineProxy,
        worker: WorkerClient | None = None,
        state: bytes | None = None,
        faults: list[tuple[Fault, Trigger]] | None = None,
        mode: Mode = "run",
    ) -> None:
        """Build the machine on a worker (the least loaded live one unless given): powered on
        with its training faults as they stand (an armed one armed again, an active one at
        once), or restored from a snapshot's `state` (faults and all)."""
        with self._placing:
            try:
                worker = worker or self.pool.choose(self._load)
            except NoLiveWorker as e:
                raise Unavailable(str(e)) from None
            self._building[proxy.id] = (proxy, worker)
        epoch = proxy.epoch + 1
        if faults is None:
            faults = [
                (f.fault, f.trigger if f.active_since is None else NOW)
                for f in proxy.faults.values()
            ]
        if state is not None:
            faults = []
        build = AddMachine(
            proxy.id,
            proxy.name,
            proxy.cfg,
            epoch,
            state=state,
            faults=faults,
            exercise=proxy.exercise,
            mode=mode,
        )
        try:
            info = worker.call(build)
        except BaseException:
            self._built(proxy.id)
            raise
        assert isinstance(info, MachineInfo)
        proxy.attach(worker, info)
        if proxy.id in self._proxies:  # a new machine counts as building until it is listed
            self._built(proxy.id)
        if proxy.watchers:
            worker.post(Watch(proxy.id, True))

    def _built(self, mid: str) -> None:
        with self._placing:
            self._building.pop(mid, None)

    def load(self, create_demo: bool) -> None:
        """Bring back every stored machine; a fresh store gets the demo lathe."""
        stored = self.store.machines()
        if not stored and create_demo:
            sm = StoredMachine("demo", "Demo lathe", "demo")
            self.store.add_machine(sm)
            stored = [sm]
        for sm in stored:
            proxy = MachineProxy(sm, self._config(sm))
            proxy.exercise, faults = self.seats.get(sm.id, (None, None))
            self._place(proxy, faults=faults)
            self._proxies[sm.id] = proxy
            self._built(sm.id)

    def create(
        self,
        req: MachineCreate,
        values: Values | None = None,
        faults: list[tuple[Fault, Trigger]] | None = None,
        exercise: object | None = None,
    ) -> MachineProxy:
        """A new machine placed on a worker; a class's seat gets its exercise's starting
        `values` (written into its lists: the caller stores them), `faults` and checks."""
        if req.id in self._proxies:
            raise Conflict(f"machine '{req.id}' exists")
        sm = StoredMachine(
            req.id,
            req.name or req.id,
            "demo" if req.demo else "lists",
            req.channel_list,
            req.axis_lists,
            req.tool_list,
        )
        try:
            cfg = self._config(sm)
        except (ParamListError, NcUsageError) as e:
            raise lists_rejected(e) from None
        try:
            apply_values(cfg, values or [])
        except NcUsageError as e:
            raise Invalid(str(e)) from None
        proxy = MachineProxy(sm, cfg)
        proxy.exercise = exercise
        try:
            self._place(proxy, faults=faults)
        except (WorkerGone, WorkerRefused) as e:
            raise Unavailable(f"no worker could build the machine: {e}") from None
        self.store.add_machine(sm)
        with self._lock:
            self._proxies[sm.id] = proxy
        self._built(sm.id)
        return proxy

    def restart(self, mid: str) -> MachineProxy:
        """Power the machine off and on: all stored values apply, pending ones included."""
        proxy = self.get(mid)
        sm = next(s for s in self.store.machines() if s.id == mid)
        with proxy.lock:
            proxy.cfg = self._config(sm)
            proxy.pending.clear()
            worker = proxy.worker if proxy.worker is not None and proxy.worker.alive else None
            try:
                self._place(proxy, worker)
            except (WorkerGone, WorkerRefused) as e:
                raise Unavailable(f"machine '{mid}': {e}") from None
        return proxy

    def restore(self, mid: str, state: bytes, params: ParamSnapshot) -> MachineProxy:
        """Rebuild the machine from a snapshot (a new epoch continuing at the snapshot's
        cycle); `params` are its lists then, which the gateway's copy takes over."""
        proxy = self.get(mid)
        with proxy.lock:
            for (scope, target), values in params.items():
                lists = proxy.cfg.list_values(Scope(scope), target)
                lists.clear()
                lists.update(values)
            proxy.pending.clear()
            worker = proxy.worker if proxy.worker is not None and proxy.worker.alive else None
            mode = proxy.pacing.mode if proxy.pacing is not None else "run"
            try:
                self._place(proxy, worker, state, mode=mode)
            except (WorkerGone, WorkerRefused) as e:
                raise Unavailable(f"machine '{mid}': {e}") from None
        return proxy

    def delete(self, mid: str) -> None:
        proxy = self.get(mid)
        with self._lock:
            del self._proxies[mid]
        proxy.deleted = True
        if proxy.worker is not None and proxy.worker.alive:
            with contextlib.suppress(WorkerGone, WorkerRefused):  # gone with its worker
                proxy.worker.call(RemoveMachine(mid))
        self.store.delete_machine(mid)

    # --- worker events ----------------------------------------------------------------------
    def on_push(self, worker: WorkerClient, push: Push) -> None:
        if isinstance(push, MachineNews | MachineSamples):
            building = self._building.get(push.mid)
            proxy = self._proxies.get(push.mid) or (building[0] if building else None)
            if proxy is not None and (proxy.worker is worker or push.epoch > proxy.epoch):
                proxy.take(push)
        elif isinstance(push, WorkerNews):
            worker.latest = push
            for mid, pacing in push.pacing.items():
                proxy = self._proxies.get(mid)
                if proxy is not None and proxy.worker is worker:
                    proxy.pacing = pacing

    def on_death(self, worker: WorkerClient) -> None:
        """Rebuild the dead worker's machines on live workers (on a thread: the calls wait
        for replies, which the event loop reading them must stay free to deliver)."""
        threading.Thread(
            target=self._rebuild_from, args=(worker,), name="rebuild", daemon=True
        ).start()

    def _rebuild_from(self, dead: WorkerClient) -> None:
        lost = self.on_machine(dead)
        self.pool.replace(dead)  # first: the lost machines go to the least loaded, it among them
        why = f"its worker {dead.id} (pid {dead.pid}, node {dead.node}) stopped"
        for proxy in lost:
            if proxy.deleted:
                continue
            sm = next((s for s in self.store.machines() if s.id == proxy.id), None)
            if sm is None:
                continue
            try:
                with proxy.lock:
                    proxy.cfg = self._config(sm)
                    proxy.pending.clear()
                    self._place(proxy)
            except Exception:
                log.exception("machine %s could not be rebuilt", proxy.id)
                continue
            self.rebuilt += 1
            proxy.notice(
                "rebuilt",
                f"machine {proxy.id} was rebuilt from its stored parameters: {why}. It "
                "starts as after power-on: simulated time from 0, axes at their start "
                "positions, spindle stopped, earlier events and pending values gone",
            )


def lists_rejected(e: ParamListError | NcUsageError) -> ApiError:
    """The 422 of parameter lists a machine cannot be built from: each problem with its
    parameter and line."""
    if isinstance(e, NcUsageError):
        return Invalid(str(e))
    return Invalid(
        {
            "message": f"parameter list rejected: {e}",
            "problems": [
                {"parameter": p.name, "line": p.line, "message": p.detail} for p in e.errors
            ],
        }
    )
