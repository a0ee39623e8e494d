"""SQLite storage: machines, their accepted parameter values and versions, the audit trail,
traces, NC programs, assistant runs and sign-offs.

One file, one connection guarded by a lock (the service writes rarely and briefly). Values are
stored as JSON so numbers stay numbers and strings stay strings.
"""

from __future__ import annotations

import json
import sqlite3
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, TypeVar

from backend import VERSION
from backend.services import audit_log, migrations
from backend.services.migrations import Step, add_column, has_table
from nc_sim.params import Value

T = TypeVar("T")

# a row of a query: its columns by name (`row["machine"]`), never by position
Row = sqlite3.Row

_PROGRAMS = """
CREATE TABLE IF NOT EXISTS programs (
    owner TEXT NOT NULL,           -- '' service-wide; a class seat's machine: that seat's own
    name TEXT NOT NULL,            -- as written; unique per owner regardless of case
    text TEXT NOT NULL,
    size INTEGER NOT NULL,         -- characters
    lines INTEGER NOT NULL,
    updated REAL NOT NULL,         -- Unix time of the last write
    updated_by TEXT NOT NULL,
    PRIMARY KEY (owner, name)
)"""
# after the steps: a store of the first versions has programs without owners until step 1
_PROGRAMS_INDEX = (
    "CREATE UNIQUE INDEX IF NOT EXISTS programs_owner_name ON programs (owner, name COLLATE NOCASE)"
)
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
    version INTEGER NOT NULL DEFAULT 0,  -- seq of the audit row that wrote it
    PRIMARY KEY (machine, scope, target, name)
);
CREATE TABLE IF NOT EXISTS traces (
    id TEXT PRIMARY KEY,
    machine TEXT NOT NULL,
    created REAL NOT NULL,
    name TEXT NOT NULL,
    notes TEXT NOT NULL,
    meta TEXT NOT NULL,            -- JSON TraceDetail (its name and notes live in the columns)
    created_by TEXT NOT NULL DEFAULT ''  -- who saved or imported it (its files count for them)
);
-- programs: _PROGRAMS above
-- parameter versions of a machine (backend/services/versions.py)
CREATE TABLE IF NOT EXISTS param_versions (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- never reused: an old link never shows another
    machine TEXT NOT NULL,
    name TEXT NOT NULL,
    note TEXT NOT NULL,
    created REAL NOT NULL,
    created_by TEXT NOT NULL,
    baseline INTEGER NOT NULL DEFAULT 0,   -- 1 for the machine's baseline (at most one)
    lists TEXT NOT NULL                    -- JSON [[scope, target, name, value], ...]
);
CREATE UNIQUE INDEX IF NOT EXISTS param_versions_name
    ON param_versions (machine, name COLLATE NOCASE);
