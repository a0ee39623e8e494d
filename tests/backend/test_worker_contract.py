"""One contract, two transports: the gateway's machine service behaves the same whether its
workers are local processes (samples in shared memory) or Ray actors on the nodes of a
cluster (samples pushed into the gateway's copy of each ring).

Each test runs against both, through `MachineService` and a `WorkerPool` of two workers;
every test has a machine of its own, paused and stepped by request (no clock judged).
"""

from __future__ import annotations

import itertools
import os
import signal
from collections import Counter
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from api.machines import MachineCreate
from backend.services.machines import MachineProxy, MachineService
from backend.services.store import Store
from backend.workers.client import WorkerClient, WorkerRefused
from backend.workers.local import LocalWorker
from backend.workers.pool import Factory, WorkerPool
from backend.workers.protocol import (
    Pace,
    Pacing,
    ReadStatus,
    ScopeAct,
    ScopeArm,
    StatusRead,
    Step,
    Submit,
    Submitted,
)
from nc_sim.commands import Accepted, Command, EmergencyStop, HliWrite, Invalid, Mdi, Move, Refused
from nc_sim.errors import Code
from nc_sim.scope import LevelTrigger, ScopeMode, ScopeSetup
from tests.backend.inprocess import machine_service, paused_demo, wait_until

PERIOD_S = 0.002
_serial = itertools.count(1)


@pytest.fixture(scope="module", params=["local", "ray"])
def transport(request: pytest.FixtureRequest) -> Iterator[tuple[str, Factory]]:
    """(name, how a worker is made): local processes, or actors on a head + 2 node cluster."""
    if request.param == "local":
        yield "local", LocalWorker
        return
    address = request.getfixturevalue("ray_cluster").address  # before Ray loads (loopback)
    from backend.workers.ray_transport import RayWorker, connect, disconnect

    connect(address)

    def ray_worker(wid: str, period_s: float, _ring_dir: Path) -> WorkerClient:
        return RayWorker(wid, period_s, address)

    yield "ray", ray_worker
    disconnect()


@pytest.fixture(scope="module")
def service(
    transport: tuple[str, Factory], tmp_path_factory: pytest.TempPathFactory
) -> Iterator[MachineService]:
    store = Store(tmp_path_factory.mktemp(transport[0]) / "db.sqlite")
    pool = WorkerPool(2, PERIOD_S, factory=transport[1])
    service = MachineService(store, pool)
    pool.start(service.on_push, service.on_death)
    yield service
    pool.stop()
    store.close()


@pytest.fixture
def m(service: MachineService) -> MachineProxy:
    """The test's own demo lathe: powered on, paused."""
    return paused_demo(service, f"c{next(_serial)}")


def submit(m: MachineProxy, cmd: Command) -> Submitted:
    done = m.link.call(Submit(m.id, cmd))
    assert isinstance(done, Submitted)
    return done


def step(m: MachineProxy, cycles: int) -> Pacing:
    pacing = m.link.call(Step(m.id, cycles))
    assert isinstance(pacing, Pacing)
    return pacing


def read_status(m: MachineProxy) -> StatusRead:
    status = m.link.call(ReadStatus(m.id))
    assert isinstance(status, StatusRead)
    return status


def test_commands_are_accepted_refused_or_invalid(m: MachineProxy) -> None:
    block = "G01 X10 F500 &"
    bad = submit(m, Mdi(block)).outcome
    assert isinstance(bad, Invalid)
    assert bad.column == block.index("&") + 1 and bad.code == Code.BLOCK_SYNTAX
    assert isinstance(submit(m, HliWrite("DriveOn", 0, "X")).outcome, Accepted)
    refused = submit(m, Mdi("G00 X100")).outcome  # a motion without the drive enable
    assert isinstance(refused, Refused)
    assert refused.code == Code.NO_ENABLES and refused.error.axis == "X"
    assert isinstance(submit(m, Mdi("M3 S1000")).outcome, Accepted)


