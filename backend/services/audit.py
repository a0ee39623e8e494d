"""The audit trail: every command, parameter change, control change, login and failed login,
with the real identity, time, machine and outcome, in the store.

Append-only twice over: triggers refuse UPDATE and DELETE, and each row carries the SHA-256 of
the row before it and of itself, so an edited, inserted or removed row breaks the chain where
it happened (`verify`), even when someone edits the file with the triggers dropped.
"""

from __future__ import annotations

import asyncio
import csv
import functools
import io
import json
import logging
import queue
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from api.audit import AuditPage, AuditRecord, AuditVerification
from backend.errors import ApiError
from backend.services.audit_log import COLUMNS, Entry, row_hash, who_and_when

if TYPE_CHECKING:
    from backend.services.store import Row, Store

log = logging.getLogger(__name__)

MAX_PAGE = 1000
BATCH_S = 0.05  # rows recorded later wait at most this long (plus the write) for the disk
CSV_ROWS = 100_000  # an export holds at most this many rows (newest)
# a row's fields the CSV shows as they are (after seq and time), and those its hash covers
# (audit_log.append: all but prev and hash)
_CSV_FIELDS = ("actor", "session", "address", "machine", "kind", "action", "detail", "outcome")
_HASHED = ("seq", "time", *_CSV_FIELDS)


_Written = Callable[[int | BaseException], None]  # told a row's seq once it is committed


def _settle(future: asyncio.Future[int], seq: int | BaseException) -> None:
    if future.done():  # the waiting request was cancelled (its client went away)
        return
    if isinstance(seq, BaseException):
        future.set_exception(seq)
    else:
        future.set_result(seq)


@dataclass(frozen=True)
class AuditFilter:
    """Which rows: all given conditions hold."""

    machine: str | None = None
    kind: str | None = None
    actor: str | None = None
    since_unix: float | None = None
    until_unix: float | None = None
    text: str | None = None  # in the action or the outcome
    kinds_left_out: tuple[str, ...] = ()

    def where(self) -> tuple[str, tuple[object, ...]]:
        conds: list[str] = []
        args: list[object] = []
        for column, value in (("machine", self.machine), ("kind", self.kind)):
            if value is not None:
                conds.append(f"{column} = ?")
                args.append(value)
        if self.kinds_left_out:
            conds.append(f"kind NOT IN ({', '.join('?' * len(self.kinds_left_out))})")
            args += self.kinds_left_out
        who, when = who_and_when(self.actor, self.since_unix, self.until_unix)
        conds += who
        args += when
        if self.text:
            conds.append("(instr(lower(action), ?) > 0 OR instr(lower(outcome), ?) > 0)")
            args += [self.text.lower(), self.text.lower()]
        return (" WHERE " + " AND ".join(conds) if conds else ""), tuple(args)


def _record(r: Row) -> AuditRecord:
    return AuditRecord(
        seq=r["seq"],
        time_unix=r["time"],
        actor=r["actor"],
        session=r["session"],
        address=r["address"],
        machine=r["machine"],
        kind=r["kind"],
        action=r["action"],
        detail=json.loads(r["detail"]),
        outcome=r["outcome"],
        hash=r["hash"],
        request_id=r["request_id"],
    )


