"""Background work is supervised: the telemetry hub, the real-time loop and the recorders
survive a failure, and the loop's figures can be read while it appends to them. In process,
machines stepped by hand (no clock judged)."""

from __future__ import annotations

import asyncio
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any, cast

import pytest
from fastapi import WebSocket

from api.telemetry import decode_frame
from backend.services.host import MachineHost
from backend.services.loop import RealtimeLoop
from backend.services.recorder import Recorders
from backend.services.telemetry import CLOSE_INTERNAL, Subscriber, TelemetryHub
from nc_sim.machine.config import demo_machine
from tests.backend.fakews import FakeSocket

FRAME_S = 0.005


def _subscribe(hub: TelemetryHub, host: MachineHost) -> tuple[Subscriber, FakeSocket]:
    ws = FakeSocket()
    sub = hub.add(cast(WebSocket, ws), host)
    sub.signals, sub.min_stride = [host.signal_by_name["X.pos_act_mm"]], 1
    return sub, ws


def _last_cycle(ws: FakeSocket) -> int:
    header, _ = decode_frame(ws.frames[-1])
    return header.first_cycle + (header.count - 1) * header.stride


@pytest.fixture
def host() -> MachineHost:
    h = MachineHost("m", "m", "demo", demo_machine())
    h.set_mode("pause")
    return h


async def _until(pred: Any, ticks: int = 400) -> None:
    for _ in range(ticks):
        if pred():
            return
        await asyncio.sleep(FRAME_S)
    raise AssertionError("not reached")


def test_a_client_whose_frames_fail_is_closed_and_the_others_go_on(
    host: MachineHost, monkeypatch: pytest.MonkeyPatch
) -> None:
    broken = MachineHost("b", "b", "demo", demo_machine())
    broken.set_mode("pause")

    def fail(*_: object) -> Any:
        raise OverflowError("samples of an impossible range")

    monkeypatch.setattr(broken, "samples", fail)

    async def run() -> None:
        hub = TelemetryHub(FRAME_S, 1000)
        hub.start()
        _, good = _subscribe(hub, host)
        _, bad = _subscribe(hub, broken)
        broken.step(10)
        await _until(lambda: bad.close_code is not None)
        assert bad.close_code == CLOSE_INTERNAL and hub.clients_dropped == 1
        host.step(100)
        end = host.cycle
        await _until(lambda: bool(good.frames) and _last_cycle(good) == end)
        assert hub.restarts == 0
        await hub.stop()

    asyncio.run(run())


def test_a_failing_hub_is_restarted(host: MachineHost, monkeypatch: pytest.MonkeyPatch) -> None:
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
        host.step(100)
        end = host.cycle
        await _until(lambda: bool(ws.frames) and _last_cycle(ws) == end)
        assert hub.restarts == 2
        await hub.stop()

    asyncio.run(run())


def test_a_machine_that_fails_in_the_loop_is_paused_and_the_others_keep_time(
    host: MachineHost, monkeypatch: pytest.MonkeyPatch
) -> None:
    broken = MachineHost("b", "b", "demo", demo_machine())

    def fail(*_: object) -> None:
        raise RuntimeError("kernel bug")

    monkeypatch.setattr(broken, "advance", fail)
    broken.set_mode("run")
    host.set_mode("run")
    loop = RealtimeLoop(lambda: [broken, host], 0.002)
    loop.start()
    try:
        c0 = host.cycle
        for _ in range(5000):
            if loop.host_failures and host.cycle > c0 + 50:
                break
            threading.Event().wait(0.002)
        assert loop.host_failures == 1  # paused after its first failure, not every tick
        assert broken.pacing.mode == "pause"
        assert host.cycle > c0 + 50 and loop.status().host_failures == 1
    finally:
        loop.stop()


class Overrunning:
    """A machine whose every tick works past the loop's next deadline."""

    id = "slow"

    def tick(self, now_mono: float, fast_budget_s: float) -> None:
        end = time.monotonic() + 0.003
        while time.monotonic() < end:
            pass


@pytest.fixture
def fine_switching() -> Iterator[None]:
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # switch threads as often as possible to meet the race
    yield
    sys.setswitchinterval(old)


@pytest.mark.usefixtures("fine_switching")
def test_loop_status_while_the_loop_appends() -> None:
    """`GET /api/service/status` read the overrun records while the loop thread appended to
    them: 'deque mutated during iteration', a 500. Every tick here overruns."""
    slow = cast(MachineHost, Overrunning())
    loop = RealtimeLoop(lambda: [slow], 0.001)
    loop.start()
    try:
        for _ in range(3000):
            st = loop.status()
            assert st.overruns >= len(st.recent_overruns)
        assert st.overruns > 20 and len(st.recent_overruns) == 20
    finally:
        loop.stop()


def test_the_loop_restarts_when_its_own_code_fails(host: MachineHost) -> None:
    calls = iter([True])

    def hosts() -> list[MachineHost]:
        if next(calls, False):
            raise RuntimeError("loop bug")
        return [host]

    host.set_mode("run")
    loop = RealtimeLoop(hosts, 0.002)
    loop.start()
    try:
        c0 = host.cycle
        for _ in range(5000):
            if host.cycle > c0 + 50:
                break
            threading.Event().wait(0.002)
        assert loop.restarts == 1 and host.cycle > c0 + 50  # paced on after the failure
    finally:
        loop.stop()


def test_a_failing_recording_ends_and_the_others_go_on(
    host: MachineHost, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    other = MachineHost("o", "o", "demo", demo_machine())
    other.set_mode("pause")
    recorders = Recorders(tmp_path)
    bad = recorders.begin(host, ["X.pos_act_mm"]).id
    good = recorders.begin(other, ["X.pos_act_mm"]).id

    def fail(*_: object) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(recorders.all[bad].writer, "block", fail)
    host.step(100)
    other.step(100)
    recorders.pump()  # no exception escapes into the recorders' thread
    assert not recorders.all[bad].active
    assert recorders.all[good].active and recorders.all[good].info().cycles == 100
    recorders.end(other.id)
