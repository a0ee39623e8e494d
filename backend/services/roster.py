"""The trainer's roster: a class made with `roster` puts its named students on it (found by
name, any case, or added) and links each to their seat; a student's record gathers their
seats' results across classes. Logins stay per seat and class (one-time links)."""

from __future__ import annotations

import threading
import time

from api.roster import MAX_ROSTER, RosterStudent, StudentRecord, StudentSession
from backend.errors import Conflict, not_found
from backend.services.classes import Classes
from backend.services.seats import Class
from backend.services.store import Row, Store

SCHEMA = """
CREATE TABLE IF NOT EXISTS roster (  -- backend/services/roster.py
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL UNIQUE COLLATE NOCASE,
    created REAL NOT NULL,
    by TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS roster_seats (  -- a roster student's seat in a class
    person INTEGER NOT NULL,
    class TEXT NOT NULL,
    n INTEGER NOT NULL,
    PRIMARY KEY (class, n)
);
CREATE INDEX IF NOT EXISTS roster_seats_person ON roster_seats (person);
"""


class Roster:
    def __init__(self, store: Store, classes: Classes) -> None:
        self.store = store
        self.classes = classes
        store.script(SCHEMA)
        self._lock = threading.Lock()

    def enrol(self, c: Class, by: str) -> None:
        """The class's named seats (not 'Seat n') as roster students, found or added."""
        with self._lock:
            for seat in c.seats:
                if seat.student == f"Seat {seat.n}":
                    continue
                pid = self._find_or_add(seat.student, by)
                self.store.run(
                    "INSERT OR REPLACE INTO roster_seats VALUES (?, ?, ?)", (pid, c.id, seat.n)
                )

    def _find_or_add(self, name: str, by: str) -> int:
        rows = self.store.query("SELECT id FROM roster WHERE name = ?", (name,))
        if rows:
            return int(rows[0]["id"])
        count = self.store.query("SELECT count(*) AS n FROM roster")[0]["n"]
        if count >= MAX_ROSTER:
            raise Conflict(f"the roster holds {MAX_ROSTER} students: remove some first")
        self.store.run(
            "INSERT INTO roster (name, created, by) VALUES (?, ?, ?)", (name, time.time(), by)
        )
        return int(self.store.query("SELECT id FROM roster WHERE name = ?", (name,))[0]["id"])

    def person_of(self, class_id: str, n: int) -> int | None:
        """The roster student of a class's seat (None: a seat's login only)."""
        rows = self.store.query(
            "SELECT person FROM roster_seats WHERE class = ? AND n = ?", (class_id, n)
        )
        return int(rows[0]["person"]) if rows else None

    def people(self) -> list[RosterStudent]:
        """Everybody on the roster, by name."""
        rows = self.store.query(
            "SELECT r.id, r.name, r.created, r.by, count(s.class) AS classes FROM roster r "
            "LEFT JOIN roster_seats s ON s.person = r.id GROUP BY r.id ORDER BY r.name"
        )
        return [self._student(r) for r in rows]

    def _student(self, r: Row) -> RosterStudent:
        seats = self.store.query("SELECT class FROM roster_seats WHERE person = ?", (r["id"],))
        began = [self.classes.get(s["class"]).created_unix for s in seats]
        return RosterStudent(
            id=r["id"],
            name=r["name"],
            classes=r["classes"],
            last_unix=max(began) if began else None,
            created_unix=r["created"],
            by=r["by"],
        )

    def record(self, pid: int) -> StudentRecord:
        """A student's classes, newest first, with their results in each (404: none such)."""
        rows = self.store.query(
            "SELECT r.id, r.name, r.created, r.by, count(s.class) AS classes FROM roster r "
            "LEFT JOIN roster_seats s ON s.person = r.id WHERE r.id = ? GROUP BY r.id",
            (pid,),
        )
        if not rows:
            raise not_found(f"student {pid} of the roster")
        sessions = []
        for s in self.store.query("SELECT class, n FROM roster_seats WHERE person = ?", (pid,)):
            c = self.classes.get(s["class"])
            seat = self.classes.seat(c.id, s["n"])
            at = c.ended_unix or time.time()
            stages = [*seat.done, self.classes.stage_result(c, seat, "", at)]
            sessions.append(
                StudentSession(
                    class_id=c.id,
                    title=c.title,
                    instructor=c.instructor,
                    seat=seat.n,
                    created_unix=c.created_unix,
                    ended_unix=c.ended_unix,
                    stages=stages,
                    score=sum(x.score for x in stages),
                    max_points=sum(ex.max_points for ex in c.plan),
                )
            )
        sessions.sort(key=lambda x: -x.created_unix)
        return StudentRecord(student=self._student(rows[0]), sessions=sessions)

    def forget(self, pid: int) -> None:
        """Take a student off the roster (their seats' results stay with their classes)."""
        if not self.store.query("SELECT id FROM roster WHERE id = ?", (pid,)):
            raise not_found(f"student {pid} of the roster")
        self.store.run("DELETE FROM roster_seats WHERE person = ?", (pid,))
        self.store.run("DELETE FROM roster WHERE id = ?", (pid,))

    def drop_class(self, class_id: str) -> None:
        """A class deleted: its seats are nobody's any more."""
        self.store.run("DELETE FROM roster_seats WHERE class = ?", (class_id,))