class Audit:
    """Recording into, reading and checking the store's audit trail."""

    def __init__(self, store: Store) -> None:
        self.store = store
        # commands are recorded by a writer thread, in batches: the event loop that carries
        # them out never waits for the disk (a command's answer awaits its row's commit)
        self._later: queue.Queue[tuple[Entry, _Written | None] | None] = queue.Queue()
        self._hurry = threading.Event()  # someone waits for the rows: write them now
        self._writer = threading.Thread(target=self._write, name="audit-writer", daemon=True)
        self._writer.start()

    def record(self, entry: Entry) -> int:
        """Append one row now (after those waiting); its seq."""
        self.flush()
        return self.store.transaction(lambda db: self.store.append_audit(db, [entry]))[0]

    @contextmanager
    def refusals(self, entry: Entry) -> Iterator[None]:
        """Record `entry` with the refusal as its outcome if the block inside raises one (an
        attempt that changed nothing is worth recording too)."""
        try:
            yield
        except ApiError as e:
            self.record_later(replace(entry, outcome=f"refused ({e.status}): {e}"))
            raise

    def queue_depth(self) -> int:
        """Entries waiting for the writer thread."""
        return self._later.qsize()

    def record_later(self, entry: Entry, written: _Written | None = None) -> None:
        """Append one row soon, in order, without waiting (`written` is told its seq, or the
        error, on the writer's thread once the row is committed)."""
        self._later.put((entry, written))

    async def recorded(self, entry: Entry) -> int:
        """Append one row and wait, without holding up the event loop, until it is committed
        (it survives a crash of the service from then on); its seq. The writer writes at once
        for it, without the batch's gathering time."""
        loop = asyncio.get_running_loop()
        future: asyncio.Future[int] = loop.create_future()

        def written(seq: int | BaseException) -> None:
            loop.call_soon_threadsafe(_settle, future, seq)

        self.record_later(entry, written)
        self._hurry.set()
        return await future

    def flush(self) -> None:
        """Wait until every row given to `record_later` is written (at once, not after the
        batch's gathering time)."""
        self._hurry.set()
        self._later.join()
        self._hurry.clear()

    def stop(self) -> None:
        self._later.put(None)
        self._writer.join(timeout=5.0)

    def _write(self) -> None:
        while True:
            batch = [self._later.get()]
            if batch[0] is not None:  # let a burst gather: one wake-up and one commit for it,
                self._hurry.wait(BATCH_S)  # not a GIL hand-over from the event loop per command
            while not self._later.empty() and len(batch) < 500:
                batch.append(self._later.get_nowait())
            items = [i for i in batch if i is not None]
            outcome: list[int] | BaseException = []
            try:
                if items:
                    entries = [entry for entry, _ in items]
                    outcome = self.store.transaction(
                        functools.partial(self.store.append_audit, entries=entries)
                    )
            except Exception as e:  # the store is closed or failing: say so, keep serving
                log.exception("audit rows lost: %d", len(items))
                outcome = e
            finally:
                for k, (_, written) in enumerate(items):
                    if written is not None:
                        written(outcome if isinstance(outcome, BaseException) else outcome[k])
                for _ in batch:
                    self._later.task_done()
            if None in batch:
                return

    def page(self, f: AuditFilter, limit: int = 200, before_seq: int | None = None) -> AuditPage:
        """Matching rows, newest first (older ones: `before_seq`), and how many match."""
        self.flush()
        where, args = f.where()
        total = self.store.query(f"SELECT count(*) AS n FROM audit_log{where}", args)[0]["n"]
        if before_seq is not None:
            where += (" AND" if where else " WHERE") + " seq < ?"
            args += (before_seq,)
        rows = self.store.query(
            f"SELECT {COLUMNS}, request_id FROM audit_log{where} ORDER BY seq DESC LIMIT ?",
            (*args, min(limit, MAX_PAGE)),
        )
        return AuditPage(rows=[_record(r) for r in rows], total=total)

    def csv(self, f: AuditFilter) -> str:
        """Matching rows as CSV (oldest first, at most CSV_ROWS), for a spreadsheet."""
        self.flush()
        where, args = f.where()
        rows = self.store.query(
            f"SELECT {COLUMNS}, request_id FROM audit_log{where} ORDER BY seq DESC LIMIT ?",
            (*args, CSV_ROWS),
        )
        out = io.StringIO()
        writer = csv.writer(out)
        writer.writerow(
            [
                "seq",
                "time_utc",
                "actor",
                "session",
                "address",
                "machine",
                "kind",
                "action",
                "detail",
                "outcome",
                "hash",
            ]
        )
        for r in reversed(rows):
            stamp = (
                time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(r["time"]))
                + f".{int(r['time'] % 1 * 1000):03d}Z"
            )
            writer.writerow([r["seq"], stamp, *(r[c] for c in _CSV_FIELDS), r["hash"]])
        return out.getvalue()

    def verify(self) -> AuditVerification:
        """Recompute the chain from the first row: the first row edited, inserted or lost."""
        self.flush()
        rows = self.store.query(f"SELECT {COLUMNS} FROM audit_log ORDER BY seq")
        prev = ""
        for i, r in enumerate(rows, start=1):
            if r["seq"] != i:
                return AuditVerification(
                    ok=False, rows=i - 1, first_bad_seq=i, message=f"row {i} is missing"
                )
            fields = tuple(r[c] for c in _HASHED)
            if r["prev"] != prev or row_hash(prev, fields) != r["hash"]:
                return AuditVerification(
                    ok=False,
                    rows=i - 1,
                    first_bad_seq=r["seq"],
                    message=f"row {r['seq']} was changed after it was written",
                )
            prev = r["hash"]
        return AuditVerification(ok=True, rows=len(rows), message=f"all {len(rows)} rows intact")
