"""One pass of a worker's loop over its machines, in this process: a request served between
two machines (the worker looks for one after each) may rebuild or remove a machine the pass
has not finished with. Found in CI: a graded class moved a seat on to its next exercise (a
rebuild) while its worker was in the middle of a pass, and the worker died reading the old
build's closed ring for the exercise's checks."""

from __future__ import annotations

import time
from pathlib import Path

from backend.workers.protocol import AddMachine, MachineNews, Push, RemoveMachine, Reply, Watch
from backend.workers.threaded import QueueChannel
from backend.workers.worker import Worker
from nc_sim.config import demo_machine
from nc_sim.training.exercise import parse_exercise
from tests.backend.test_graded_training import SOUND_X

PERIOD_S = 0.01
CYCLE_S = 0.001  # the demo's NC cycle


def build(mid: str, epoch: int) -> AddMachine:
    """A seat's machine with an exercise whose checks read the ring at every status."""
    return AddMachine(mid, mid, demo_machine(), epoch, exercise=parse_exercise(SOUND_X, "t.toml"))


def test_machines_rebuilt_or_removed_by_a_request_in_the_middle_of_a_pass(tmp_path: Path) -> None:
    pushes: list[Push] = []
    worker = Worker(QueueChannel(pushes.append), PERIOD_S, tmp_path)
    for mid in ("a", "b", "c"):
        worker.handle(0, build(mid, 1), 0.0)
        worker.handle(0, Watch(mid, True), 0.0)
    old = dict(worker.hosts)
    start = time.monotonic()
    worker.tick_machines(start + 0.5, PERIOD_S, time.monotonic())
    assert all(h.cycle > 0 for h in old.values())

    # waiting when the pass begins: served right after the first machine's tick
    worker.backlog.extend([(11, build("a", 2), 0.0), (12, build("b", 2), 0.0)])
    worker.backlog.append((13, RemoveMachine("c"), 0.0))
    pushes.clear()
    worker.tick_machines(start + 1.0, PERIOD_S, time.monotonic())

    replies = {p.req: p.value for p in pushes if isinstance(p, Reply)}
    assert set(replies) == {11, 12, 13} and replies[13] is None
    assert not [p for p in pushes if isinstance(p, MachineNews)]  # none of the old builds
    assert worker.host_failures == 0  # no machine stepped on a closed ring
    assert sorted(worker.hosts) == ["a", "b"]
    assert all(worker.hosts[m] is not old[m] for m in ("a", "b"))
    assert not list(tmp_path.glob("*.1.ring"))  # the old builds' rings are gone

    # the next pass steps the new builds, and their statuses carry the exercise's checks
    for mid in ("a", "b"):
        worker.handle(0, Watch(mid, True), 0.0)  # as the gateway does for a rebuilt machine
    pushes.clear()
    later = time.monotonic()
    worker.tick_machines(later + 0.2, PERIOD_S, later)
    news = [p for p in pushes if isinstance(p, MachineNews)]
    assert sorted((n.mid, n.epoch) for n in news) == [("a", 2), ("b", 2)]
    for mid in ("a", "b"):
        # built at `later - x`; stepped to its deadline 0.2 s on: at least 200 cycles
        assert worker.hosts[mid].cycle >= round(0.2 / CYCLE_S)
    assert all(n.status is not None and n.status.checks for n in news)
