"""A machine's training faults are known to the gateway from the moment its build answers:
created, power-cycled or restored, before any status is pushed (an unwatched machine pushes
none). The fault list of a seat created a moment ago was empty until its first status."""

from __future__ import annotations

from pathlib import Path

from api.machines import MachineCreate
from backend.services.machines import MachineService
from backend.workers.client import WorkerClient
from backend.workers.protocol import ReadStatus, Request, TakeSnapshot
from nc_sim.faults import NOW, Fault, MotorInverted, PlcSlowAck, Trigger
from tests.backend.inprocess import machine_service

ARMED = Trigger(after_s=30.0)


def no_status_reads(service: MachineService) -> list[Request]:
    """Every request the machines' workers get from here on; a ReadStatus fails the test
    (what the gateway knows must come with the build's answer)."""
    seen: list[Request] = []
    for w in service.pool.alive():
        call = w.call

        def spy(request: Request, timeout_s: float = 10.0, call=call) -> object:  # type: ignore[no-untyped-def]
            assert not isinstance(request, ReadStatus), "faults read after the build"
            seen.append(request)
            return call(request, timeout_s)

        w.call = spy  # type: ignore[method-assign]
    return seen


def kinds(service: MachineService, mid: str) -> list[tuple[int, str, bool]]:
    faults = service.get(mid).link.faults
    return [(f.id, f.fault.kind, f.active_since is not None) for f in faults.values()]


def test_created_restarted_and_restored_machines_know_their_faults_at_once(
    tmp_path: Path,
) -> None:
    with machine_service(tmp_path) as service:
        no_status_reads(service)
        faults: list[tuple[Fault, Trigger]] = [(MotorInverted("X"), NOW), (PlcSlowAck(8.0), ARMED)]
        service.create(MachineCreate(id="m", name="m", demo=True), faults=faults)
        assert kinds(service, "m") == [(1, "motor_inverted", True), (2, "plc_slow_ack", False)]
        service.restart("m", "test")  # a power cycle: injected again, the armed one armed again
        assert kinds(service, "m") == [(1, "motor_inverted", True), (2, "plc_slow_ack", False)]
        m = service.get("m")
        worker: WorkerClient = m.link.worker  # type: ignore[assignment]
        snap = worker.call(TakeSnapshot("m"))
        service.create(MachineCreate(id="n", name="n", demo=True))
        assert kinds(service, "n") == []
        service.restore("n", snap.data, snap.params, "test")  # type: ignore[attr-defined]
        assert kinds(service, "n") == [(1, "motor_inverted", True), (2, "plc_slow_ack", False)]
