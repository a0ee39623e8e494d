"""The machine log: the table of a machine's history that the NC and the service write (job
errors and their causes, events, power-ons, service starts and stops, notes), and the
reading of a machine's whole history, those rows merged with its audit rows by wall clock
(backend/services/history.py writes the rows and keeps them live)."""

from __future__ import annotations

import csv
import io
import sqlite3
import time
from dataclasses import dataclass, field
from typing import cast

from api.history import HistoryEntry, HistoryKind, Severity
from api.scope import TraceDetail
from backend.services.audit_log import Entry, who_and_when
from backend.services.store import Row, Store
from nc_sim.events import Event

SCHEMA = """
CREATE TABLE IF NOT EXISTS machine_log (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    machine TEXT NOT NULL,
    time REAL NOT NULL,            -- wall clock, Unix time
    sim_t_s REAL,                  -- the machine's simulated time (NULL: not running then)
    epoch INTEGER,                 -- the machine's build
    kind TEXT NOT NULL,            -- api/history.py LogKind, or 'command' for a dropped block
    severity TEXT NOT NULL,        -- error | warning | info
    actor TEXT NOT NULL,           -- '' for the NC itself
    text TEXT NOT NULL,
    outcome TEXT NOT NULL DEFAULT '',
    code INTEGER,
    axis TEXT NOT NULL DEFAULT '',
    trace TEXT,                    -- a trace saved with it (flight recorder)
    cause TEXT                     -- a job error: the command that raised it
);
CREATE INDEX IF NOT EXISTS machine_log_time ON machine_log (machine, time);
CREATE INDEX IF NOT EXISTS machine_log_kind ON machine_log (kind, time);
"""
_LOG_COLUMNS = (
    "machine, time, sim_t_s, epoch, kind, severity, actor, text, outcome, code, axis, trace, cause"
)
_ENTRY_COLUMNS = (
    "time, sim_t_s, epoch, kind, severity, actor, text, outcome, code, axis, trace, cause"
)
# both tables in the columns of a history entry (a machine's rows; `?` twice: the machine)
_MERGED = """
SELECT 'a' || seq AS id, 0 AS src, seq AS n, time, sim_t_s, epoch, kind,
       CASE WHEN outcome = 'ok' THEN 'info' ELSE 'warning' END AS severity,
       actor, action AS text, outcome, NULL AS code, '' AS axis, NULL AS trace, NULL AS cause
FROM audit_log WHERE machine = ?
UNION ALL
SELECT 'h' || id, 1, id, time, sim_t_s, epoch, kind, severity, actor, text, outcome, code, axis,
       trace, cause
FROM machine_log WHERE machine = ?
"""
MAX_PAGE = 1000
EXPORT_ROWS = 100_000  # an export holds at most this many entries (the newest)


@dataclass(frozen=True)
class LogRow:
    """A row for the machine log."""

    machine: str
    kind: HistoryKind
    severity: Severity
    text: str
    actor: str = ""
    sim_t_s: float | None = None
    epoch: int | None = None
    outcome: str = ""
    code: int | None = None
    axis: str = ""
    trace: str | None = None
    cause: str | None = None
    time: float = field(default_factory=time.time)


@dataclass(frozen=True)
class HistoryFilter:
    """Which entries: all given conditions hold."""

    kinds: tuple[str, ...] = ()
    severities: tuple[str, ...] = ()
    actor: str | None = None  # part of the name, any case
    since_unix: float | None = None
    until_unix: float | None = None
    text: str | None = None  # in the text, outcome or cause

    def where(self) -> tuple[str, tuple[object, ...]]:
        conds: list[str] = []
        args: list[object] = []
        for column, values in (("kind", self.kinds), ("severity", self.severities)):
            if values:
                conds.append(f"{column} IN ({', '.join('?' * len(values))})")
                args += values
        who, when = who_and_when(self.actor, self.since_unix, self.until_unix)
        conds += who
        args += when
        if self.text:
            conds.append("instr(lower(text || ' ' || outcome || ' ' || ifnull(cause, '')), ?) > 0")
            args.append(self.text.lower())
        return (" WHERE " + " AND ".join(conds) if conds else ""), tuple(args)


