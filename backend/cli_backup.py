"""`inbetrieb backup FILE` and `inbetrieb restore FILE` (backend/backup.py): the store and
the traces in one archive; a backup while the service runs, a restore while it is stopped."""

from __future__ import annotations

import argparse
import sqlite3
import sys
from pathlib import Path

from backend.backup import BackupError, Summary, backup, restore
from backend.settings import Settings


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p_b = sub.add_parser("backup", help="the store and the traces into one archive (online)")
    p_b.add_argument("file", type=Path, help="the archive to write (.tar.gz)")
    p_r = sub.add_parser("restore", help="the store and the traces from an archive (stopped)")
    p_r.add_argument("file", type=Path, help="an archive `inbetrieb backup` wrote")
    for p in (p_b, p_r):
        p.add_argument("--db", type=Path, help="SQLite file (default var/inbetrieb.sqlite)")
        p.add_argument("--traces", type=Path, help="trace folder (default: beside the store)")


def _say(what: str, s: Summary) -> None:
    main = ("users", "machines", "param_values", "audit_log", "traces", "classes")
    rows = ", ".join(f"{t} {s.tables[t]}" for t in main if t in s.tables)
    print(f"{what}: store {s.store_bytes} bytes ({rows}), {s.trace_files} trace files")


def run(args: argparse.Namespace) -> int:
    """0, or 2 with the reason on stderr."""
    settings = Settings(db_path=args.db) if args.db else Settings()
    traces = args.traces or settings.traces_path
    try:
        if args.cmd == "backup":
            _say(f"backed up to {args.file}", backup(settings.db_path, traces, args.file))
        else:
            _say(f"restored from {args.file}", restore(args.file, settings.db_path, traces))
    except (BackupError, OSError, sqlite3.Error) as e:  # a full disk, a folder not there
        print(f"inbetrieb {args.cmd}: {e}", file=sys.stderr)
        return 2
    return 0
