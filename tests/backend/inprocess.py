"""The gateway's machine service with its worker on a thread of this process (in-process
tests of the hub, the recorders and the worker loop: real workers, real rings, no server)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from api.auth import Role
from api.machines import MachineCreate
from backend.services.auth import Actor
from backend.services.machines import MachineProxy, MachineService
from backend.services.store import Store
from backend.workers.pool import WorkerPool
from backend.workers.protocol import Pace, Step
from backend.workers.threaded import InProcessWorker

INSTRUCTOR = Actor("test", Role.INSTRUCTOR, "session-test")


@contextmanager
def machine_service(tmp: Path, workers: int = 1) -> Iterator[MachineService]:
    """A machine service without machines, its workers running as threads."""
    store = Store(tmp / "db.sqlite")
    pool = WorkerPool(workers, 0.002, factory=InProcessWorker)
    service = MachineService(store, pool)
    pool.start(service.on_push, service.on_death)
    try:
        yield service
    finally:
        pool.stop()
        store.close()


def paused_demo(service: MachineService, mid: str, powered: bool = True) -> MachineProxy:
    """A demo lathe, paused; powered on (stepped 100 cycles) unless told otherwise."""
    m = service.create(MachineCreate(id=mid, name=mid, demo=True))
    m.link.call(Pace(mid, "pause"))
    if powered:
        step(m, 100)
    return m


def step(m: MachineProxy, cycles: int) -> None:
    m.link.call(Step(m.id, cycles))


def wait_until(pred: object, timeout_s: float = 10.0) -> None:
    """Poll a condition the worker thread brings about (pushes arrive asynchronously)."""
    deadline = time.monotonic() + timeout_s
    while not pred():  # type: ignore[operator]
        if time.monotonic() > deadline:
            raise AssertionError("not reached")
        time.sleep(0.002)