def _entry(r: Row) -> HistoryEntry:
    return HistoryEntry(
        id=r["id"],
        time_unix=r["time"],
        sim_t_s=r["sim_t_s"],
        epoch=r["epoch"],
        kind=r["kind"],
        severity=r["severity"],
        actor=r["actor"],
        text=r["text"],
        outcome=r["outcome"],
        code=r["code"],
        axis=r["axis"],
        trace=r["trace"],
        cause=r["cause"],
    )


def audit_entry(seq: int, e: Entry, stamp: tuple[int, float] | None) -> HistoryEntry:
    return HistoryEntry(
        id=f"a{seq}",
        time_unix=e.time if e.time is not None else time.time(),
        sim_t_s=stamp[1] if stamp else None,
        epoch=stamp[0] if stamp else None,
        kind=e.kind,
        severity="info" if e.outcome == "ok" else "warning",
        actor=e.actor,
        text=e.action,
        outcome=e.outcome,
    )


def _log_entry(rid: int, r: LogRow) -> HistoryEntry:
    return HistoryEntry(
        id=f"h{rid}",
        time_unix=r.time,
        sim_t_s=r.sim_t_s,
        epoch=r.epoch,
        kind=r.kind,
        severity=r.severity,
        actor=r.actor,
        text=r.text,
        outcome=r.outcome,
        code=r.code,
        axis=r.axis,
        trace=r.trace,
        cause=r.cause,
    )


def page(
    store: Store,
    mid: str,
    f: HistoryFilter,
    limit: int = 200,
    before: tuple[float, str] | None = None,
) -> tuple[list[HistoryEntry], int]:
    """Matching entries, newest first (older ones: `before` = (time, id) of the last
    one seen), and how many match in all."""
    where, args = f.where()
    merged = f"SELECT * FROM ({_MERGED}){where}"
    total = store.query(f"SELECT count(*) AS n FROM ({merged})", (mid, mid, *args))
    page_where, page_args = "", cast(tuple[object, ...], ())
    if before is not None:
        src, n = (0 if before[1].startswith("a") else 1), int(before[1][1:])
        page_where, page_args = " WHERE (time, src, n) < (?, ?, ?)", (before[0], src, n)
    rows = store.query(
        f"SELECT * FROM ({merged}){page_where} ORDER BY time DESC, src DESC, n DESC LIMIT ?",
        (mid, mid, *args, *page_args, min(limit, EXPORT_ROWS)),
    )
    return [_entry(r) for r in rows], int(total[0]["n"])


def alarms(store: Store, machines: list[str], limit: int) -> list[tuple[str, HistoryEntry]]:
    """The newest job errors of these machines, newest first, with their machine."""
    if not machines:
        return []
    rows = store.query(
        f"SELECT 'h' || id AS id, machine, {_ENTRY_COLUMNS} FROM machine_log "
        f"WHERE kind = 'job_error' AND machine IN ({', '.join('?' * len(machines))}) "
        "ORDER BY time DESC LIMIT ?",
        (*machines, limit),
    )
    return [(str(r["machine"]), _entry(r)) for r in rows]


def notes_in(store: Store, d: TraceDetail) -> list[tuple[float, str]]:
    """The notes written on the trace's machine while it was recorded, at their
    simulated time (sim_time s, 'who: text'), for its timeline."""
    t0, t1 = d.first_cycle * d.cycle_s, (d.first_cycle + d.count) * d.cycle_s
    span = t1 - t0
    rows = store.query(
        "SELECT sim_t_s, actor, text FROM machine_log WHERE machine = ? AND kind = 'note' "
        "AND time BETWEEN ? AND ? AND sim_t_s BETWEEN ? AND ? ORDER BY time",
        (d.machine, d.created_unix - span - 60.0, d.created_unix + 1.0, t0, t1),
    )
    return [(float(r["sim_t_s"]), f"{r['actor']}: {r['text']}") for r in rows]


