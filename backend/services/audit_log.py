"""The audit trail's table: its rows, chained by hash, appended and never changed (the
service around it, backend/services/audit.py; the store that holds it, store.py)."""

from __future__ import annotations

import hashlib
import json
import sqlite3
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from api.audit import AuditKind
from backend.logs import request_id

SCHEMA = """
CREATE TABLE IF NOT EXISTS audit_log (
    seq INTEGER PRIMARY KEY,       -- 1, 2, 3, ...: a gap is a removed row
    time REAL NOT NULL,
    actor TEXT NOT NULL,
    session TEXT NOT NULL,
    address TEXT NOT NULL,
    machine TEXT NOT NULL,         -- '' for service-wide rows
    kind TEXT NOT NULL,
    action TEXT NOT NULL,
    detail TEXT NOT NULL,          -- JSON, keys sorted
    outcome TEXT NOT NULL,
    prev TEXT NOT NULL,            -- the row before's hash ('' before the first)
    hash TEXT NOT NULL,
    sim_t_s REAL,                  -- the machine's simulated time then (not hashed: a stamp)
    epoch INTEGER,                 -- the machine's build then
    request_id TEXT NOT NULL DEFAULT ''  -- the request that made it (the log's; not hashed)
);
CREATE INDEX IF NOT EXISTS audit_log_machine ON audit_log (machine, kind);
CREATE INDEX IF NOT EXISTS audit_log_machine_time ON audit_log (machine, time);
CREATE TRIGGER IF NOT EXISTS audit_log_no_update BEFORE UPDATE ON audit_log
BEGIN SELECT RAISE(ABORT, 'the audit trail is append-only'); END;
CREATE TRIGGER IF NOT EXISTS audit_log_no_delete BEFORE DELETE ON audit_log
BEGIN SELECT RAISE(ABORT, 'the audit trail is append-only'); END;
"""
COLUMNS = "seq, time, actor, session, address, machine, kind, action, detail, outcome, prev, hash"
# a machine's build and simulated time now (None: no such machine): stamps its rows
Clock = Callable[[str], tuple[int, float] | None]


@dataclass(frozen=True)
class Entry:
    """One thing to record. `time` is now unless given (rows carried over from older files)."""

    actor: str
    session: str
    kind: AuditKind
    action: str
    machine: str = ""
    detail: dict[str, Any] = field(default_factory=dict)
    outcome: str = "ok"
    address: str = ""
    time: float | None = None
    # the machine's build and simulated time it happened at (None: when it is written)
    stamp: tuple[int, float] | None = None
    request_id: str = field(default_factory=request_id)  # the request being served, if any


def who_and_when(
    actor: str | None, since_unix: float | None, until_unix: float | None
) -> tuple[list[str], list[object]]:
    """SQL conditions (and their arguments) on a row's `actor` (part of the name, any case:
    "be" finds ben and Bert) and its `time` (since ≤ time < until)."""
    conds: list[str] = []
    args: list[object] = []
    if actor:
        conds.append("instr(lower(actor), ?) > 0")
        args.append(actor.lower())
    if since_unix is not None:
        conds.append("time >= ?")
        args.append(since_unix)
    if until_unix is not None:
        conds.append("time < ?")
        args.append(until_unix)
    return conds, args


def row_hash(prev: str, fields: tuple[object, ...]) -> str:
    """A row's link in the chain: the hash of the row before and this row's fields."""
    text = "\x1f".join([prev, *(repr(f) if isinstance(f, float) else str(f) for f in fields)])
    return hashlib.sha256(text.encode()).hexdigest()


def append(db: sqlite3.Connection, entries: list[Entry], clock: Clock | None = None) -> list[int]:
    """Chain the entries onto the trail (inside the caller's transaction); their seqs. A
    machine's rows are stamped with its build and simulated time by `clock`."""
    last = db.execute("SELECT seq, hash FROM audit_log ORDER BY seq DESC LIMIT 1").fetchone()
    seq, prev = (last["seq"], last["hash"]) if last else (0, "")
    now = time.time()
    seqs = []
    for e in entries:
        seq += 1
        fields = (
            seq,
            float(e.time if e.time is not None else now),
            e.actor,
            e.session,
            e.address,
            e.machine,
            e.kind,
            e.action,
            json.dumps(e.detail, sort_keys=True, separators=(",", ":"), default=str),
            e.outcome,
        )
        digest = row_hash(prev, fields)
        stamp = e.stamp or (clock(e.machine) if clock is not None and e.machine else None)
        db.execute(
            f"INSERT INTO audit_log ({COLUMNS}, epoch, sim_t_s, request_id) "
            f"VALUES ({', '.join('?' * 15)})",
            (*fields, prev, digest, *(stamp or (None, None)), e.request_id),
        )
        prev = digest
        seqs.append(seq)
    return seqs
