"""The audit trail's table: its rows, chained by hash, appended and never changed (the
service around it, backend/services/audit.py; the store that holds it, store.py)."""

from __future__ import annotations

import hashlib
import json
import sqlite3
import time
from dataclasses import dataclass, field
from typing import Any

from api.audit import AuditKind

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
    hash TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS audit_log_machine ON audit_log (machine, kind);
CREATE TRIGGER IF NOT EXISTS audit_log_no_update BEFORE UPDATE ON audit_log
BEGIN SELECT RAISE(ABORT, 'the audit trail is append-only'); END;
CREATE TRIGGER IF NOT EXISTS audit_log_no_delete BEFORE DELETE ON audit_log
BEGIN SELECT RAISE(ABORT, 'the audit trail is append-only'); END;
"""
COLUMNS = "seq, time, actor, session, address, machine, kind, action, detail, outcome, prev, hash"


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


def row_hash(prev: str, fields: tuple[object, ...]) -> str:
    """A row's link in the chain: the hash of the row before and this row's fields."""
    text = "\x1f".join([prev, *(repr(f) if isinstance(f, float) else str(f) for f in fields)])
    return hashlib.sha256(text.encode()).hexdigest()


def append(db: sqlite3.Connection, entries: list[Entry]) -> list[int]:
    """Chain the entries onto the trail (inside the caller's transaction); their seqs."""
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
        db.execute(
            f"INSERT INTO audit_log ({COLUMNS}) VALUES ({', '.join('?' * 12)})",
            (*fields, prev, digest),
        )
        prev = digest
        seqs.append(seq)
    return seqs
