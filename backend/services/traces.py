"""Traces: the recent captures of every machine and the library (SQLite rows + .npy files).

A capture stays in memory (the newest few per machine) until it is saved; then its samples go
to `<trace_dir>/<id>.npy` and its description to the `traces` table. Recordings in Rerun
format are made on demand and cached next to the samples.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from api.scope import (
    ChannelInfo,
    MeasurementsModel,
    ParamCompare,
    ParamValueAt,
    TraceCompare,
    TraceDetail,
    TraceInfo,
    TracePatch,
    TraceSave,
)
from api.telemetry import FrameHeader, encode_frame
from backend.errors import Conflict, Invalid, QuotaUsedUp, not_found
from backend.services.captures import Capture
from backend.services.commands import job_error_model
from backend.services.machines import MachineProxy, MachineService
from backend.services.recorder import MB
from backend.services.store import Store
from backend.workers.protocol import ParamSnapshot
from nc_sim.events import Event
from nc_sim.measure import measure
from nc_sim.params import ParamError, Scope
from nc_sim.params.listfile import resolve

log = logging.getLogger(__name__)


@dataclass
class Trace:
    """A trace's description and its samples (channels × count, one per cycle)."""

    detail: TraceDetail
    data: np.ndarray

    def times_s(self) -> np.ndarray:
        """Sample times relative to the trigger (to the first sample without one)."""
        d = self.detail
        ref = d.trigger_cycle if d.trigger_cycle is not None else d.first_cycle
        return (np.arange(d.count) + d.first_cycle - ref) * d.cycle_s

    def events(self) -> list[Event]:
        """The trace's events (seq -1 where a trace saved before events were numbered has
        none)."""
        return [
            Event(
                seq=-1 if e.seq is None else e.seq,
                cycle=e.cycle,
                t_s=e.t_s,
                axis=e.axis,
                code=e.code,
                message=e.message,
                m=e.m,
                gear=e.gear,
                line=e.line,
                column=e.column,
                signal=e.signal,
                value=e.value,
            )
            for e in self.detail.events
        ]


def param_diff(snapshot: ParamSnapshot) -> list[ParamValueAt]:
    """The written values that differ from the manuals' defaults."""
    out = []
    for (scope, target), values in snapshot.items():
        for name, value in sorted(values.items()):
            try:
                default = resolve(Scope(scope), name).default
            except ParamError:
                default = None
            if value != default:
                row = {"scope": scope, "target": target, "name": name}
                out.append(ParamValueAt(**row, value=value, default=default))
    return out


def _info(detail: TraceDetail) -> TraceInfo:
    return TraceInfo.model_validate(detail.model_dump(exclude={"params", "events"}))


