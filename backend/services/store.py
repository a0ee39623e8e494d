"""SQLite storage: machines, their accepted parameter values, and the audit trail.

One file, one connection guarded by a lock (the service writes rarely and briefly). Values are
stored as JSON so numbers stay numbers and strings stay strings.
"""

from __future__ import annotations

import json
import sqlite3
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from nc_sim.params import Value

_SCHEMA = """
CREATE TABLE IF NOT EXISTS machines (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    source TEXT NOT NULL,          -- 'demo' or 'lists'
    channel_list TEXT NOT NULL,
    axis_lists TEXT NOT NULL,      -- JSON {log_achs_nr: text}
    tool_list TEXT NOT NULL,
    created REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS param_values (
    machine TEXT NOT NULL,
    scope TEXT NOT NULL,
    target TEXT NOT NULL,          -- axis name, '' for channel and tool lists
    name TEXT NOT NULL,
    value TEXT NOT NULL,           -- JSON
    PRIMARY KEY (machine, scope, target, name)
);
CREATE TABLE IF NOT EXISTS audit (
    seq INTEGER PRIMARY KEY AUTOINCREMENT,
    time REAL NOT NULL,
    machine TEXT NOT NULL,
    actor TEXT NOT NULL,
    scope TEXT NOT NULL,
    target TEXT NOT NULL,
    name TEXT NOT NULL,
    old TEXT,                      -- JSON, NULL when the parameter was at its default
    new TEXT NOT NULL,
    effect TEXT NOT NULL,
    comment TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS traces (
    id TEXT PRIMARY KEY,
    machine TEXT NOT NULL,
    created REAL NOT NULL,
    name TEXT NOT NULL,
    notes TEXT NOT NULL,
    meta TEXT NOT NULL             -- JSON TraceDetail (its name and notes live in the columns)
);
"""


@dataclass(frozen=True)
class StoredMachine:
    id: str
    name: str
    source: str
    channel_list: str = ""
    axis_lists: dict[int, str] | None = None
    tool_list: str = ""


@dataclass(frozen=True)
class StoredChange:
    """One accepted change: (scope, target, name) went from old to new."""

    scope: str
    target: str
    name: str
    old: Value | None
    new: Value
    effect: str


@dataclass(frozen=True)
class AuditRow:
    seq: int
    time: float
    machine: str
    actor: str
    change: StoredChange
    comment: str


