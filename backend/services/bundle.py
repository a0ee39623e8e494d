"""Diagnostic bundles: one zip with what an expert far away needs to see what the engineer on
site saw, and such a zip opened read-only as an offline machine on another service.

A bundle holds `manifest.json` (format, service version, when, by whom, which machine),
`machine.json`, the parameter lists in the native format (`lists/`, as a restart would load
them), `versions.json` and `diff.json` (the live lists against the baseline), the history
(`history.json`, `history.csv`), the flight recorder's traces of the newest alarms
(`traces/<id>.json`, `.csv`, `.rrd`), and `status.json` (the machine, its flight recorder and
the service). Opening one stores the zip, keeps its manifest in the store and takes its traces
into the trace library (as imports, under the offline machine), so the scope and Rerun show
them as any other.
"""

from __future__ import annotations

import contextlib
import io
import json
import threading
import time
import uuid
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from api.bundle import BundleDetail, BundleInfo, BundleManifest
from api.history import HistoryEntry
from api.scope import TraceDetail, TraceInfo
from api.versions import VersionDiff, VersionInfo
from backend import VERSION
from backend.errors import ApiError, Invalid, not_found
from backend.services.machine_log import EXPORT_ROWS, HistoryFilter, csv_text
from backend.services.store import Row, Store
from backend.services.trace_csv import from_csv, to_csv
from backend.services.traces import TraceService
from nc_sim.params import Scope

FORMAT = "inbetrieb-bundle"
FORMAT_VERSION = 1
ALARM_TRACES = 10  # the flight recorder's newest traces a bundle carries
MAX_UNPACKED_BYTES = 512 * 1024 * 1024  # what an opened bundle may unpack to in all
SCHEMA = """
CREATE TABLE IF NOT EXISTS bundles (
    id TEXT PRIMARY KEY,
    created REAL NOT NULL,          -- when it was opened here
    opened_by TEXT NOT NULL,
    manifest TEXT NOT NULL,         -- JSON BundleManifest
    traces TEXT NOT NULL            -- JSON {id in the bundle: id in this library}
);
"""


@dataclass(frozen=True)
class Contents:
    """What goes into a bundle of one machine (gathered by the route from the services)."""

    machine: dict[str, Any]
    lists: dict[str, str]  # file name -> list text
    versions: list[VersionInfo]
    diff: VersionDiff | None
    history: list[HistoryEntry]  # oldest first
    status: dict[str, Any]


def lists_of(scopes: Sequence[tuple[Scope, str | None]], export: Any) -> dict[str, str]:
    """The native lists by file name: `channel.txt`, `tool.txt`, `axis_X.txt`, ..."""
    out = {}
    for scope, target in scopes:
        name = f"{scope.value}_{target}.txt" if target else f"{scope.value}.txt"
        out[name] = export(scope, target)
    return out


