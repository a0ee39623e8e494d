"""One service per store: `inbetrieb serve` holds an exclusive lock beside the store file for
as long as it runs, so a second service on the same store (two gateways in a compose file,
a unit started twice) and a restore over a served store are refused, instead of two writers
losing each other's rows. The lock is the kernel's (flock): it goes with the process, a
killed service leaves nothing to clean up."""

from __future__ import annotations

import fcntl
import os
from pathlib import Path
from typing import IO


class StoreInUse(Exception):
    """Another process serves this store."""


def lock_path(db: Path) -> Path:
    return db.with_name(db.name + ".lock")


def hold(db: Path) -> IO[str]:
    """Take the store's lock for this process (keep the returned file open while serving);
    StoreInUse when another process holds it."""
    db.parent.mkdir(parents=True, exist_ok=True)
    f = lock_path(db).open("a+")
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        f.seek(0)
        holder = f.read().strip() or "?"
        f.close()
        raise StoreInUse(
            f"{db} is served by another process (pid {holder}): stop it first"
        ) from None
    f.truncate(0)
    f.write(f"{os.getpid()}\n")
    f.flush()
    return f


def check_free(db: Path) -> None:
    """StoreInUse when a service holds the store's lock now."""
    if lock_path(db).exists():
        hold(db).close()
