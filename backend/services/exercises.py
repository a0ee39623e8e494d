"""The service's exercises: the shipped files in `exercises/` and those instructors upload
(kept in the store), parsed by nc_sim.training."""

from __future__ import annotations

import threading
import time
from pathlib import Path

from api.classes import CheckInfo, ExerciseInfo, HintInfo
from backend.errors import Conflict, Invalid, not_found
from backend.services.store import Store
from nc_sim.errors import NcUsageError
from nc_sim.params import ParamListError
from nc_sim.training.exercise import Exercise, ExerciseError, parse_exercise
from nc_sim.training.template import check_fits

SHIPPED = Path(__file__).resolve().parents[2] / "exercises"
MAX_UPLOADED = 200

SCHEMA = """
CREATE TABLE IF NOT EXISTS exercises (  -- backend/services/exercises.py: uploaded ones
    id TEXT PRIMARY KEY,
    text TEXT NOT NULL,
    user TEXT NOT NULL,
    time REAL NOT NULL
);
"""


def exercise_info(ex: Exercise, source: str, hints_taken: set[int] | None = None) -> ExerciseInfo:
    """An exercise as the API lists it; a hint's text only once taken (`hints_taken`), all
    of them for None (the instructor)."""
    return ExerciseInfo(
        id=ex.id,
        title=ex.title,
        summary=ex.summary,
        task=ex.task,
        par_time_s=ex.par_time_s,
        checks=[CheckInfo(id=c.id, text=c.text, points=c.points) for c in ex.checks],
        hints=hint_infos(ex, hints_taken),
        faults=len(ex.faults),
        source=source,
        locked_assistants=list(ex.locked),
        varied=[v.key for v in ex.vary],
    )


def hint_infos(ex: Exercise, taken: set[int] | None) -> list[HintInfo]:
    """The hints with their text where taken (all for None)."""
    return [
        HintInfo(n=i, cost=h.cost, text=h.text if taken is None or i in taken else None)
        for i, h in enumerate(ex.hints, start=1)
    ]


class Exercises:
    """Shipped and uploaded exercises by id (an upload may not replace a shipped one)."""

    def __init__(self, store: Store, shipped: Path = SHIPPED) -> None:
        self.store = store
        store.script(SCHEMA)
        self._lock = threading.Lock()
        self._by_id: dict[str, tuple[Exercise, str, str]] = {}  # id -> (exercise, source, text)
        for path in sorted(shipped.glob("*.toml")):
            text = path.read_text(encoding="utf-8")
            ex = parse_exercise(text, path.name)  # a broken shipped file stops the start
            check_fits(ex, path.name)
            self._by_id[ex.id] = (ex, f"shipped: {path.name}", text)
        self._shipped = frozenset(self._by_id)
        for r in store.query("SELECT id, text, user FROM exercises ORDER BY time"):
            try:
                ex = parse_exercise(r["text"], f"uploaded {r['id']}")
            except ExerciseError:
                continue  # stored under an older format: listed no more
            self._by_id[ex.id] = (ex, f"uploaded by {r['user']}", r["text"])

    def list(self) -> list[ExerciseInfo]:
        with self._lock:
            found = list(self._by_id.values())
        return [exercise_info(ex, source) for ex, source, _ in found]

    def get(self, eid: str) -> tuple[Exercise, str]:
        """The exercise and its TOML text; 404 when there is none."""
        with self._lock:
            found = self._by_id.get(eid)
        if found is None:
            raise not_found(f"exercise '{eid}'")
        return found[0], found[2]

    def info(self, eid: str) -> ExerciseInfo:
        with self._lock:
            found = self._by_id.get(eid)
        if found is None:
            raise not_found(f"exercise '{eid}'")
        return exercise_info(found[0], found[1])

    @staticmethod
    def check(text: str, source: str = "upload") -> Exercise:
        """Parse an exercise file and check it against its machine; 422 with the file's own
        words (the key, the value, what is allowed; a TOML error's line and column)."""
        try:
            ex = parse_exercise(text, source)
            check_fits(ex, source)  # its axes and values fit its machine template
        except (ExerciseError, ParamListError, NcUsageError) as e:
            raise Invalid(str(e)) from None
        return ex

    def text(self, eid: str) -> str:
        """An exercise's file as it was shipped or uploaded; 404 when there is none."""
        return self.get(eid)[1]

    def remove(self, eid: str) -> None:
        """Forget an uploaded exercise (classes that ran it keep their copy); 409 for a
        shipped one, 404 for none."""
        with self._lock:
            if eid in self._shipped:
                raise Conflict(f"exercise '{eid}' is shipped: it stays")
            if self._by_id.pop(eid, None) is None:
                raise not_found(f"exercise '{eid}'")
        self.store.run("DELETE FROM exercises WHERE id = ?", (eid,))

    def upload(self, text: str, user: str) -> ExerciseInfo:
        """Parse and keep an exercise file; 422 with the file's own words when it is wrong,
        409 for a shipped id."""
        ex = self.check(text)
        with self._lock:
            if ex.id in self._shipped:
                raise Conflict(f"exercise '{ex.id}' is shipped: choose an id")
            if ex.id not in self._by_id and len(self._by_id) >= MAX_UPLOADED + len(self._shipped):
                raise Conflict(f"at most {MAX_UPLOADED} uploaded exercises")
            self._by_id[ex.id] = (ex, f"uploaded by {user}", text)
        self.store.run(
            "INSERT OR REPLACE INTO exercises VALUES (?, ?, ?, ?)", (ex.id, text, user, time.time())
        )
        return exercise_info(ex, f"uploaded by {user}")