def build(c: Contents, traces: TraceService, mid: str, by: str) -> tuple[bytes, BundleManifest]:
    """The bundle as zip bytes, and its manifest."""
    flight = [
        t for t in traces.library(mid) if t.source == "flight" and t.trigger.startswith("job error")
    ][:ALARM_TRACES]
    manifest = BundleManifest(
        format=FORMAT,
        format_version=FORMAT_VERSION,
        service_version=VERSION,
        created_unix=time.time(),
        created_by=by,
        machine_id=str(c.machine["id"]),
        machine_name=str(c.machine["name"]),
        history_entries=len(c.history),
        traces=[t.id for t in flight],
        lists=sorted(c.lists),
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("manifest.json", manifest.model_dump_json(indent=1))
        z.writestr("machine.json", json.dumps(c.machine, indent=1))
        for name, text in c.lists.items():
            z.writestr(f"lists/{name}", text)
        z.writestr("versions.json", json.dumps([v.model_dump(mode="json") for v in c.versions]))
        z.writestr("diff.json", c.diff.model_dump_json(by_alias=True) if c.diff else "null")
        z.writestr("history.json", "[" + ",\n".join(e.model_dump_json() for e in c.history) + "]")
        z.writestr("history.csv", csv_text(c.history))
        z.writestr("status.json", json.dumps(c.status, indent=1, default=str))
        for t in flight:
            trace = traces.get(t.id)
            z.writestr(f"traces/{t.id}.json", trace.detail.model_dump_json())
            z.writestr(f"traces/{t.id}.csv", to_csv(trace))
            z.write(traces.rrd_path(t.id), f"traces/{t.id}.rrd")
    return buf.getvalue(), manifest


def _described(d: TraceDetail, text: str) -> TraceDetail:
    """A trace read from its CSV as the bundle describes it: what the CSV cannot say (its
    name, source, trigger, events, parameters, channel kinds, capture time); 422 when the
    description is malformed."""
    try:
        was = TraceDetail.model_validate_json(text)
    except ValidationError as e:
        raise Invalid(f"bundle: a trace's description: {e.errors()[0]['msg']}") from None
    kinds = {c.name: c for c in was.channels}
    return d.model_copy(
        update={
            "name": was.name,
            "notes": was.notes,
            "source": was.source,
            "trigger": was.trigger,
            "forced": was.forced,
            "created_unix": was.created_unix,
            "params": was.params,
            "params_changed": was.params_changed,
            "events": was.events,
            "channels": [kinds.get(c.name, c) for c in d.channels],
        }
    )


class Bundles:
    """Bundles opened here: each an offline machine, read-only."""

    def __init__(self, store: Store, directory: Path, traces: TraceService) -> None:
        self.store, self.dir, self.traces = store, directory, traces
        self.dir.mkdir(parents=True, exist_ok=True)
        store.script(SCHEMA)
        self._lock = threading.Lock()

    def open(self, data: bytes, by: str) -> BundleDetail:
        """Check a bundle and keep it as an offline machine: 422 naming what is wrong."""
        try:
            z = zipfile.ZipFile(io.BytesIO(data))
        except zipfile.BadZipFile:
            raise Invalid("bundle: not a zip file") from None
        with z:
            if sum(i.file_size for i in z.infolist()) > MAX_UNPACKED_BYTES:
                raise Invalid(f"bundle: unpacks to more than {MAX_UNPACKED_BYTES >> 20} MB")
            manifest = _manifest(z)
            bid = uuid.uuid4().hex[:12]
            offline = f"offline-{bid}"
            ids: dict[str, str] = {}
            for tid in manifest.traces:
                trace = from_csv(_text(z, f"traces/{tid}.csv"), "")
                trace.detail.machine = offline
                trace.detail.machine_name = f"{manifest.machine_name} (offline, {bid})"
                trace.detail.created_unix = manifest.created_unix  # not the opening's time
                if f"traces/{tid}.json" in z.namelist():  # as it was captured
                    trace.detail = _described(trace.detail, _text(z, f"traces/{tid}.json"))
                ids[tid] = self.traces.add(trace, by).id
        (self.dir / f"{bid}.zip").write_bytes(data)
        self.store.run(
            "INSERT INTO bundles VALUES (?, ?, ?, ?, ?)",
            (bid, time.time(), by, manifest.model_dump_json(), json.dumps(ids)),
        )
        return self.detail(bid)

    def opened(self) -> list[BundleInfo]:
        """The bundles opened here, newest first."""
        rows = self.store.query("SELECT id FROM bundles ORDER BY created DESC")
        return [self._info(str(r["id"])) for r in rows]

    def _info(self, bid: str) -> BundleInfo:
        rows = self.store.query("SELECT * FROM bundles WHERE id = ?", (bid,))
        if not rows:
            raise not_found(f"bundle {bid}")
        r = rows[0]
        return BundleInfo(
            id=bid,
            opened_unix=r["created"],
            opened_by=r["opened_by"],
            manifest=BundleManifest.model_validate_json(r["manifest"]),
            traces=list(self._ids(bid, r).values()),
        )

    @staticmethod
    def _ids(bid: str, r: Row) -> dict[str, str]:
        """Its traces' ids in the bundle → in this library."""
        ids: dict[str, str] = json.loads(r["traces"])
        return ids

    def _zip(self, bid: str) -> zipfile.ZipFile:
        self._info(bid)  # 404 for an unknown bundle
        return zipfile.ZipFile(self.dir / f"{bid}.zip")

    def detail(self, bid: str) -> BundleDetail:
        """The offline machine: what the bundle says about it, its lists, versions and diff."""
        info = self._info(bid)
        with self._zip(bid) as z:
            diff = json.loads(_text(z, "diff.json"))
            return BundleDetail(
                **info.model_dump(),
                machine=json.loads(_text(z, "machine.json")),
                status=json.loads(_text(z, "status.json")),
                versions=[
                    VersionInfo.model_validate(v) for v in json.loads(_text(z, "versions.json"))
                ],
                diff=VersionDiff.model_validate(diff) if diff is not None else None,
                trace_infos=[_trace_info(self.traces.get(tid).detail) for tid in info.traces],
            )

    def history(self, bid: str, f: HistoryFilter) -> list[HistoryEntry]:
        """The bundle's history, newest first, filtered as a live machine's is."""
        with self._zip(bid) as z:  # 404 for an unknown bundle
            rows = [HistoryEntry.model_validate(e) for e in json.loads(_text(z, "history.json"))]
        ids = self._ids(bid, self.store.query("SELECT traces FROM bundles WHERE id = ?", (bid,))[0])
        for e in rows:  # a trace it carries, as it is in this library; else none
            e.trace = ids.get(e.trace) if e.trace else None
        return [e for e in reversed(rows) if _matches(e, f)][:EXPORT_ROWS]

    def list_text(self, bid: str, name: str) -> str:
        """One of the bundle's parameter lists in the native format."""
        with self._zip(bid) as z:
            if f"lists/{name}" not in z.namelist():
                raise not_found(f"list {name} of bundle {bid}")
            return _text(z, f"lists/{name}")

    def delete(self, bid: str) -> None:
        """Forget a bundle and its traces."""
        info = self._info(bid)
        for tid in info.traces:
            with contextlib.suppress(ApiError):  # deleted from the library meanwhile
                self.traces.delete(tid)
        self.store.run("DELETE FROM bundles WHERE id = ?", (bid,))
        (self.dir / f"{bid}.zip").unlink(missing_ok=True)


def _trace_info(d: TraceDetail) -> TraceInfo:
    return TraceInfo.model_validate(d.model_dump(exclude={"params", "events"}))


def _text(z: zipfile.ZipFile, name: str) -> str:
    try:
        return z.read(name).decode("utf-8")
    except KeyError:
        raise Invalid(f"bundle: {name} is missing") from None
    except UnicodeDecodeError:
        raise Invalid(f"bundle: {name} is not UTF-8 text") from None


def _manifest(z: zipfile.ZipFile) -> BundleManifest:
    try:
        m = BundleManifest.model_validate_json(_text(z, "manifest.json"))
    except ValidationError as e:
        raise Invalid(
            f"bundle: manifest.json is not a bundle's manifest: {e.errors()[0]['msg']}"
        ) from None
    if m.format != FORMAT or m.format_version > FORMAT_VERSION:
        raise Invalid(f"bundle: format {m.format} {m.format_version} is not one this service reads")
    return m


def _matches(e: HistoryEntry, f: HistoryFilter) -> bool:
    text = f"{e.text} {e.outcome} {e.cause or ''}".lower()
    return (
        (not f.kinds or e.kind in f.kinds)
        and (not f.severities or e.severity in f.severities)
        and (not f.actor or f.actor.lower() in e.actor.lower())
        and (f.since_unix is None or e.time_unix >= f.since_unix)
        and (f.until_unix is None or e.time_unix < f.until_unix)
        and (not f.text or f.text.lower() in text)
    )