CREATE TABLE IF NOT EXISTS assist_runs (  -- backend/services/assist_runs.py
    id INTEGER PRIMARY KEY,
    machine TEXT NOT NULL,
    assistant TEXT NOT NULL,
    user TEXT NOT NULL,
    time REAL NOT NULL,
    live INTEGER NOT NULL,         -- 1: on the live machine, 0: on a copy
    ok INTEGER NOT NULL,
    axis TEXT NOT NULL,
    summary TEXT NOT NULL,
    result TEXT NOT NULL           -- JSON AssistResult (inputs, figures, changes, series, notes)
);
CREATE INDEX IF NOT EXISTS assist_runs_machine ON assist_runs (machine, id);
CREATE TABLE IF NOT EXISTS sign_offs (  -- backend/services/report.py
    id INTEGER PRIMARY KEY,
    machine TEXT NOT NULL,
    name TEXT NOT NULL,
    role TEXT NOT NULL,
    remark TEXT NOT NULL,
    user TEXT NOT NULL,
    time REAL NOT NULL
);
"""


@dataclass(frozen=True)
class StoredProgram:
    """An NC program in the store (`text` empty when only the list was asked for)."""

    name: str
    size: int  # characters
    lines: int
    updated: float  # Unix time
    updated_by: str
    text: str = ""
    owner: str = ""  # '' service-wide, else the class seat (machine) whose own it is


@dataclass(frozen=True)
class StoredTrace:
    """A trace in the library (its samples live in a file next to the database)."""

    id: str
    name: str
    notes: str
    meta: str  # JSON TraceDetail (its name and notes are the columns above)


@dataclass(frozen=True)
class StoredMachine:
    id: str
    name: str
    source: str
    channel_list: str = ""
    axis_lists: dict[int, str] | None = None
    tool_list: str = ""


def parameter_entry(
    mid: str, actor: str, session: str, c: StoredChange, comment: str, when: float | None = None
) -> audit_log.Entry:
    """The audit row of one accepted parameter change."""
    where = f"{c.target}: " if c.target else ""
    old = "default" if c.old is None else c.old
    return audit_log.Entry(
        actor=actor,
        session=session,
        kind="parameter",
        action=f"{where}{c.name} {old} → {c.new}",
        machine=mid,
        detail={
            "scope": c.scope,
            "target": c.target,
            "name": c.name,
            "old": c.old,
            "new": c.new,
            "effect": c.effect,
            "comment": comment,
        },
        time=when,
    )


@dataclass(frozen=True)
class StoredChange:
    """One accepted change: (scope, target, name) went from old to new."""

    scope: str
    target: str
    name: str
    old: Value | None
    new: Value
    effect: str


class Store:
    """The service's SQLite file."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(str(path), check_same_thread=False, isolation_level=None)
        self._db.row_factory = Row  # every row, in `query` and in a transaction's work
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=NORMAL")  # WAL stays consistent; no sync per row
        new = migrations.is_new(self._db)
        self._db.executescript(_SCHEMA)
        self._db.execute(_PROGRAMS)
        self._db.executescript(audit_log.SCHEMA)
        self._lock = threading.Lock()
        # stamps a machine's audit rows with its build and simulated time (the history's)
        self.clock: audit_log.Clock | None = None
        # told each transaction's new audit rows once committed (the history's live view)
        self.on_audited: Callable[[list[tuple[int, audit_log.Entry]]], None] | None = None
        self._audited: list[tuple[int, audit_log.Entry]] = []  # in the running transaction
        try:
            self.steps_taken = migrations.upgrade(self._db, STEPS, VERSION, new, str(path))
        except migrations.StoreTooNew:
            self._db.close()
            raise
        self._db.execute(_PROGRAMS_INDEX)

    def transaction(self, work: Callable[[sqlite3.Connection], T]) -> T:
        """Run `work` on the connection in one transaction (the audit trail's chain)."""
        with self._lock:
            try:
                with self._db:
                    self._db.execute("BEGIN")
                    out = work(self._db)
            finally:
                audited, self._audited = self._audited, []
        if audited and self.on_audited is not None:
            self.on_audited(audited)
        return out

    def append_audit(self, db: sqlite3.Connection, entries: list[audit_log.Entry]) -> list[int]:
        """Chain audit rows onto the trail inside a transaction's `work`; their seqs."""
        seqs = audit_log.append(db, entries, self.clock)
        self._audited += zip(seqs, entries, strict=True)
        return seqs

    def close(self) -> None:
        """Close the file, its write-ahead log folded in (a stopped service leaves one file)."""
        with self._lock:
            self._db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
            self._db.close()

    # --- for the services with tables of their own (accounts) -------------------------------
    def script(self, sql: str) -> None:
        """Run a schema script (CREATE TABLE IF NOT EXISTS ...)."""
        with self._lock:
            self._db.executescript(sql)

    def query(self, sql: str, args: tuple[object, ...] = ()) -> list[Row]:
        """The rows of a SELECT, read by column name (`AS` names a computed column)."""
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
                r["id"],
                r["name"],
                r["source"],
                r["channel_list"],
                {int(k): v for k, v in json.loads(r["axis_lists"]).items()},
                r["tool_list"],
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
        """Forget a machine, its values, versions, assistant runs and sign-offs; its audit trail
        stays."""
        with self._lock, self._db:
            self._db.execute("BEGIN")
            self._db.execute("DELETE FROM machines WHERE id = ?", (mid,))
            self._db.execute("DELETE FROM param_values WHERE machine = ?", (mid,))
            self._db.execute("DELETE FROM param_versions WHERE machine = ?", (mid,))
            self._db.execute("DELETE FROM assist_runs WHERE machine = ?", (mid,))
            self._db.execute("DELETE FROM sign_offs WHERE machine = ?", (mid,))

    def values(self, mid: str) -> list[tuple[str, str, str, Value]]:
        """(scope, target, name, value) of every accepted value of a machine."""
        with self._lock:
            rows = self._db.execute(
                "SELECT scope, target, name, value FROM param_values WHERE machine = ?", (mid,)
            ).fetchall()
        return [(r["scope"], r["target"], r["name"], json.loads(r["value"])) for r in rows]

    def write(
        self, mid: str, changes: list[StoredChange], entries: list[audit_log.Entry]
    ) -> list[int]:
        """Store accepted changes and their audit rows (one each) in one transaction; each
        value's version is its audit row's seq. The versions, in the order of `changes`."""

        def work(db: sqlite3.Connection) -> list[int]:
            seqs = self.append_audit(db, entries)
            for c, seq in zip(changes, seqs, strict=True):
                db.execute(
                    "INSERT OR REPLACE INTO param_values VALUES (?, ?, ?, ?, ?, ?)",
                    (mid, c.scope, c.target, c.name, json.dumps(c.new), seq),
                )
            return seqs

        return self.transaction(work)

    def replace_values(
        self, mid: str, changes: list[StoredChange], entries: list[audit_log.Entry]
    ) -> None:
        """Every accepted value of a machine goes; `changes` (with their audit rows) are its
        values from now on, in one transaction (a class seat starting its next exercise)."""

        def work(db: sqlite3.Connection) -> None:
            db.execute("DELETE FROM param_values WHERE machine = ?", (mid,))
            seqs = self.append_audit(db, entries)
            for c, seq in zip(changes, seqs, strict=True):
                db.execute(
                    "INSERT INTO param_values VALUES (?, ?, ?, ?, ?, ?)",
                    (mid, c.scope, c.target, c.name, json.dumps(c.new), seq),
                )

        self.transaction(work)

    def versions(self, mid: str) -> dict[tuple[str, str, str], int]:
        """(scope, target, name) → version of every written value of a machine."""
        rows = self.query(
            "SELECT scope, target, name, version FROM param_values WHERE machine = ?", (mid,)
        )
        return {(r["scope"], r["target"], r["name"]): r["version"] for r in rows}

    def parameter_history(
        self, mid: str, limit: int = 1000
    ) -> list[tuple[int, float, str, dict[str, Any]]]:
        """(seq, time, actor, detail) of the newest `limit` parameter changes, oldest first."""
        rows = self.query(
            "SELECT seq, time, actor, detail FROM audit_log "
            "WHERE machine = ? AND kind = ? AND outcome = 'ok' ORDER BY seq DESC LIMIT ?",
            (mid, "parameter", limit),
        )
        return [(r["seq"], r["time"], r["actor"], json.loads(r["detail"])) for r in reversed(rows)]

    # --- the trace library (samples live in files next to the database) -----------------------
    def add_trace(
        self,
        tid: str,
        machine: str,
        created: float,
        name: str,
        notes: str,
        meta: str,
        created_by: str,
    ) -> None:
        with self._lock:
            self._db.execute(
                "INSERT INTO traces VALUES (?, ?, ?, ?, ?, ?, ?)",
                (tid, machine, created, name, notes, meta, created_by),
            )

    def trace_ids(self, created_by: str | None = None) -> list[str]:
        """The stored traces' ids (of the one who saved or imported them, when given)."""
        if created_by is None:
            return [str(r["id"]) for r in self.query("SELECT id FROM traces")]
        rows = self.query("SELECT id FROM traces WHERE created_by = ?", (created_by,))
        return [str(r["id"]) for r in rows]

    def traces(self, machine: str | None = None) -> list[StoredTrace]:
        """The stored traces, newest first."""
        q = "SELECT id, name, notes, meta FROM traces"
        args: tuple[str, ...] = ()
        if machine is not None:
            q, args = q + " WHERE machine = ?", (machine,)
        with self._lock:
            rows = self._db.execute(q + " ORDER BY created DESC", args).fetchall()
        return [_trace(r) for r in rows]

    def trace(self, tid: str) -> StoredTrace | None:
        with self._lock:
            r = self._db.execute(
                "SELECT id, name, notes, meta FROM traces WHERE id = ?", (tid,)
            ).fetchone()
        return _trace(r) if r else None

    def trace_machine(self, tid: str) -> str | None:
        """The machine a stored trace was captured on, None for no such trace."""
        rows = self.query("SELECT machine FROM traces WHERE id = ?", (tid,))
        return str(rows[0]["machine"]) if rows else None

    def update_trace(self, tid: str, name: str, notes: str) -> None:
        with self._lock:
            self._db.execute(
                "UPDATE traces SET name = ?, notes = ? WHERE id = ?", (name, notes, tid)
            )

    def delete_trace(self, tid: str) -> bool:
        with self._lock:
            cur = self._db.execute("DELETE FROM traces WHERE id = ?", (tid,))
        return cur.rowcount > 0

    # --- NC programs (by owner: service-wide '' or a class seat's own; then by name) ----------
    def programs(self, owners: tuple[str, ...]) -> list[StoredProgram]:
        """The programs of these owners without their text, by name (a name owned twice:
        the first owner's)."""
        marks = ", ".join("?" * len(owners))
        rows = self.query(
            f"SELECT name, size, lines, updated, updated_by, '' AS text, owner FROM programs "
            f"WHERE owner IN ({marks}) ORDER BY name COLLATE NOCASE",
            owners,
        )
        found: dict[str, StoredProgram] = {}
        for r in sorted(rows, key=lambda r: owners.index(r["owner"])):
            found.setdefault(r["name"].lower(), _program(r))
        return sorted(found.values(), key=lambda p: p.name.lower())

    def program(self, name: str, owners: tuple[str, ...]) -> StoredProgram | None:
        """The program `name` (any case) with its text, of the first of these owners that has
        one; None when none has."""
        for owner in owners:
            rows = self.query(
                "SELECT name, size, lines, updated, updated_by, text, owner FROM programs "
                "WHERE owner = ? AND name = ? COLLATE NOCASE",
                (owner, name),
            )
            if rows:
                return _program(rows[0])
        return None

    def put_program(
        self, name: str, text: str, entry: audit_log.Entry, owner: str = ""
    ) -> StoredProgram:
        """Create or replace an owner's program (one of another case is replaced and renamed)
        and append its audit row, in one transaction."""
        now = time.time() if entry.time is None else entry.time
        stored = StoredProgram(name, len(text), _lines(text), now, entry.actor, text, owner)

        def work(db: sqlite3.Connection) -> None:
            db.execute(
                "DELETE FROM programs WHERE owner = ? AND name = ? COLLATE NOCASE", (owner, name)
            )
            db.execute(
                "INSERT INTO programs VALUES (?, ?, ?, ?, ?, ?, ?)",
                (owner, name, text, stored.size, stored.lines, now, entry.actor),
            )
            audit_log.append(db, [replace(entry, time=now)])

        self.transaction(work)
        return stored

    def delete_program(self, name: str, entry: audit_log.Entry, owner: str = "") -> bool:
        """Delete an owner's program and audit it in one transaction; False when there was
        none."""

        def work(db: sqlite3.Connection) -> bool:
            cur = db.execute(
                "DELETE FROM programs WHERE owner = ? AND name = ? COLLATE NOCASE", (owner, name)
            )
            if cur.rowcount == 0:
                return False
            audit_log.append(db, [entry])
            return True

        return self.transaction(work)