class Store:
    """The service's SQLite file."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(str(path), check_same_thread=False, isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.executescript(_SCHEMA)
        self._lock = threading.Lock()

    def close(self) -> None:
        with self._lock:
            self._db.close()

    # --- for the services with tables of their own (accounts) -------------------------------
    def script(self, sql: str) -> None:
        """Run a schema script (CREATE TABLE IF NOT EXISTS ...)."""
        with self._lock:
            self._db.executescript(sql)

    def query(self, sql: str, args: tuple[object, ...] = ()) -> list[tuple[Any, ...]]:
        with self._lock:
            return self._db.execute(sql, args).fetchall()

    def run(self, sql: str, args: tuple[object, ...] = ()) -> None:
        with self._lock:
            self._db.execute(sql, args)

    def machines(self) -> list[StoredMachine]:
        with self._lock:
            rows = self._db.execute(
                "SELECT id, name, source, channel_list, axis_lists, tool_list FROM machines "
                "ORDER BY created"
            ).fetchall()
        return [
            StoredMachine(
                r[0], r[1], r[2], r[3], {int(k): v for k, v in json.loads(r[4]).items()}, r[5]
            )
            for r in rows
        ]

    def add_machine(self, m: StoredMachine) -> None:
        with self._lock:
            self._db.execute(
                "INSERT INTO machines VALUES (?, ?, ?, ?, ?, ?, ?)",
                (
                    m.id,
                    m.name,
                    m.source,
                    m.channel_list,
                    json.dumps({str(k): v for k, v in (m.axis_lists or {}).items()}),
                    m.tool_list,
                    time.time(),
                ),
            )

    def delete_machine(self, mid: str) -> None:
        """Forget a machine and its values; its audit trail stays."""
        with self._lock, self._db:
            self._db.execute("BEGIN")
            self._db.execute("DELETE FROM machines WHERE id = ?", (mid,))
            self._db.execute("DELETE FROM param_values WHERE machine = ?", (mid,))

    def values(self, mid: str) -> list[tuple[str, str, str, Value]]:
        """(scope, target, name, value) of every accepted value of a machine."""
        with self._lock:
            rows = self._db.execute(
                "SELECT scope, target, name, value FROM param_values WHERE machine = ?", (mid,)
            ).fetchall()
        return [(r[0], r[1], r[2], json.loads(r[3])) for r in rows]

    def write(self, mid: str, actor: str, comment: str, changes: list[StoredChange]) -> None:
        """Store accepted changes and their audit rows in one transaction."""
        now = time.time()
        with self._lock, self._db:
            self._db.execute("BEGIN")
            for c in changes:
                self._db.execute(
                    "INSERT OR REPLACE INTO param_values VALUES (?, ?, ?, ?, ?)",
                    (mid, c.scope, c.target, c.name, json.dumps(c.new)),
                )
                self._db.execute(
                    "INSERT INTO audit (time, machine, actor, scope, target, name, old, new, "
                    "effect, comment) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                    (
                        now,
                        mid,
                        actor,
                        c.scope,
                        c.target,
                        c.name,
                        None if c.old is None else json.dumps(c.old),
                        json.dumps(c.new),
                        c.effect,
                        comment,
                    ),
                )

    def audit(self, mid: str, limit: int = 1000) -> list[AuditRow]:
        """The newest `limit` changes of a machine, oldest first."""
        with self._lock:
            rows = self._db.execute(
                "SELECT seq, time, machine, actor, scope, target, name, old, new, effect, comment "
                "FROM audit WHERE machine = ? ORDER BY seq DESC LIMIT ?",
                (mid, limit),
            ).fetchall()
        return [
            AuditRow(
                r[0],
                r[1],
                r[2],
                r[3],
                StoredChange(
                    r[4],
                    r[5],
                    r[6],
                    None if r[7] is None else json.loads(r[7]),
                    json.loads(r[8]),
                    r[9],
                ),
                r[10],
            )
            for r in reversed(rows)
        ]

    # --- the trace library (samples live in files next to the database) -----------------------
    def add_trace(
        self, tid: str, machine: str, created: float, name: str, notes: str, meta: str
    ) -> None:
        with self._lock:
            self._db.execute(
                "INSERT INTO traces VALUES (?, ?, ?, ?, ?, ?)",
                (tid, machine, created, name, notes, meta),
            )

    def traces(self, machine: str | None = None) -> list[tuple[str, str, str, str]]:
        """(id, name, notes, meta JSON) of stored traces, newest first."""
        q = "SELECT id, name, notes, meta FROM traces"
        args: tuple[str, ...] = ()
        if machine is not None:
            q, args = q + " WHERE machine = ?", (machine,)
        with self._lock:
            rows = self._db.execute(q + " ORDER BY created DESC", args).fetchall()
        return [(r[0], r[1], r[2], r[3]) for r in rows]

    def trace(self, tid: str) -> tuple[str, str, str, str] | None:
        with self._lock:
            r = self._db.execute(
                "SELECT id, name, notes, meta FROM traces WHERE id = ?", (tid,)
            ).fetchone()
        return (r[0], r[1], r[2], r[3]) if r else None

    def update_trace(self, tid: str, name: str, notes: str) -> None:
        with self._lock:
            self._db.execute(
                "UPDATE traces SET name = ?, notes = ? WHERE id = ?", (name, notes, tid)
            )

    def delete_trace(self, tid: str) -> bool:
        with self._lock:
            cur = self._db.execute("DELETE FROM traces WHERE id = ?", (tid,))
        return cur.rowcount > 0
