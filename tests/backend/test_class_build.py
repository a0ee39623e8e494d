"""Building a class's seats: in parallel, one build in flight per worker, and all or nothing
(a seat that cannot be built takes every seat built, its login and machine, away again)."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest

from api.auth import Role
from api.classes import ClassCreate
from api.machines import MachineCreate
from backend.errors import ApiError, Unavailable, not_found
from backend.services.accounts import Accounts
from backend.services.audit import Audit
from backend.services.auth import Actor
from backend.services.classes import Classes
from backend.services.exercises import Exercises
from backend.services.store import Store
from backend.services.training import Snapshots, StandingFaults
from backend.workers.protocol import Snapshot

TRAINER = Actor("trainer", Role.INSTRUCTOR, "s1")


class Machines:
    """The machine service as the classes see it, with `workers` live workers whose builds
    wait at a barrier: builds at once are counted, `fail` names a seat that fails."""

    def __init__(self, workers: int, fail: str | None = None) -> None:
        self.pool = self
        self.workers = workers
        self.fail = fail
        self.seats: dict[str, Any] = {}
        self.on_deleted: list[Any] = []
        self.made: dict[str, object] = {}
        self.lock = threading.Lock()
        self.building = self.most_at_once = 0

    def alive(self) -> list[object]:
        return [object()] * self.workers

    def create(self, req: MachineCreate, **_: object) -> Any:
        with self.lock:
            self.building += 1
            self.most_at_once = max(self.most_at_once, self.building)
        try:
            threading.Event().wait(0.02)  # a build takes a while: others may overlap
            if req.id == self.fail:
                raise Unavailable(f"no worker could build '{req.id}'")
            control = type("Control", (), {"holder": None})()
            # its state as a snapshot: the seat's start the class keeps
            start = Snapshot(0, 0.0, b"state", {})
            link = type("Link", (), {"call": staticmethod(lambda _req: start)})()
            proxy = type("Proxy", (), {"id": req.id, "control": control, "link": link})()
            with self.lock:
                self.made[req.id] = proxy
            return proxy
        finally:
            with self.lock:
                self.building -= 1

    def get(self, mid: str) -> object:
        if mid not in self.made:
            raise not_found(f"machine '{mid}'")
        return self.made[mid]

    def delete(self, mid: str) -> None:
        del self.made[mid]


def classes(tmp_path: Path, machines: Machines) -> tuple[Classes, Accounts]:
    store = Store(tmp_path / "c.sqlite")
    accounts = Accounts(store)
    audit = Audit(store)
    faults = StandingFaults(store, machines)  # type: ignore[arg-type]
    snapshots = Snapshots(store, machines, faults)  # type: ignore[arg-type]
    built = Classes(store, accounts, machines, Exercises(store), audit, faults, snapshots)  # type: ignore[arg-type]
    return built, accounts


def test_seats_are_built_one_per_worker_at_a_time_in_seat_order(tmp_path: Path) -> None:
    machines = Machines(workers=2)
    cls, accounts = classes(tmp_path, machines)
    req = ClassCreate(id="par", exercises=["sign-error"], seats=9, students=["Anna"])
    created = cls.create(TRAINER, req, "http://x")
    assert machines.most_at_once == 2
    seats = created.info.seats
    assert [s.n for s in seats] == list(range(1, 10))
    assert [s.machine for s in seats] == [f"par-s{n:02d}" for n in range(1, 10)]
    assert seats[0].student == "Anna" and seats[1].student == "Seat 2"
    assert {f"par-s{n:02d}" for n in range(1, 10)} <= {u.name for u in accounts.users()}


def test_a_seat_that_cannot_be_built_takes_the_whole_class_away(tmp_path: Path) -> None:
    machines = Machines(workers=2, fail="bad-s05")
    cls, accounts = classes(tmp_path, machines)
    with pytest.raises(ApiError) as e:
        cls.create(TRAINER, ClassCreate(id="bad", exercises=["sign-error"], seats=9), "http://x")
    assert e.value.status == 503
    assert machines.made == {}
    assert not [u.name for u in accounts.users() if u.name.startswith("bad-")]
    with pytest.raises(ApiError):
        cls.get("bad")
