"""The machines of the service as the gateway knows them: identity and parameter lists (kept in
SQLite), which worker runs each, and what that worker last pushed.

A machine runs on exactly one worker. When a worker dies a replacement is started, then its
machines are rebuilt from their stored parameters on the least loaded live workers, the
replacement among them (a power cycle: cycle 0, new epoch), and their viewers are told;
machines on other workers never notice.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable

from api.machines import MachineCreate
from backend.errors import ApiError, Conflict, Invalid, Unavailable, not_found
from backend.services.captures import Captures
from backend.services.control import MachineControl
from backend.services.jog_leases import JogLeases
from backend.services.notices import Notices
from backend.services.pending import PendingValues
from backend.services.store import Store, StoredMachine
from backend.workers.client import WorkerClient, WorkerGone, WorkerRefused
from backend.workers.flight import FlightWindow
from backend.workers.link import EventsTaken, FlightsTaken, MachineLink
from backend.workers.pool import NoLiveWorker, WorkerPool
from backend.workers.protocol import (
    AddMachine,
    MachineInfo,
    MachineNews,
    MachineSamples,
    Mode,
    ParamSnapshot,
    Push,
    RemoveMachine,
    Values,
    Watch,
    WorkerNews,
)
from nc_sim.config import MachineConfig, apply_values, demo_machine, machine_from_lists
from nc_sim.errors import NcUsageError
from nc_sim.events import Event
from nc_sim.faults import NOW, Fault, Trigger
from nc_sim.params import ParamListError, Scope

log = logging.getLogger(__name__)

# a machine was powered on: (machine, its new epoch, why, a failure did it); the history
# marks it
PoweredOn = Callable[["MachineProxy", int, str, bool], None]


class MachineProxy:
    """One machine in the gateway: its identity and the parameter lists it runs with (the
    gateway's copy), its worker link, and what the gateway keeps about it besides, each a
    concern of its own. Request threads share it: `lock` guards the lists and the pending
    values."""

    def __init__(self, sm: StoredMachine, cfg: MachineConfig) -> None:
        self.id = sm.id
        self.name = sm.name
        self.source = sm.source
        self.cfg = cfg  # the written lists the worker runs with (the gateway's copy)
        self.lock = threading.RLock()
        self.captures = Captures()  # the scope's setup and completed records
        self.link = MachineLink(sm.id, cfg.cycle_s, self.captures.add)
        self.pending = PendingValues()  # values waiting for reset or restart
        self.jogs = JogLeases()  # held jogs, for the audit
        self.notices = Notices()  # banners for every viewer
        self.control = MachineControl()  # who holds it (backend/services/control.py)
        self.exercise: object | None = None  # a class seat's checks: go with every rebuild
        self.deleted = False  # telemetry closes its subscribers
        self.last_command: dict[str, float] = {}  # user → wall time of their last command
        self.since_unix = time.time()  # this gateway has known it since (its last_command)


class MachineService:
    """Owns the proxies; places machines on workers and rebuilds them when a worker dies."""

    def __init__(
        self, store: Store, pool: WorkerPool, flight_s: tuple[float, float] | None = None
    ) -> None:
        """`flight_s`: the seconds before and after each job error that every machine's
        worker copies for the flight recorder (None: none)."""
        self.store = store
        self.pool = pool
        self.flight_s = flight_s
        self._proxies: dict[str, MachineProxy] = {}
        # machines being built and where: their pushes may come before the reply, and they
        # count as load, so machines created at once spread over the workers
        self._building: dict[str, tuple[MachineProxy, WorkerClient]] = {}
        self._placing = threading.Lock()
        self._lock = threading.Lock()
        self.rebuilt = 0  # machines rebuilt after their worker died
        # class seats' exercises and starting faults, by machine: `load` builds them so
        self.seats: dict[str, tuple[object, list[tuple[Fault, Trigger]]]] = {}
        self.on_power: PoweredOn | None = None  # the history: every build is a power-on
        # the history, the flight recorder: every machine's new events (a push thread's)
        self.event_takers: list[EventsTaken] = []
        self.on_flights: FlightsTaken | None = None  # the flight recorder: job error windows
        self.on_deleted: list[Callable[[str], None]] = []  # what keeps something per machine
        # a machine's training faults as they stood before the service stopped (None: none
        # kept, a seat starts with its exercise's)
        self.kept_faults: Callable[[str], list[tuple[Fault, Trigger]] | None] = lambda mid: None
        # the newest build of a machine before this start (the history knows it)
        self.last_epoch: Callable[[str], int] = lambda mid: 0

    def proxies(self) -> list[MachineProxy]:
        with self._lock:
            return list(self._proxies.values())

    def get(self, mid: str) -> MachineProxy:
        proxy = self._proxies.get(mid)
        if proxy is None:
            raise not_found(f"machine '{mid}'")
        return proxy

    def _took_events(self, mid: str, epoch: int, events: list[Event]) -> None:
        for take in self.event_takers:
            take(mid, epoch, events)

    def _took_flights(self, mid: str, epoch: int, windows: list[FlightWindow]) -> None:
        if self.on_flights is not None:
            self.on_flights(mid, epoch, windows)

    def building(self, mid: str) -> bool:
        """The machine is being built (placed, or rebuilt after its worker died)."""
        return mid in self._building

    def find(self, mid: str) -> MachineProxy | None:
        """The machine, or None (deleted, or never there)."""
        return self._proxies.get(mid)

    def stamp(self, mid: str) -> tuple[int, float] | None:
        """A machine's build and simulated time now (None: no such machine)."""
        proxy = self._proxies.get(mid)
        if proxy is None:
            return None
        return proxy.link.epoch, proxy.link.cycle * proxy.link.cycle_s

    def on_machine(self, worker: WorkerClient) -> list[MachineProxy]:
        return [p for p in self.proxies() if p.link.worker is worker]

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
        why: str,
        worker: WorkerClient | None = None,
        state: bytes | None = None,
        faults: list[tuple[Fault, Trigger]] | None = None,
        mode: Mode = "run",
        failure: bool = False,
    ) -> None:
        """Build the machine on a worker (the least loaded live one unless given): powered on
        with its training faults as they stand (an armed one armed again, an active one at
        once), or restored from a snapshot's `state` (faults and all); `why` goes into its
        history."""
        with self._placing:
            try:
                worker = worker or self.pool.choose(self._load)
            except NoLiveWorker as e:
                raise Unavailable(str(e)) from None
            self._building[proxy.id] = (proxy, worker)
        epoch = proxy.link.epoch + 1
        if faults is None:
            faults = [
                (f.fault, f.trigger if f.active_since is None else NOW)
                for f in proxy.link.faults.values()
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
            flight_s=self.flight_s,
        )
        try:
            info = worker.call(build)
        except BaseException:
            self._built(proxy.id)
            raise
        assert isinstance(info, MachineInfo)
        if self.on_power is not None:  # first: the build's own first events come after it
            self.on_power(proxy, info.epoch, why, failure)
        proxy.link.on_events = self._took_events
        proxy.link.on_flights = self._took_flights
        with self._placing:  # a death handler sees it attached, or this sees the death
            if not worker.alive:
                self._building.pop(proxy.id, None)
                raise WorkerGone(f"worker {worker.id} stopped as it built machine {proxy.id}")
            proxy.link.attach(worker, info)
        if proxy.id in self._proxies:  # a new machine counts as building until it is listed
            self._built(proxy.id)
        if proxy.link.watchers:
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
            proxy.link.epoch = self.last_epoch(sm.id)  # its builds count on across restarts
            proxy.exercise, faults = self.seats.get(sm.id, (None, None))
            kept = self.kept_faults(sm.id)
            self._place(proxy, "the service started", faults=faults if kept is None else kept)
            self._proxies[sm.id] = proxy
            self._built(sm.id)

    def create(
        self,
        req: MachineCreate,
        values: Values | None = None,
        faults: list[tuple[Fault, Trigger]] | None = None,
        exercise: object | None = None,
        mode: Mode = "run",
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
            self._place(proxy, "created", faults=faults, mode=mode)
        except (WorkerGone, WorkerRefused) as e:
            raise Unavailable(f"no worker could build the machine: {e}") from None
        self.store.add_machine(sm)
        with self._lock:
            self._proxies[sm.id] = proxy
        self._built(sm.id)
        return proxy

    def restart(self, mid: str, by: str) -> MachineProxy:
        """Power the machine off and on: all stored values apply, pending ones included."""
        proxy = self.get(mid)
        sm = next(s for s in self.store.machines() if s.id == mid)
        with proxy.lock:
            proxy.cfg = self._config(sm)
            proxy.pending.clear()
            try:
                self._place(proxy, f"power cycle by {by}", proxy.link.live_worker)
            except (WorkerGone, WorkerRefused) as e:
                raise Unavailable(f"machine '{mid}': {e}") from None
        return proxy

    def restage(
        self,
        mid: str,
        exercise: object,
        faults: list[tuple[Fault, Trigger]],
        why: str,
        mode: Mode,
    ) -> MachineProxy:
        """Power the machine on afresh for another exercise: its stored values (the caller
        wrote the exercise's start), these faults and checks, simulated time from 0."""
        proxy = self.get(mid)
        sm = next(s for s in self.store.machines() if s.id == mid)
        with proxy.lock:
            proxy.cfg = self._config(sm)
            proxy.pending.clear()
            proxy.exercise = exercise
            self.seats[mid] = (exercise, faults)
            try:
                self._place(proxy, why, proxy.link.live_worker, faults=faults, mode=mode)
            except (WorkerGone, WorkerRefused) as e:
                raise Unavailable(f"machine '{mid}': {e}") from None
        return proxy

    def restore(self, mid: str, state: bytes, params: ParamSnapshot, by: str) -> MachineProxy:
        """Rebuild the machine from a snapshot (a new epoch continuing at the snapshot's
        cycle); `params` are its lists then, which the gateway's copy takes over."""
        proxy = self.get(mid)
        with proxy.lock:
            for (scope, target), values in params.items():
                lists = proxy.cfg.list_values(Scope(scope), target)
                lists.clear()
                lists.update(values)
            proxy.pending.clear()
            mode = proxy.link.pacing.mode if proxy.link.pacing is not None else "run"
            try:
                why = f"restored from a snapshot by {by}"
                self._place(proxy, why, proxy.link.live_worker, state, mode=mode)
            except (WorkerGone, WorkerRefused) as e:
                raise Unavailable(f"machine '{mid}': {e}") from None
        return proxy

    def delete(self, mid: str) -> None:
        proxy = self.get(mid)
        with self._lock:
            del self._proxies[mid]
        proxy.deleted = True
        for forget in self.on_deleted:
            forget(mid)
        worker = proxy.link.live_worker
        if worker is not None:
            with contextlib.suppress(WorkerGone, WorkerRefused):  # gone with its worker
                worker.call(RemoveMachine(mid))
        self.store.delete_machine(mid)

    # --- worker events ----------------------------------------------------------------------
    def on_push(self, worker: WorkerClient, push: Push) -> None:
        if isinstance(push, MachineNews | MachineSamples):
            building = self._building.get(push.mid)
            proxy = self._proxies.get(push.mid) or (building[0] if building else None)
            if proxy is not None and (proxy.link.worker is worker or push.epoch > proxy.link.epoch):
                proxy.link.take(push)
        elif isinstance(push, WorkerNews):
            worker.latest = push
            for mid, pacing in push.pacing.items():
                proxy = self._proxies.get(mid)
                if proxy is not None and proxy.link.worker is worker:
                    proxy.link.pacing = pacing

    def on_death(self, worker: WorkerClient) -> None:
        """Rebuild the dead worker's machines on live workers (on a thread: the calls wait
        for replies, which the event loop reading them must stay free to deliver)."""
        threading.Thread(
            target=self._rebuild_from, args=(worker,), name="rebuild", daemon=True
        ).start()

    def _rebuild_from(self, dead: WorkerClient) -> None:
        if self.pool.stopping:  # a worker ending with the service: nothing to rebuild
            return
        with self._placing:  # a build that attaches to `dead` after this is placed again
            lost = self.on_machine(dead)
        self.pool.replace(dead)  # first: the lost machines go to the least loaded, it among them
        why = f"its worker {dead.id} (pid {dead.pid}, node {dead.node}) stopped"
        for proxy in lost:
            if proxy.deleted:
                continue
            sm = next((s for s in self.store.machines() if s.id == proxy.id), None)
            if sm is None:
                continue
            if not self._rebuild(proxy, sm, why):
                continue
            self.rebuilt += 1
            proxy.notices.add(
                "rebuilt",
                f"machine {proxy.id} was rebuilt from its stored parameters: {why}. It "
                "starts as after power-on: simulated time from 0, axes at their start "
                "positions, spindle stopped, earlier events and pending values gone",
            )

    def _rebuild(self, proxy: MachineProxy, sm: StoredMachine, why: str) -> bool:
        """Build a lost machine on a live worker; with none left (a Ray head restarting
        took every one), once the first successor runs. False if it could not be."""
        while True:
            try:
                with proxy.lock:
                    proxy.cfg = self._config(sm)
                    proxy.pending.clear()
                    self._place(proxy, f"rebuilt: {why}", failure=True)
                return True
            except WorkerGone as e:  # the worker chosen died too: the next live one
                if self.pool.stopping:
                    return False
                log.warning("machine %s is rebuilt once more: %s", proxy.id, e)
            except ApiError as e:  # no live worker (the service stops, or none could start)
                if self.pool.stopping:
                    return False
                if self.pool.alive():
                    log.warning("machine %s could not be rebuilt: %s", proxy.id, e)
                    return False
                log.warning("machine %s waits for a worker to be rebuilt on", proxy.id)
                if not self.pool.wait_for_live():
                    return False
            except Exception:
                log.exception("machine %s could not be rebuilt", proxy.id)
                return False


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