def test_a_step_moves_the_cycle_exactly_and_its_samples_reach_the_gateway(
    m: MachineProxy,
) -> None:
    start = step(m, 1).cycle
    pos = m.link.signal_by_name["X.pos_cmd_mm"]
    x0 = float(m.link.samples([pos], start, start, 1)[0][0, 0])
    submit(m, Move("X", x0 + 50.0, rapid=False, feed_mm_min=600.0))
    assert step(m, 700).cycle == start + 700
    assert read_status(m).pacing.cycle == start + 700
    assert m.link.cycle == start + 700  # the gateway's ring holds every stepped cycle
    data, first = m.link.samples([pos], start + 1, start + 700, 1)
    assert first == start + 1 and data.shape == (1, 700)
    # G01 at 600 mm/min: 10 mm/s, 0.01 mm per 1 ms cycle once at feed (consecutive rows)
    assert np.diff(data[0, -300:]) == pytest.approx(0.01, abs=1e-9)
    assert data[0, 0] == pytest.approx(x0, abs=0.01)


def test_pacing_answers_with_where_time_stands(m: MachineProxy) -> None:
    paused = m.link.call(Pace(m.id, "pause"))
    assert isinstance(paused, Pacing) and paused.mode == "pause"
    again = m.link.call(Pace(m.id, "pause"))
    assert isinstance(again, Pacing) and again.cycle == paused.cycle  # paused: time stands


def test_events_and_a_scope_capture_reach_the_gateway(m: MachineProxy) -> None:
    read = m.link.events_since(0)
    seen = read[2]
    submit(m, EmergencyStop())
    step(m, 5)
    wait_until(lambda: any(e.code == Code.EMERGENCY_STOP for e in m.link.events_since(seen)[0]))
    pos = m.link.signal_by_name["X.pos_act_mm"]
    setup = ScopeSetup([pos], 200, 25.0, ScopeMode.SINGLE, LevelTrigger(pos, 1e6))
    m.link.call(ScopeArm(m.id, setup))
    m.link.call(ScopeAct(m.id, "force"))
    step(m, 300)
    wait_until(lambda: len(m.captures.recent()) == 1)
    record = m.captures.recent()[-1].record
    assert record.forced and record.count == 200 and record.channels == [pos]


def test_a_removed_machine_is_gone_from_its_worker(service: MachineService) -> None:
    m = paused_demo(service, f"c{next(_serial)}")
    worker = m.link.worker
    assert worker is not None
    service.delete(m.id)
    with pytest.raises(WorkerRefused) as refused:
        worker.call(ReadStatus(m.id))
    assert refused.value.failure.kind == "not_found"
    with pytest.raises(WorkerRefused):
        worker.call(Step(m.id, 1))


def test_a_dead_worker_is_detected_and_its_machines_rebuilt_on_another(
    service: MachineService, transport: tuple[str, Factory], m: MachineProxy
) -> None:
    dead, epoch, rebuilt = m.link.worker, m.link.epoch, service.rebuilt
    assert dead is not None
    if transport[0] == "local":
        assert dead.pid is not None
        os.kill(dead.pid, signal.SIGKILL)
    else:
        import ray

        ray.kill(dead.actor)  # type: ignore[attr-defined]
    wait_until(lambda: m.link.worker is not dead and m.link.epoch == epoch + 1, 30)
    assert not dead.alive and service.rebuilt > rebuilt
    assert read_status(m).pacing.mode == "run"  # the rebuilt machine answers, running
    wait_until(lambda: m.link.cycle > 0)  # its samples flow from the new worker
    wait_until(lambda: len(service.pool.alive()) == 2, 60)  # a replacement took its place


def test_machines_created_at_once_spread_over_the_workers(tmp_path: Path) -> None:
    """A machine being built counts as its worker's load: four created at the same time on
    two workers land two and two (before, each saw both workers empty)."""
    with machine_service(tmp_path, workers=2) as service, ThreadPoolExecutor(4) as ex:
        made = list(
            ex.map(
                lambda k: service.create(MachineCreate(id=f"s{k}", demo=True)),
                range(4),
            )
        )
        per_worker = Counter(id(m.link.worker) for m in made)
        assert sorted(per_worker.values()) == [2, 2]
