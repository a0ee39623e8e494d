"""Continuous recording: chosen signals of a machine, every cycle, into a Rerun .rrd file.

A recorder reads the machine's sample ring behind a cursor (like a telemetry subscriber) and one
thread writes every recorder's new cycles every `period_s`; the worker's loop never waits
for it. A power cycle of the machine ends
its recording (simulated time starts again at zero), and so does deleting the machine.

All files in the recordings folder together may take `quota_mb`: no recording starts when it
is used up (507), and the running ones stop when they reach it (`stopped_reason` says so).
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from api.scope import RecordingInfo
from backend.errors import Conflict, Invalid, QuotaUsedUp, not_found
from backend.services.machines import MachineProxy
from nc_sim.events import Event

if TYPE_CHECKING:  # Rerun loads only when a recording starts (it adds 0.4 s to every start)
    from backend.services import rrd

log = logging.getLogger(__name__)

QUOTA_MB = 2048.0  # the default disk quota of all recordings together
MB = 1_000_000


@dataclass
class Recording:
    id: str
    machine: MachineProxy
    signals: list[str]
    path: Path
    writer: rrd.RrdWriter
    epoch: int
    first_cycle: int
    cursor: int  # next cycle to write
    started_unix: float
    active: bool = True
    stopped_reason: str = ""  # why it ended ('' while it runs)
    skipped: int = 0  # cycles lost because the writer fell a whole ring behind
    events_from: int = 0
    lock: threading.Lock = field(default_factory=threading.Lock)

    def info(self) -> RecordingInfo:
        return RecordingInfo(
            id=self.id,
            machine=self.machine.id,
            signals=self.signals,
            active=self.active,
            first_cycle=self.first_cycle,
            cycles=self.cursor - self.first_cycle,
            bytes=self.path.stat().st_size if self.path.exists() else 0,
            skipped_cycles=self.skipped,
            started_unix=self.started_unix,
            stopped_reason=self.stopped_reason,
        )

    def pump(self) -> None:
        """Write the cycles stepped since the last pump."""
        with self.lock:
            if not self.active:
                return
            m = self.machine
            sigs = [m.link.signal_by_name[n] for n in self.signals]
            ended = m.deleted or m.link.epoch != self.epoch
            if ended:
                head, data, start = self.cursor - 1, None, self.cursor
                events: list[Event] = []
            else:
                head = m.link.cycle
                data, start = (None, self.cursor)
                if head >= self.cursor:
                    data, start = m.link.samples(sigs, self.cursor, head, 1)
                events, _, self.events_from, _ = m.link.events_since(self.events_from)
            if data is not None:
                self.skipped += start - self.cursor
                self.writer.block(start, data)
            self.writer.events(events)
            self.cursor = head + 1
            if ended:
                why = "the machine was deleted" if m.deleted else "the machine was power cycled"
                self._close(why)

    def stop(self, reason: str) -> None:
        """Write what is left and end the recording, saying why."""
        self.pump()
        with self.lock:
            self._close(reason)

    def _close(self, reason: str) -> None:
        if self.active:
            self.active = False
            self.stopped_reason = reason
            from backend.services import rrd

            rrd.close_stream(self.writer.stream)


class Recorders:
    """Every continuous recording of the service, written by one thread."""

    def __init__(self, directory: Path, quota_mb: float = QUOTA_MB, period_s: float = 0.25) -> None:
        self.dir = directory
        self.dir.mkdir(parents=True, exist_ok=True)
        self.quota_mb = quota_mb
        self.period_s = period_s
        self.all: dict[str, Recording] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="recorders", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        for r in list(self.all.values()):
            r.stop("the service stopped")

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            self.pump()

    def pump(self) -> None:
        """Write every active recording; one that fails is logged and ended, the others go on.
        When the recordings reach their quota, the running ones stop."""
        for r in list(self.all.values()):
            try:
                r.pump()
            except Exception:
                log.exception("recording %s failed; ending it", r.id)
                with r.lock, contextlib.suppress(Exception):  # the stream may be what failed
                    r._close("writing it failed (see the service log)")
                r.active = False
        running = [r for r in self.all.values() if r.active]
        if running and self.used_mb() >= self.quota_mb:
            for r in running:
                r.stop(f"the recordings' disk quota of {self.quota_mb:g} MB is used up")

    def used_mb(self) -> float:
        """What every file in the recordings folder takes together."""
        total = 0
        for f in self.dir.rglob("*"):
            with contextlib.suppress(OSError):  # removed meanwhile
                total += f.stat().st_size if f.is_file() else 0
        return total / MB

    def begin(self, m: MachineProxy, signals: list[str]) -> RecordingInfo:
        """Start recording from the next cycle; 409 when the machine already records."""
        bad = [n for n in signals if n not in m.link.signal_by_name]
        if bad:
            raise Invalid(f"recording: unknown signals {bad}")
        if self.active(m.id) is not None:
            raise Conflict(f"{m.id} is already recording: stop it first")
        used = self.used_mb()
        if used >= self.quota_mb:
            why = (
                f"recordings use {used:.1f} MB of their {self.quota_mb:g} MB disk quota: "
                f"remove some from {self.dir}"
            )
            raise QuotaUsedUp(why)
        rid = uuid.uuid4().hex[:12]
        path = self.dir / f"{rid}.rrd"
        about = f"# continuous recording of {m.name} ({m.id})\n- signals: " + ", ".join(signals)
        from backend.services import rrd

        stream = rrd.open_stream(path, rid, m.id, about, signals)
        first = m.link.cycle + 1
        rec = Recording(
            rid,
            m,
            list(signals),
            path,
            rrd.RrdWriter(stream, m.id, signals, m.link.cycle_s),
            m.link.epoch,
            first,
            first,
            time.time(),
            events_from=m.link.events.cursor,
        )
        self.all[rid] = rec
        return rec.info()

    def active(self, mid: str) -> Recording | None:
        return next((r for r in self.all.values() if r.machine.id == mid and r.active), None)

    def info(self, mid: str) -> RecordingInfo | None:
        """The machine's running recording, else its newest finished one."""
        mine = [r for r in self.all.values() if r.machine.id == mid]
        act = [r for r in mine if r.active]
        pick = act[0] if act else (mine[-1] if mine else None)
        return pick.info() if pick else None

    def end(self, mid: str) -> RecordingInfo:
        rec = self.active(mid)
        if rec is None:
            raise Conflict(f"{mid} is not recording")
        rec.stop("stopped on request")
        return rec.info()

    def path(self, rid: str, seat: str | None = None) -> Path:
        """The recording's .rrd file (written up to now); 404 for none, and for a class's
        student (`seat`: their seat's machine) one of another machine."""
        rec = self.all.get(rid)
        if rec is None or (seat is not None and rec.machine.id != seat):
            raise not_found(f"recording {rid}")
        if rec.active:
            rec.pump()
            rec.writer.stream.flush()
        return rec.path