class TraceService:
    """Finds traces by id wherever they are; saves, lists, renames, deletes, compares."""

    def __init__(
        self,
        store: Store,
        directory: Path,
        machines: MachineService,
        quota_mb: float = 4096.0,
        user_quota_mb: float = 1024.0,
    ) -> None:
        self.store = store
        self.dir = directory
        self.dir.mkdir(parents=True, exist_ok=True)
        self.machines = machines
        self.quota_mb = quota_mb  # the library's files together, derived ones included
        self.user_quota_mb = user_quota_mb  # one user's saved and imported traces
        self._lock = threading.Lock()
        self._cache: dict[str, Trace] = {}  # recent captures, converted once
        # the logbook's notes in a trace's time (sim_time s, text): set by the history
        self.notes_of: Callable[[TraceDetail], list[tuple[float, str]]] = lambda d: []

    # --- finding ----------------------------------------------------------------------------
    def _from_capture(self, m: MachineProxy, cap: Capture) -> Trace:
        with self._lock:
            hit = self._cache.get(cap.id)
            if hit is not None:
                return hit
        rec = cap.record
        params = param_diff(cap.params)
        detail = TraceDetail(
            id=cap.id,
            machine=m.id,
            machine_name=m.name,
            name="",
            notes="",
            source="capture",
            stored=False,
            trigger=rec.trigger,
            forced=rec.forced,
            created_unix=cap.created_unix,
            first_cycle=rec.first_cycle,
            trigger_cycle=rec.trigger_cycle,
            count=rec.count,
            cycle_s=rec.cycle_s,
            channels=[ChannelInfo(name=s.name, unit=s.unit, kind=s.kind) for s in rec.channels],
            params_changed=len(params),
            params=params,
            events=[job_error_model(e) for e in rec.events],
        )
        trace = Trace(detail, rec.data)
        with self._lock:
            self._cache[cap.id] = trace
            live = {c.id for p in self.machines.proxies() for c in p.captures.recent()}
            for k in [k for k in self._cache if k not in live]:
                del self._cache[k]
                (self.dir / "recent" / f"{k}.rrd").unlink(missing_ok=True)
        return trace

    def recent(self, m: MachineProxy) -> list[TraceInfo]:
        """The machine's recent captures, newest first."""
        caps = m.captures.recent()
        out = []
        for c in reversed(caps):
            info = _info(self._from_capture(m, c).detail)
            info.stored = self.store.trace(c.id) is not None  # the library is the one record
            out.append(info)
        return out

    def get(self, tid: str) -> Trace:
        """A recent capture or a stored trace; 404 when neither."""
        stored = self.store.trace(tid)
        if stored is not None:
            try:
                detail = TraceDetail.model_validate_json(stored.meta)
                data = np.load(self.dir / f"{tid}.npy")
            except (ValidationError, OSError, ValueError) as e:
                # a damaged row (an older version stored NaN) or lost samples: only deletable
                raise not_found(f"readable stored trace {tid} ({type(e).__name__})") from None
            detail.name, detail.notes = stored.name, stored.notes
            return Trace(detail, data)
        for m in self.machines.proxies():
            cap = m.captures.find(tid)
            if cap is not None:
                return self._from_capture(m, cap)
        raise not_found(f"trace {tid}")

    # --- the library ------------------------------------------------------------------------
    def library(self, machine: str | None = None) -> list[TraceInfo]:
        out = []
        for t in self.store.traces(machine):
            try:
                info = TraceInfo.model_validate_json(t.meta)
            except ValidationError as e:  # one damaged row must not hide the others
                log.warning("stored trace %s is not readable, left out: %s", t.id, e)
                continue
            info.name, info.notes = t.name, t.notes
            out.append(info)
        return out

    # --- the quota ----------------------------------------------------------------------------
    def used_mb(self, created_by: str | None = None) -> float:
        """Disk space of the stored traces' files, samples and Rerun recordings (of the one
        who saved or imported them, when given)."""
        total = 0
        for tid in self.store.trace_ids(created_by):
            for suffix in (".npy", ".rrd"):
                with contextlib.suppress(OSError):
                    total += (self.dir / f"{tid}{suffix}").stat().st_size
        return total / MB

    def _room_for(self, mb: float, by: str | None, what: str) -> None:
        """507 when storing `mb` more would pass the library's quota (or `by`'s)."""
        used = self.used_mb()
        if used + mb > self.quota_mb:
            why = (
                f"{what}: the trace library uses {used:.1f} MB of its {self.quota_mb:g} MB "
                f"(this needs {mb:.1f} MB more): delete traces first"
            )
            raise QuotaUsedUp(why)
        if by is None:
            return
        mine = self.used_mb(by)
        if mine + mb > self.user_quota_mb:
            why = (
                f"{what}: {by}'s traces use {mine:.1f} MB of their {self.user_quota_mb:g} MB "
                f"(this needs {mb:.1f} MB more): delete some first"
            )
            raise QuotaUsedUp(why)

    def add(self, trace: Trace, by: str) -> TraceInfo:
        """Store a trace (a capture being saved, or an import) for `by`, within the quotas:
        its samples durably on disk first, then its row, so a committed row never points at
        a missing or partial file."""
        d = trace.detail
        self._room_for(trace.data.nbytes / MB, by, f"storing trace {d.id}")
        d.stored = True
        meta = d.model_dump_json()  # name and notes: the columns are the live ones
        path = self.dir / f"{d.id}.npy"
        _write_durably(path, trace.data)
        try:
            self.store.add_trace(d.id, d.machine, d.created_unix, d.name, d.notes, meta, by)
        except BaseException:
            path.unlink(missing_ok=True)
            raise
        return _info(d)

    def save(self, tid: str, req: TraceSave, by: str) -> TraceInfo:
        trace = self.get(tid)
        if trace.detail.stored:
            raise Conflict(f"trace {tid} is already in the library")
        detail = trace.detail.model_copy(deep=True)
        detail.name = req.name or f"{detail.trigger or 'capture'} {detail.id[:6]}"
        detail.notes = req.notes
        return self.add(Trace(detail, trace.data), by)

    def patch(self, tid: str, req: TracePatch) -> TraceInfo:
        trace = self.get(tid)
        if not trace.detail.stored:
            raise Conflict(f"trace {tid} is not in the library: save it first")
        d = trace.detail
        name = d.name if req.name is None else req.name
        self.store.update_trace(tid, name, d.notes if req.notes is None else req.notes)
        return _info(self.get(tid).detail)

    def delete(self, tid: str) -> None:
        if not self.store.delete_trace(tid):
            raise not_found(f"stored trace {tid}")
        for suffix in (".npy", ".rrd"):
            (self.dir / f"{tid}{suffix}").unlink(missing_ok=True)

    def compare(self, a: str, b: str) -> TraceCompare:
        ta, tb = self.get(a).detail, self.get(b).detail
        pa = {(p.scope, p.target, p.name): p.value for p in ta.params}
        pb = {(p.scope, p.target, p.name): p.value for p in tb.params}
        # a capture lists only the parameters off their default: one missing there had its
        # default then (an import has no snapshot at all: its values stay unknown, None)
        defaults = {(p.scope, p.target, p.name): p.default for p in [*ta.params, *tb.params]}
        rows = []
        for key in sorted(set(pa) | set(pb)):
            va = pa.get(key, defaults[key] if ta.source == "capture" else None)
            vb = pb.get(key, defaults[key] if tb.source == "capture" else None)
            if va != vb:
                s, t, n = key
                rows.append(ParamCompare(scope=s, target=t, name=n, a=va, b=vb))
        names_b = {c.name for c in tb.channels}
        common = [c.name for c in ta.channels if c.name in names_b]
        return TraceCompare(a=_info(ta), b=_info(tb), params=rows, common_channels=common)

    # --- reading ----------------------------------------------------------------------------
    def frame(self, tid: str) -> bytes:
        """The samples as one binary frame (api/telemetry.py format, stride 1)."""
        trace = self.get(tid)
        d = trace.detail
        header = FrameHeader(
            machine=d.machine,
            first_cycle=d.first_cycle,
            count=d.count,
            stride=1,
            cycle_s=d.cycle_s,
            t0_unix=0.0,
            signals=[c.name for c in d.channels],
            decimated=False,
            skipped_cycles=0,
        )
        return encode_frame(header, trace.data)

    def measure(
        self,
        tid: str,
        channel: str,
        t0_s: float | None,
        t1_s: float | None,
        band_pct: float,
        band_abs: float | None,
    ) -> MeasurementsModel:
        trace = self.get(tid)
        names = [c.name for c in trace.detail.channels]
        if channel not in names:
            raise Invalid(f"channel {channel} is not in trace {tid}: {names}")
        k = names.index(channel)
        t = trace.times_s()
        lo = t[0] if t0_s is None else t0_s
        hi = t[-1] if t1_s is None else t1_s
        sel = (t >= lo - 1e-12) & (t <= hi + 1e-12)
        if np.count_nonzero(sel) < 2:
            raise Invalid(f"window {lo:g} … {hi:g} s holds fewer than 2 samples")
        ref = 0.0 if trace.detail.trigger_cycle is not None and lo <= 0.0 <= hi else None
        m = measure(t[sel], trace.data[k][sel], band_pct, band_abs, ref)
        return MeasurementsModel(
            channel=channel,
            unit=trace.detail.channels[k].unit,
            t0_s=float(t[sel][0]),
            t1_s=float(t[sel][-1]),
            **m.__dict__,
        )

    def rrd_path(self, tid: str) -> Path:
        """The trace as a Rerun recording (made once, then cached)."""
        trace = self.get(tid)
        # a capture not (yet) saved gets its recording beside the recent ones, dropped with it
        path = self.dir / ("" if trace.detail.stored else "recent") / f"{tid}.rrd"
        if not path.exists():
            if trace.detail.stored:  # it counts for the library from now on
                self._room_for(trace.data.nbytes / MB, None, f"the Rerun recording of {tid}")
            path.parent.mkdir(exist_ok=True)
            d = trace.detail
            about = _about(d)
            from backend.services import rrd  # Rerun loads only when a capture is written

            rrd.write_capture(
                path,
                tid,
                d.machine,
                about,
                [c.name for c in d.channels],
                d.first_cycle,
                d.cycle_s,
                trace.data,
                trace.events(),
                self.notes_of(d),
            )
        return path


def _write_durably(path: Path, data: np.ndarray) -> None:
    """Write `path` as a whole or not at all: a temporary file, fsynced, renamed into place,
    and the directory fsynced so the rename itself survives a power cut."""
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with tmp.open("wb") as f:
            np.save(f, data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _about(d: TraceDetail) -> str:
    """A markdown description logged statically into the recording."""
    lines = [
        f"# {d.name or d.trigger or 'capture'}",
        f"- machine: {d.machine_name} ({d.machine})",
        f"- trigger: {d.trigger or '—'} at cycle {d.trigger_cycle}",
        f"- cycles {d.first_cycle} … {d.first_cycle + d.count - 1}, cycle time {d.cycle_s:g} s",
    ]
    if d.notes:
        lines.append(f"- notes: {d.notes}")
    if d.params:
        lines += ["", "| parameter | value | default |", "|---|---|---|"]
        lines += [
            f"| {p.target + ' ' if p.target else ''}{p.name} | {p.value} | {p.default} |"
            for p in d.params
        ]
    return "\n".join(lines)
