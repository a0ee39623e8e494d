"""`inbetrieb backup FILE` and `inbetrieb restore FILE`: the store and the trace directory
(traces, scope recordings, bundles) in one archive.

The store is copied with SQLite's online backup while the service may be writing: the copy is
one consistent state of the file (every write acknowledged before the backup began is in it;
one acknowledged during it may be). The trace files are copied after it: a trace the store
does not know yet is harmless, one the store knows was written before. Restore puts the
archive's store and traces in place of the service's (which must not run), keeping what was
there beside it as `*.before-restore-<time>`, and checks the store's integrity.
"""

from __future__ import annotations

import io
import json
import shutil
import sqlite3
import tarfile
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from backend import VERSION
from backend.services import migrations, store_lock
from backend.services.store import STEPS

ROOT = "inbetrieb"  # the archive's top folder
STORE = f"{ROOT}/store.sqlite"
TRACES = f"{ROOT}/traces"
MANIFEST = f"{ROOT}/manifest.json"


class BackupError(Exception):
    """A backup or restore that cannot be done, in words."""


@dataclass(frozen=True)
class Summary:
    """What an archive holds."""

    created_unix: float
    version: str
    store_bytes: int
    trace_files: int
    tables: dict[str, int]  # rows of the main tables


def _integrity(db: Path) -> None:
    con = sqlite3.connect(db)
    try:
        found = con.execute("PRAGMA integrity_check").fetchone()[0]
    finally:
        con.close()
    if found != "ok":
        raise BackupError(f"{db}: integrity check says {found}")


def _tables(db: Path) -> dict[str, int]:
    con = sqlite3.connect(db)
    try:
        names = [
            r[0]
            for r in con.execute(
                "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'"
            )
        ]
        return {n: con.execute(f'SELECT count(*) FROM "{n}"').fetchone()[0] for n in sorted(names)}
    finally:
        con.close()


def backup(db: Path, traces: Path, out: Path) -> Summary:
    """Write the archive `out` (tar.gz) of the store `db` and the folder `traces`."""
    if not db.exists():
        raise BackupError(f"no store at {db}")
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / "store.sqlite"
        src = sqlite3.connect(db)
        dst = sqlite3.connect(copy)
        try:
            src.backup(dst)  # SQLite's online backup: one consistent state while it is written
        finally:
            dst.close()
            src.close()
        _integrity(copy)
        files = sorted(p for p in traces.rglob("*") if p.is_file()) if traces.exists() else []
        summary = Summary(time.time(), VERSION, copy.stat().st_size, len(files), _tables(copy))
        part = out.with_name(out.name + ".part")
        with tarfile.open(part, "w:gz") as tar:
            tar.add(copy, STORE)
            for f in files:
                tar.add(f, f"{TRACES}/{f.relative_to(traces).as_posix()}")
            manifest = json.dumps(summary.__dict__, indent=1).encode()
            info = tarfile.TarInfo(MANIFEST)
            info.size, info.mtime = len(manifest), int(summary.created_unix)
            tar.addfile(info, io.BytesIO(manifest))
        part.replace(out)
    return summary


def restore(archive: Path, db: Path, traces: Path) -> Summary:
    """Put the archive's store and traces in place (the service stopped): what was there is
    kept beside as `*.before-restore-<time>`; the restored store's integrity is checked."""
    if not archive.exists():
        raise BackupError(f"no archive at {archive}")
    try:
        store_lock.check_free(db)
    except store_lock.StoreInUse as e:
        raise BackupError(str(e)) from None
    with tempfile.TemporaryDirectory() as tmp:
        try:
            with tarfile.open(archive, "r:gz") as tar:
                tar.extractall(tmp, filter="data")  # no path outside, no links out, no devices
        except (tarfile.TarError, OSError) as e:
            raise BackupError(f"{archive}: not an Inbetrieb backup ({e})") from None
        root = Path(tmp)
        store = root / STORE
        if not store.exists() or not (root / MANIFEST).exists():
            raise BackupError(f"{archive}: not an Inbetrieb backup (no {STORE} or manifest)")
        _integrity(store)
        try:  # a newer release's store would be refused at start: leave what is there
            migrations.check_file(store, STEPS)
        except migrations.StoreTooNew as e:
            raise BackupError(f"{archive}: {e}") from None
        summary = Summary(**json.loads((root / MANIFEST).read_text()))
        stamp = time.strftime("%Y%m%d-%H%M%S")
        db.parent.mkdir(parents=True, exist_ok=True)
        for old in (db, db.with_name(db.name + "-wal"), db.with_name(db.name + "-shm")):
            if old.exists():
                old.rename(old.with_name(f"{old.name}.before-restore-{stamp}"))
        if traces.exists():
            traces.rename(traces.with_name(f"{traces.name}.before-restore-{stamp}"))
        shutil.copyfile(store, db)
        if (root / TRACES).exists():
            shutil.copytree(root / TRACES, traces)
        else:
            traces.mkdir(parents=True)
    _integrity(db)
    return summary