def insert(store: Store, rows: list[LogRow]) -> list[HistoryEntry]:
    """Write rows in one transaction; their entries (with their ids)."""

    def work(db: sqlite3.Connection) -> list[int]:
        ids = []
        for r in rows:
            cur = db.execute(
                f"INSERT INTO machine_log ({_LOG_COLUMNS}) VALUES ({', '.join('?' * 13)})",
                (
                    r.machine,
                    r.time,
                    r.sim_t_s,
                    r.epoch,
                    r.kind,
                    r.severity,
                    r.actor,
                    r.text,
                    r.outcome,
                    r.code,
                    r.axis,
                    r.trace,
                    r.cause,
                ),
            )
            ids.append(int(cur.lastrowid or 0))
        return ids

    ids = store.transaction(work)
    return [_log_entry(rid, r) for rid, r in zip(ids, rows, strict=True)]


def prune(store: Store, days: float, rows_per_machine: int) -> int:
    """End rows past the retention: older than `days`, beyond `rows_per_machine` per
    machine (the oldest first); how many."""
    cutoff = time.time() - days * 86400.0

    def work(db: sqlite3.Connection) -> int:
        gone = db.execute("DELETE FROM machine_log WHERE time < ?", (cutoff,)).rowcount
        full = db.execute(
            "SELECT machine FROM machine_log GROUP BY machine HAVING count(*) > ?",
            (rows_per_machine,),
        ).fetchall()
        for r in full:
            gone += db.execute(
                "DELETE FROM machine_log WHERE machine = ? AND id <= (SELECT id FROM "
                "machine_log WHERE machine = ? ORDER BY id DESC LIMIT 1 OFFSET ?)",
                (r["machine"], r["machine"], rows_per_machine),
            ).rowcount
        return int(gone)

    return store.transaction(work)


def last_epoch(store: Store, mid: str) -> int:
    """The newest build of the machine its log names (0 for none)."""
    rows = store.query("SELECT max(epoch) AS e FROM machine_log WHERE machine = ?", (mid,))
    return int(rows[0]["e"] or 0)


def link_trace(
    store: Store, mid: str, epoch: int, errors: list[Event], trace: str
) -> list[HistoryEntry]:
    """Link these job errors' rows to a trace; their entries as they are now."""

    def work(db: sqlite3.Connection) -> list[Row]:
        rows: list[Row] = []
        for e in errors:
            where = "machine = ? AND epoch = ? AND kind = 'job_error' AND code = ? AND sim_t_s = ?"
            args = (mid, epoch, e.code, e.t_s)
            db.execute(f"UPDATE machine_log SET trace = ? WHERE {where}", (trace, *args))
            rows += db.execute(
                f"SELECT 'h' || id AS id, {_ENTRY_COLUMNS} FROM machine_log WHERE {where}", args
            ).fetchall()
        return rows

    return [_entry(r) for r in store.transaction(work)]


CSV_HEADER = (
    "time_utc", "sim_t_s", "epoch", "kind", "severity", "actor", "text", "outcome", "code",
    "axis", "cause", "trace", "id",
)  # fmt: skip


def utc(t: float) -> str:
    """A Unix time as ISO 8601 UTC with milliseconds."""
    return time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(t)) + f".{int(t % 1 * 1000):03d}Z"


def csv_text(entries: list[HistoryEntry]) -> str:
    """Entries as CSV, in the order given, for a spreadsheet."""
    out = io.StringIO()
    w = csv.writer(out)
    w.writerow(CSV_HEADER)
    for e in entries:
        w.writerow(
            [utc(e.time_unix), "" if e.sim_t_s is None else f"{e.sim_t_s:.3f}",
             "" if e.epoch is None else e.epoch, e.kind, e.severity, e.actor, e.text,
             e.outcome, "" if e.code is None else e.code, e.axis, e.cause or "", e.trace or "",
             e.id]
        )  # fmt: skip
    return out.getvalue()
