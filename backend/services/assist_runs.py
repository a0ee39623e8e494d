"""Stored assistant runs: every successful run of an assistant (on a copy or live) with who ran
it, when, its inputs and its whole answer, for the list in the HMI and the commissioning
report. Rows live in the store's `assist_runs` table and go with the machine.
"""

from __future__ import annotations

import asyncio
import json
import time
from typing import Any

from api.assist import AssistResult
from api.report import AssistRun, AssistRunInfo
from backend.errors import not_found
from backend.services.store import Row, Store
from nc_sim.assist.registry import BY_NAME

MAX_LIST = 200  # runs in one list (newest)
# what it measured, for an assistant that measures several things (SQLite reads it out of
# the stored JSON: a list needs no result parsed in Python)
_INFO = (
    "id, machine, assistant, user, time, live, ok, axis, summary, "
    "json_extract(result, '$.inputs.measurement') AS measurement"
)


def summary(result: AssistResult) -> str:
    """The main figures in words: 'k = 8.75 1/s, f = 2.29; 3 changes proposed' (the
    descriptor's summary figures, else the first three)."""
    a = BY_NAME.get(result.assistant)
    names = a.summary if a else ()
    figs = (
        [f for n in names for f in result.figures if f.name == n] if names else result.figures[:3]
    )
    text = ", ".join(f"{f.name} = {f.value:.4g}{' ' + f.unit if f.unit else ''}" for f in figs)
    n = len(result.changes)
    proposal = f"{n} change{'s' if n != 1 else ''} proposed" if n else "no change proposed"
    return f"{text}; {proposal}" if text else proposal


def _info(r: Row) -> AssistRunInfo:
    return AssistRunInfo(
        id=r["id"],
        machine=r["machine"],
        assistant=r["assistant"],
        user=r["user"],
        time_unix=r["time"],
        live=bool(r["live"]),
        ok=bool(r["ok"]),
        axis=r["axis"],
        summary=r["summary"],
        measurement=r["measurement"],
    )


class AssistRuns:
    """Recording and reading the stored runs."""

    def __init__(self, store: Store) -> None:
        self.store = store

    async def record(self, mid: str, user: str, result: AssistResult, live: bool) -> int:
        """Store one successful run of machine `mid` by `user` (live: on the live machine);
        its id."""
        return await asyncio.to_thread(self.add, mid, user, result, live, time.time())

    def add(self, mid: str, user: str, result: AssistResult, live: bool, when: float) -> int:
        """`record` on the calling thread, at a given time."""
        axis = result.inputs.get("axis", result.inputs.get("spindle", ""))
        row = (
            mid,
            result.assistant,
            user,
            when,
            int(live),
            int(result.ok),
            str(axis),
            summary(result),
            result.model_dump_json(),
        )

        def work(db: Any) -> int:
            cur = db.execute(
                "INSERT INTO assist_runs "
                "(machine, assistant, user, time, live, ok, axis, summary, result) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                row,
            )
            return int(cur.lastrowid)

        return self.store.transaction(work)

    def latest(self, mid: str, limit: int = MAX_LIST) -> list[AssistRunInfo]:
        """The machine's runs, newest first (at most `limit`, bounded by MAX_LIST)."""
        rows = self.store.query(
            f"SELECT {_INFO} FROM assist_runs WHERE machine = ? ORDER BY id DESC LIMIT ?",
            (mid, max(0, min(limit, MAX_LIST))),
        )
        return [_info(r) for r in rows]

    def runs(self, mid: str, limit: int = MAX_LIST) -> list[AssistRun]:
        """The machine's runs with their results, oldest first (the newest `limit`)."""
        rows = self.store.query(
            f"SELECT {_INFO}, result FROM assist_runs WHERE machine = ? ORDER BY id DESC LIMIT ?",
            (mid, max(0, min(limit, MAX_LIST))),
        )
        return [_run(r) for r in reversed(rows)]

    def get(self, mid: str, run_id: int) -> AssistRun:
        """One run of the machine; 404 when it has none of that id."""
        rows = self.store.query(
            f"SELECT {_INFO}, result FROM assist_runs WHERE machine = ? AND id = ?",
            (mid, run_id),
        )
        if not rows:
            raise not_found(f"assistant run {run_id} of machine {mid}")
        return _run(rows[0])


def _run(r: Row) -> AssistRun:
    info = _info(r)
    result = AssistResult.model_validate(json.loads(r["result"]) | {"run_id": info.id})
    return AssistRun(**info.model_dump(), result=result)
