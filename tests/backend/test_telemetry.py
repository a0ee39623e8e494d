"""Live telemetry over a real websocket: every cycle, events, decimation, slow clients."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed

from api.telemetry import FrameHeader, decode_frame
from tests.backend.rawws import RawWebSocket
from tests.backend.server import Server

SIGNALS = ["S1.speed_cmd_rpm", "S1.speed_act_rpm", "X.lag_mm", "S1.state"]


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("tel") / "tel.sqlite").start()
    yield s
    s.close()


async def _json(ws: ClientConnection, kind: str) -> dict[str, Any]:
    """The next JSON message of this type (frames and other messages skipped)."""
    while True:
        msg = await ws.recv()
        if isinstance(msg, str):
            data: dict[str, Any] = json.loads(msg)
            if data["type"] == kind:
                return data


async def _collect(
    ws: ClientConnection, seconds: float
) -> tuple[list[tuple[FrameHeader, np.ndarray]], list[dict[str, Any]]]:
    frames: list[tuple[FrameHeader, np.ndarray]] = []
    events: list[dict[str, Any]] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        msg = await ws.recv()
        if isinstance(msg, bytes):
            frames.append(decode_frame(msg))
        else:
            data = json.loads(msg)
            if data["type"] == "event":
                events.append(data["event"])
    return frames, events


def _cycles(frames: list[tuple[FrameHeader, np.ndarray]]) -> np.ndarray:
    return np.concatenate(
        [h.first_cycle + h.stride * np.arange(h.count) for h, _ in frames]
    ).astype(np.int64)


def test_every_cycle_for_five_seconds_with_events(srv: Server) -> None:
    async def run() -> None:
        async with connect(f"{srv.ws_base}/api/machines/demo/telemetry") as ws:
            hello = await _json(ws, "hello")
            names = {s["name"] for s in hello["signals"]}
            assert set(SIGNALS) <= names and hello["cycle_s"] == pytest.approx(0.001)
            await ws.send(json.dumps({"type": "subscribe", "signals": SIGNALS}))
            sub = await _json(ws, "subscribed")
            assert sub["stride"] == 1
            r = await asyncio.to_thread(srv.command, "demo", {"type": "mdi", "block": "M3 S1000"})
            assert r.status_code == 200
            frames, events = await _collect(ws, 5.0)
        cycles = _cycles(frames)
        # no gaps and no repeats: consecutive cycle indices, and 5 s at 1 kHz worth of them
        assert np.all(np.diff(cycles) == 1)
        assert cycles[0] == sub["first_cycle"] + 1
        assert len(cycles) >= 4500
        assert all(h.stride == 1 and not h.decimated and h.skipped_cycles == 0 for h, _ in frames)
        assert all(h.signals == SIGNALS for h, _ in frames)
        cmd = np.concatenate([d[0] for _, d in frames])
        act = np.concatenate([d[1] for _, d in frames])
        assert cmd.max() == pytest.approx(1000.0)  # the S word, rpm
        assert abs(act[-1] - 1000.0) < 10.0
        assert any(e["code"] == 15 for e in events)  # speed reached, as its own message
        # frames come every ~20 ms with the samples since the previous one
        assert np.median([h.count for h, _ in frames]) == pytest.approx(20, abs=5)

    asyncio.run(run())
    srv.command("demo", {"type": "spindle", "m": 5})


def test_max_rate_decimates_on_a_fixed_grid(srv: Server) -> None:
    async def run() -> None:
        url = f"{srv.ws_base}/api/machines/demo/telemetry?signals=X.pos_cmd_mm"
        async with connect(url) as ws:
            await _json(ws, "subscribed")
            await ws.send(
                json.dumps({"type": "subscribe", "signals": ["X.pos_cmd_mm"], "max_rate_hz": 100})
            )
            sub = await _json(ws, "subscribed")
            assert sub["stride"] == 10  # 1 kHz to 100 Hz
            frames, _ = await _collect(ws, 1.0)
        frames = [f for f in frames if f[0].stride == 10]
        cycles = _cycles(frames)
        assert np.all(np.diff(cycles) == 10)
        assert not any(h.decimated for h, _ in frames)  # asked for, not imposed

    asyncio.run(run())


def test_unknown_signal_is_an_error_message(srv: Server) -> None:
    async def run() -> None:
        async with connect(f"{srv.ws_base}/api/machines/demo/telemetry") as ws:
            await ws.send(json.dumps({"type": "subscribe", "signals": ["X.nonsense"]}))
            err = await _json(ws, "error")
            assert "X.nonsense" in err["message"]

    asyncio.run(run())


def test_reconnect_resumes_at_the_current_cycle(srv: Server) -> None:
    async def one() -> list[tuple[FrameHeader, np.ndarray]]:
        url = f"{srv.ws_base}/api/machines/demo/telemetry?signals=Z.pos_act_mm"
        async with connect(url) as ws:
            frames, _ = await _collect(ws, 0.5)
        return frames

    first = asyncio.run(one())
    now = srv.status()["simulation"]["cycle"]
    second = asyncio.run(one())
    assert second[0][0].first_cycle > now
    assert second[0][0].first_cycle > _cycles(first)[-1]


def test_slow_client_is_decimated_and_never_delays_others(srv: Server) -> None:
    """A client that stops reading fills its socket; the hub skips it, then sends it the
    backlog decimated, while a second client keeps receiving every cycle."""
    every = [s["name"] for s in srv.http.get("/api/machines/demo/signals").json()]
    slow = RawWebSocket(
        "127.0.0.1", srv.port, "/api/machines/demo/telemetry?signals=" + ",".join(every)
    )

    async def watch() -> list[tuple[FrameHeader, np.ndarray]]:
        url = f"{srv.ws_base}/api/machines/demo/telemetry?signals=X.pos_act_mm"
        async with connect(url) as fast:
            frames, _ = await _collect(fast, 3.0)  # the slow one reads nothing meanwhile
        return frames

    fast_frames = asyncio.run(watch())
    slow_frames = []
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        op, payload = slow.recv()
        if op == 2:
            slow_frames.append(decode_frame(payload))
    slow.close()
    assert np.all(np.diff(_cycles(fast_frames[1:])) == 1)
    late = [h for h, _ in slow_frames if h.decimated]
    assert late and all(h.stride > 1 and h.count <= 1000 for h in late)


def test_deleting_a_machine_closes_its_subscribers(srv: Server) -> None:
    assert srv.http.post("/api/machines", json={"id": "gone", "demo": True}).status_code == 201

    async def run() -> int | None:
        url = f"{srv.ws_base}/api/machines/gone/telemetry?signals=X.pos_act_mm"
        async with connect(url) as ws:
            await _json(ws, "subscribed")
            await asyncio.to_thread(srv.http.delete, "/api/machines/gone")
            with pytest.raises(ConnectionClosed):
                while True:
                    await ws.recv()
            return ws.close_code

    assert asyncio.run(run()) == 4404