def _trace(r: Row) -> StoredTrace:
    return StoredTrace(r["id"], r["name"], r["notes"], r["meta"])


def _program(r: Row) -> StoredProgram:
    return StoredProgram(
        r["name"], r["size"], r["lines"], r["updated"], r["updated_by"], r["text"], r["owner"]
    )


def _lines(text: str) -> int:
    """Lines as an editor counts them (a last line without its newline counts)."""
    return len(text.splitlines())


def _before_versions(db: sqlite3.Connection) -> None:
    """Step 1: a store made before the version table, of any age, gets what was added since
    the first ones; the parameter audit table of the first files becomes the start of the
    chained trail."""
    add_column(db, "param_values", "version", "INTEGER NOT NULL DEFAULT 0")
    add_column(db, "audit_log", "sim_t_s", "REAL")  # earlier rows have no simulated time
    add_column(db, "audit_log", "epoch", "INTEGER")
    add_column(db, "traces", "created_by", "TEXT NOT NULL DEFAULT ''")  # nobody's: service-wide
    programs = [c["name"] for c in db.execute("PRAGMA table_info(programs)")]
    if "owner" not in programs:  # programs were service-wide only: all of them stay so
        _programs_get_owners(db)
    if not has_table(db, "audit"):
        return
    carried = db.execute(
        "SELECT time, machine, actor, scope, target, name, old, new, effect, comment "
        "FROM audit ORDER BY seq"
    ).fetchall()
    entries = [
        parameter_entry(
            a["machine"],
            a["actor"],
            "",
            StoredChange(
                a["scope"],
                a["target"],
                a["name"],
                None if a["old"] is None else json.loads(a["old"]),
                json.loads(a["new"]),
                a["effect"],
            ),
            a["comment"],
            a["time"],
        )
        for a in carried
    ]
    audit_log.append(db, entries)
    db.execute("DROP TABLE audit")


def _request_ids(db: sqlite3.Connection) -> None:
    """Step 2: audit rows name the request that made them (the JSON log's `request_id`)."""
    add_column(db, "audit_log", "request_id", "TEXT NOT NULL DEFAULT ''")


# the schema's history (backend/services/migrations.py): append, never change a step taken
STEPS = (
    Step(1, "the schema of the stores before the version table", _before_versions),
    Step(2, "audit rows name their request", _request_ids),
)


def _programs_get_owners(db: sqlite3.Connection) -> None:
    """A store of an earlier version: its programs table (keyed by name alone) becomes the
    owner-keyed one, every program service-wide."""
    db.execute("ALTER TABLE programs RENAME TO programs_before_owners")
    db.execute("DROP INDEX IF EXISTS programs_name")
    db.execute(_PROGRAMS)
    db.execute(
        "INSERT INTO programs SELECT '', name, text, size, lines, updated, updated_by "
        "FROM programs_before_owners"
    )
    db.execute("DROP TABLE programs_before_owners")
