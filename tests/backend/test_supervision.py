"""Background work is supervised: the telemetry hub, the workers' loops and the recorders
survive a failure. In process: the gateway's machine service with its worker on a thread,
machines stepped by request (no clock judged)."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from pathlib import Path
from typing import Any, cast

import pytest
from fastapi import WebSocket

from api.telemetry import decode_frame
from backend.services.machines import MachineProxy, MachineService
from backend.services.recorder import Recorders
from backend.services.telemetry import CLOSE_INTERNAL, Subscriber, TelemetryHub
from backend.workers.protocol import Pace
from backend.workers.threaded import InProcessWorker
from tests.backend.fakews import FakeSocket
from tests.backend.inprocess import INSTRUCTOR, machine_service, paused_demo, step, wait_until

FRAME_S = 0.005


def _subscribe(hub: TelemetryHub, m: MachineProxy) -> tuple[Subscriber, FakeSocket]:
    ws = FakeSocket()
    sub = hub.add(cast(WebSocket, ws), m, INSTRUCTOR)
    sub.signals, sub.min_stride = [m.link.signal_by_name["X.pos_act_mm"]], 1
    return sub, ws


def _last_cycle(ws: FakeSocket) -> int:
    header, _ = decode_frame(ws.frames[-1])
    return header.first_cycle + (header.count - 1) * header.stride


@pytest.fixture
def service(tmp_path: Path) -> Iterator[MachineService]:
    with machine_service(tmp_path) as s:
        yield s


@pytest.fixture
def host(service: MachineService) -> MachineProxy:
    return paused_demo(service, "m", powered=False)


async def _until(pred: Any, ticks: int = 400) -> None:
    for _ in range(ticks):
        if pred():
            return
        await asyncio.sleep(FRAME_S)
    raise AssertionError("not reached")


def test_a_client_whose_frames_fail_is_closed_and_the_others_go_on(
    service: MachineService, host: MachineProxy, monkeypatch: pytest.MonkeyPatch
) -> None:
    broken = paused_demo(service, "b", powered=False)

    def fail(*_: object) -> Any:
        raise OverflowError("samples of an impossible range")

    monkeypatch.setattr(broken.link, "samples", fail)

    async def run() -> None:
        hub = TelemetryHub(FRAME_S, 1000)
        hub.start()
        _, good = _subscribe(hub, host)
        _, bad = _subscribe(hub, broken)
        step(broken, 10)
        await _until(lambda: bad.close_code is not None)
        assert bad.close_code == CLOSE_INTERNAL and hub.clients_dropped == 1
        step(host, 100)
        end = host.link.cycle
        await _until(lambda: bool(good.frames) and _last_cycle(good) == end)
        assert hub.restarts == 0
        await hub.stop()

    asyncio.run(run())


def test_a_failing_hub_is_restarted(host: MachineProxy, monkeypatch: pytest.MonkeyPatch) -> None:
    async def run() -> None:
        hub = TelemetryHub(FRAME_S, 1000)
        tick = hub.tick
        failures = iter([True, True])

        def flaky() -> None:
            if next(failures, False):
                raise RuntimeError("hub bug")
            tick()

        monkeypatch.setattr(hub, "tick", flaky)
        hub.start()
        _, ws = _subscribe(hub, host)
        step(host, 100)
        end = host.link.cycle
        await _until(lambda: bool(ws.frames) and _last_cycle(ws) == end)
        assert hub.restarts == 2
        await hub.stop()

    asyncio.run(run())


def test_a_machine_that_fails_in_the_loop_is_paused_and_the_others_keep_time(
    service: MachineService, host: MachineProxy, monkeypatch: pytest.MonkeyPatch
) -> None:
    broken = paused_demo(service, "b", powered=False)
    assert isinstance(broken.link.worker, InProcessWorker)
    worker = broken.link.worker.core.worker

    def fail(*_: object) -> None:
        raise RuntimeError("kernel bug")

    monkeypatch.setattr(worker.hosts["b"], "advance", fail)
    broken.link.call(Pace("b", "run"))
    host.link.call(Pace("m", "run"))
    c0 = host.link.cycle
    wait_until(lambda: worker.host_failures and host.link.cycle > c0 + 50)
    assert worker.host_failures == 1  # paused after its first failure, not every tick
    assert worker.hosts["b"].pacing.mode == "pause"
    assert host.link.cycle > c0 + 50


def test_a_failing_recording_ends_and_the_others_go_on(
    service: MachineService, host: MachineProxy, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    other = paused_demo(service, "o", powered=False)
    recorders = Recorders(tmp_path)
    bad = recorders.begin(host, ["X.pos_act_mm"]).id
    good = recorders.begin(other, ["X.pos_act_mm"]).id

    def fail(*_: object) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(recorders.all[bad].writer, "block", fail)
    step(host, 100)
    step(other, 100)
    recorders.pump()  # no exception escapes into the recorders' thread
    assert not recorders.all[bad].active
    assert recorders.all[good].active and recorders.all[good].info().cycles == 100
    recorders.end(other.id)
