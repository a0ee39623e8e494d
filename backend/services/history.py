"""A machine's history: one timeline, kept in the store, of what happened to it and who did it.

Two tables make it. The machine log (machine_log.py) holds what the NC and the service
report: job errors (each put down to the command whose block raised it, where one did), the
blocks a job error dropped, resets clearing errors, information events, power-ons (built,
restarted, rebuilt after a worker died, restored), service starts and stops, notes and
acknowledgements. The audit trail (audit.py) holds what people did: commands with their
outcome, parameter, version and control changes. A page of the history reads both, merged by
wall clock; every row has its wall clock, the machine's simulated time and build, and actor.

The machine log is written by a thread of its own in batches (events come in bursts from the
workers' push threads, which never wait for the disk) and pruned to its retention, days and
rows per machine; the audit trail keeps its rows for ever. Viewers get the new entries of
both live from a bounded tail per machine (the telemetry hub reads it by cursor).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections import OrderedDict, deque
from dataclasses import dataclass, field, replace

from api.history import HistoryEntry, HistoryKind, Severity
from api.scope import TraceDetail
from backend import VERSION
from backend.errors import Conflict
from backend.services import machine_log
from backend.services.audit_log import Entry
from backend.services.machine_log import HistoryFilter, LogRow, audit_entry
from backend.services.machines import MachineProxy, MachineService
from backend.services.store import Store
from nc_sim.errors import Code
from nc_sim.events import Event

log = logging.getLogger(__name__)

TAIL = 256  # live entries kept per machine for viewers that fall behind
BATCH_S = 0.1  # the writer gathers a burst this long
PRUNE_EVERY_S = 60.0
SENT_KEPT = 256  # MDI blocks per machine whose sender is remembered (to attribute errors)


@dataclass
class _Machine:
    """What the history remembers of one machine to write its rows."""

    tail: deque[tuple[int, HistoryEntry]] = field(default_factory=lambda: deque(maxlen=TAIL))
    tail_seq: int = 0
    sent: OrderedDict[tuple[int, int], tuple[str, str]] = field(default_factory=OrderedDict)
    # the newest command per axis ('' the channel's): (epoch, text, actor)
    last_command: dict[str, tuple[int, str, str]] = field(default_factory=dict)
    last_actor: str = ""  # who sent the newest channel command (a reset clears errors)
    active: list[str] = field(default_factory=list)  # job errors in force, as "90017 S1"
    errors: OrderedDict[int, int] = field(default_factory=OrderedDict)  # seq → code, newest


class History:
    """Writing, reading and exporting machines' histories."""

    def __init__(self, store: Store, days: float, rows_per_machine: int) -> None:
        self.store = store
        self.days, self.rows_per_machine = days, rows_per_machine
        store.script(machine_log.SCHEMA)
        store.on_audited = self._audited
        self._machines: dict[str, _Machine] = {}
        self._lock = threading.Lock()
        self._queue: queue.Queue[LogRow | None] = queue.Queue()
        self._pruned = 0.0
        self._writer = threading.Thread(target=self._write, name="history-writer", daemon=True)
        self._writer.start()

    def attach(self, machines: MachineService) -> None:
        """Take every machine's events and power-ons, and stamp its audit rows with its
        simulated time."""
        machines.event_takers.append(self.events)
        machines.on_deleted.append(self.forget)
        machines.last_epoch = self.last_epoch
        machines.on_power = self._powered
        self.store.clock = machines.stamp

    def _powered(self, proxy: MachineProxy, epoch: int, why: str, failure: bool) -> None:
        self.power_on(proxy.id, epoch, why, "warning" if failure else "info")

    def service_started(self, proxies: list[MachineProxy]) -> None:
        """Mark the start in every machine's history, and tell its viewers that reconnect."""
        when = time.strftime("%H:%M:%S UTC", time.gmtime())
        ran = {r["machine"] for r in self.store.query("SELECT DISTINCT machine FROM machine_log")}
        for p in proxies:
            self.add(LogRow(p.id, "service", "warning", f"service started (Inbetrieb {VERSION})"))
            if p.id not in ran:  # its first start: nothing to announce
                continue
            p.notices.add(
                "restarted",
                f"the service restarted at {when}: machine {p.name} was powered on again "
                "(simulated time from 0, axes at their start positions, spindle stopped); its "
                "history kept everything before",
            )

    def service_stopping(self, proxies: list[MachineProxy]) -> None:
        """Mark the stop in every machine's history (written before the store closes)."""
        for p in proxies:
            self.add(_now_on(p, "service", "warning", "service stopping"))
        self.flush()

    def _of(self, mid: str) -> _Machine:
        m = self._machines.get(mid)
        if m is None:
            m = self._machines[mid] = _Machine()
        return m

    # --- what happened --------------------------------------------------------------------
    def add(self, row: LogRow) -> None:
        """Write a row soon (in order, without waiting for the disk)."""
        self._queue.put(row)

    def sending(self, mid: str, epoch: int, text: str, actor: str, axis: str) -> None:
        """A command goes to the machine (before its answer: a job error it raises may come
        first): job errors of that axis ('' the channel's) are put down to it until the next."""
        with self._lock:
            m = self._of(mid)
            m.last_command[axis] = (epoch, text, actor)
            if axis == "":
                m.last_actor = actor

    def sent(self, mid: str, epoch: int, text: str, actor: str, block: int) -> None:
        """An MDI block was accepted: its sender is remembered for the job errors the block
        may raise later."""
        with self._lock:
            m = self._of(mid)
            m.sent[(epoch, block)] = (text, actor)
            while len(m.sent) > SENT_KEPT:
                m.sent.popitem(last=False)

    def events(self, mid: str, epoch: int, events: list[Event]) -> None:
        """New events of a machine as its worker pushed them (any thread)."""
        dropped: dict[int, Event] = {}  # a job error's seq → the block it dropped first
        for e in events:
            if e.code == Code.EV_BLOCK_DROPPED and e.value is not None:
                dropped.setdefault(int(e.value), e)
        with self._lock:
            m = self._of(mid)
            rows = [self._row(mid, epoch, m, e, dropped) for e in events]
        for row in rows:
            self._queue.put(row)

    def _row(
        self, mid: str, epoch: int, m: _Machine, e: Event, dropped: dict[int, Event]
    ) -> LogRow:
        row = LogRow(
            mid, "event", "info", e.message, sim_t_s=e.t_s, epoch=epoch, code=e.code, axis=e.axis
        )
        if e.error:
            m.active.append(f"{e.code} {e.axis}".strip())
            m.errors[e.seq] = e.code
            while len(m.errors) > SENT_KEPT:
                m.errors.popitem(last=False)
            block = dropped.get(e.seq)
            sender = m.sent.get((epoch, block.block)) if block and block.block else None
            cause = None
            if sender is not None:
                cause = f"raised by MDI block '{sender[0]}' sent by {sender[1]}"
            elif (last := m.last_command.get(e.axis) or m.last_command.get("")) and (
                last[0] == epoch
            ):  # the axis's last command, else the channel's (an MDI block, a program)
                cause = f"after '{last[1]}' sent by {last[2]}"
            return replace(row, kind="job_error", severity="error", cause=cause)
        if e.code == Code.EV_BLOCK_DROPPED:
            text, actor = m.sent.get((epoch, e.block or 0), (e.message, ""))
            code = m.errors.get(int(e.value)) if e.value is not None else None
            why = f"dropped by job error {code}" if code else "dropped by a job error"
            return replace(
                row,
                kind="command",
                severity="error",
                text=f"MDI {text}",
                actor=actor,
                outcome=why,
                code=None,  # the event's own number says nothing here: the outcome does
            )
        if e.code == Code.EV_RESET and m.active:
            cleared, m.active = ", ".join(m.active), []
            actor = m.last_actor
            return replace(row, kind="cleared", text=f"reset cleared {cleared}", actor=actor)
        return row

    def power_on(self, mid: str, epoch: int, why: str, severity: Severity = "info") -> None:
        """The machine was built (a power-on): time starts at 0, errors are gone."""
        with self._lock:
            m = self._of(mid)
            m.active, m.last_actor = [], ""
            m.last_command.clear()
            m.sent.clear()
            m.errors.clear()
        self.add(LogRow(mid, "power", severity, f"powered on: {why}", sim_t_s=0.0, epoch=epoch))

    def note(self, machine: MachineProxy, actor: str, text: str) -> HistoryEntry:
        """A logbook entry, written now (at the machine's time now)."""
        return self._now(_now_on(machine, "note", "info", text, actor))

    def acknowledge(self, machine: MachineProxy, actor: str) -> HistoryEntry:
        """`actor` saw the job errors in force (they stay in force until a reset)."""
        with self._lock:
            active = list(self._of(machine.id).active)
        if not active:
            raise Conflict("no job error is in force")
        text = f"acknowledged {', '.join(active)}"
        return self._now(_now_on(machine, "acknowledged", "info", text, actor))

    def _now(self, row: LogRow) -> HistoryEntry:
        self.flush()  # what came before it is written first
        return self._insert([row])[0]

    def _insert(self, rows: list[LogRow]) -> list[HistoryEntry]:
        entries = machine_log.insert(self.store, rows)
        with self._lock:
            for e, r in zip(entries, rows, strict=True):
                self._push(r.machine, e)
        return entries

    def prune(self) -> int:
        """End rows past the retention (days, rows per machine); how many."""
        self._pruned = time.monotonic()
        return machine_log.prune(self.store, self.days, self.rows_per_machine)

    def link_trace(self, mid: str, epoch: int, errors: list[Event], trace: str) -> None:
        """The flight recorder saved `trace` around these job errors: their entries link to
        it (viewers get them again, with the link)."""
        self.flush()
        entries = machine_log.link_trace(self.store, mid, epoch, errors, trace)
        with self._lock:
            for e in entries:
                self._push(mid, e)

    def flight_failed(self, machine: MachineProxy, error: Event, why: str) -> None:
        """The flight recorder could not save the window of a job error."""
        text = f"flight recorder: the seconds around job error {error.code} were not saved: {why}"
        self.add(_now_on(machine, "service", "warning", text))

    def forget(self, mid: str) -> None:
        """A deleted machine: nothing more is remembered about it (its rows stay until the
        retention ends them)."""
        with self._lock:
            self._machines.pop(mid, None)

    # --- live ------------------------------------------------------------------------------
    def _audited(self, written: list[tuple[int, Entry]]) -> None:
        clock = self.store.clock
        with self._lock:
            for seq, e in written:
                if e.machine:
                    stamp = e.stamp or (clock(e.machine) if clock is not None else None)
                    self._push(e.machine, audit_entry(seq, e, stamp))

    def _push(self, mid: str, entry: HistoryEntry) -> None:
        m = self._of(mid)
        m.tail_seq += 1
        m.tail.append((m.tail_seq, entry))

    def newest(self, mid: str) -> int:
        """The live cursor now (a viewer that connects sees what comes after)."""
        with self._lock:
            return self._of(mid).tail_seq

    def since(self, mid: str, cursor: int) -> tuple[list[HistoryEntry], int]:
        """The live entries after `cursor`, oldest first, and the next cursor."""
        with self._lock:
            m = self._of(mid)
            if m.tail_seq <= cursor:  # nothing new: every viewer asks every frame
                return [], m.tail_seq
            return [e for s, e in m.tail if s > cursor], m.tail_seq

    # --- reading ---------------------------------------------------------------------------
    # --- reading ---------------------------------------------------------------------------
    def page(
        self, mid: str, f: HistoryFilter, limit: int = 200, before: tuple[float, str] | None = None
    ) -> tuple[list[HistoryEntry], int]:
        """Matching entries of the machine's whole history, newest first (older ones:
        `before` = (time, id) of the last one seen), and how many match in all."""
        self.flush()
        return machine_log.page(self.store, mid, f, limit, before)

    def alarms(self, machines: list[str], limit: int) -> list[tuple[str, HistoryEntry]]:
        """The newest job errors of these machines, newest first, with their machine."""
        self.flush()
        return machine_log.alarms(self.store, machines, limit)

    def notes_in(self, d: TraceDetail) -> list[tuple[float, str]]:
        """The notes written on a trace's machine while it was recorded (sim_time, text)."""
        return machine_log.notes_in(self.store, d)

    def last_epoch(self, mid: str) -> int:
        """The machine's newest build in its history (0 for none)."""
        return machine_log.last_epoch(self.store, mid)

    def active(self, mid: str) -> list[str]:
        """The machine's job errors in force (since its last reset or power-on)."""
        with self._lock:
            return list(self._of(mid).active)

    # --- writing ---------------------------------------------------------------------------
    def flush(self) -> None:
        """Wait until every row given so far is written."""
        self._queue.join()

    def stop(self) -> None:
        self._queue.put(None)
        self._writer.join(timeout=5.0)

    def _write(self) -> None:
        while True:
            batch = [self._queue.get()]
            if batch[0] is not None:
                time.sleep(BATCH_S)
            while not self._queue.empty() and len(batch) < 2000:
                batch.append(self._queue.get_nowait())
            rows = [r for r in batch if r is not None]
            try:
                if rows:
                    self._insert(rows)
                if time.monotonic() - self._pruned > PRUNE_EVERY_S:
                    self.prune()
            except Exception:  # the store is closed or failing: say so, keep serving
                log.exception("history rows lost: %d", len(rows))
            finally:
                for _ in batch:
                    self._queue.task_done()
            if None in batch:
                return


def _now_on(
    machine: MachineProxy, kind: HistoryKind, severity: Severity, text: str, actor: str = ""
) -> LogRow:
    """A row stamped with the machine's simulated time and build now."""
    sim_t_s = machine.link.cycle * machine.link.cycle_s
    return LogRow(machine.id, kind, severity, text, actor, sim_t_s, machine.link.epoch)
