"""The store's schema version: which release's tables a store file holds, and the steps that
bring an older file up to this release's.

The steps are numbered from 1 (the schema of every store made before this table); a store
records each step it has taken in `schema_version`. Opening a store takes the steps it
lacks, in order, each in a transaction of its own, before any service reads a table. A new
store is made by the services' own `CREATE TABLE` statements as they are now, so it is
recorded at the newest version without taking the steps.

A store of a newer release is refused: this release would not know its tables, and writing
to them could lose what the newer one wrote. The fix is to run the newer release (or restore
a backup this release made).
"""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

_TABLE = """
CREATE TABLE IF NOT EXISTS schema_version (
    version INTEGER PRIMARY KEY,   -- a step taken (1, 2, …)
    what TEXT NOT NULL,            -- what it changed
    release TEXT NOT NULL,         -- the release that took it
    time REAL NOT NULL             -- Unix time
)
"""


class StoreTooNew(Exception):
    """The store was written by a newer release than this one (its schema has more steps)."""


@dataclass(frozen=True)
class Step:
    """One change of the schema. `run` must allow for a table that is not there (a store
    older than a service's table gets that table new, from the service's CREATE)."""

    version: int
    what: str
    run: Callable[[sqlite3.Connection], None]


def stored_version(db: sqlite3.Connection) -> int:
    """The last step the store has taken; 0 for a store older than the version table."""
    if not has_table(db, "schema_version"):
        return 0
    found = db.execute("SELECT max(version) AS v FROM schema_version").fetchone()
    return int(found["v"] or 0)


def has_table(db: sqlite3.Connection, name: str) -> bool:
    query = "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?"
    return db.execute(query, (name,)).fetchone() is not None


def add_column(db: sqlite3.Connection, table: str, column: str, definition: str) -> None:
    """ALTER TABLE … ADD COLUMN, unless the table is not there or has the column already."""
    if not has_table(db, table):
        return
    columns = [c["name"] for c in db.execute(f'PRAGMA table_info("{table}")')]
    if column not in columns:
        db.execute(f'ALTER TABLE "{table}" ADD COLUMN {column} {definition}')


def is_new(db: sqlite3.Connection) -> bool:
    """A file with no tables at all (a store about to be made)."""
    return db.execute("SELECT 1 FROM sqlite_master WHERE type = 'table'").fetchone() is None


def too_new(found: int, steps: Sequence[Step], what: str) -> StoreTooNew:
    return StoreTooNew(
        f"{what} has schema version {found}, this release knows up to {steps[-1].version}: "
        "it was written by a newer release of Inbetrieb; run that one (or restore a backup "
        "this release made)"
    )


def upgrade(
    db: sqlite3.Connection, steps: Sequence[Step], release: str, new: bool, what: str
) -> list[Step]:
    """Take the steps the store lacks (a `new` store is recorded at the newest version);
    the steps taken. Raises StoreTooNew for a store of a newer release."""
    db.execute(_TABLE)
    found = stored_version(db)
    if found > steps[-1].version:
        raise too_new(found, steps, what)
    if new:
        with db:
            db.execute("BEGIN")
            for step in steps:
                _record(db, step, release)
        return []
    todo = [s for s in steps if s.version > found]
    for step in todo:
        with db:
            db.execute("BEGIN")
            step.run(db)
            _record(db, step, release)
    return todo


def _record(db: sqlite3.Connection, step: Step, release: str) -> None:
    db.execute(
        "INSERT INTO schema_version VALUES (?, ?, ?, ?)",
        (step.version, step.what, release, time.time()),
    )


def check_file(path: Path, steps: Sequence[Step]) -> None:
    """Raise StoreTooNew when the store file at `path` is of a newer release (read only; a
    file that is not there is fine)."""
    if not path.exists():
        return
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    con.row_factory = sqlite3.Row  # columns by name, as the store's own connection
    try:
        found = stored_version(con)
    finally:
        con.close()
    if found > steps[-1].version:
        raise too_new(found, steps, str(path))
