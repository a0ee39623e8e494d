"""Telemetry fan-out: 1, 10 and 50 websocket subscribers to one machine at 1 kHz.

Starts the real service (uvicorn, demo lathe, spindle turning), connects the subscribers from
this process and prints per run: sample-to-client latency p50/p99 (receive time minus the
sample's nominal wall time `t0_unix + cycle * cycle_s`, for every sample), frames and samples
per second received, gaps in the cycle indices, loop overruns during the run, and CPU of the
service and of this client process. Bars: p99 <= 50 ms, no gaps, no overruns with 50.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from websockets.asyncio.client import connect

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from api.telemetry import decode_frame
from tests.backend.server import Server

SIGNALS = [
    "S1.speed_cmd_rpm",
    "S1.speed_act_rpm",
    "S1.lag_deg",
    "X.pos_act_mm",
    "X.lag_mm",
    "Z.pos_act_mm",
    "Z.lag_mm",
    "S1.state",
]


def cpu_s(pid: int) -> float:
    """User + system CPU seconds of a process (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@dataclass
class Received:
    latency_s: np.ndarray
    frames: int
    samples: int
    gaps: int


async def subscriber(url: str, seconds: float) -> Received:
    lat: list[np.ndarray] = []
    cycles: list[np.ndarray] = []
    frames = 0
    async with connect(url, max_size=None) as ws:
        await ws.send(json.dumps({"type": "subscribe", "signals": SIGNALS}))
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            msg = await ws.recv()
            now = time.time()
            if not isinstance(msg, bytes):
                continue
            h, _data = decode_frame(msg)
            c = h.first_cycle + h.stride * np.arange(h.count)
            cycles.append(c)
            lat.append(now - (h.t0_unix + c * h.cycle_s))
            frames += 1
    all_cycles = np.concatenate(cycles) if cycles else np.zeros(0, dtype=np.int64)
    return Received(
        np.concatenate(lat) if lat else np.zeros(0),
        frames,
        len(all_cycles),
        int(np.count_nonzero(np.diff(all_cycles) != 1)),
    )


async def run(srv: Server, n: int, seconds: float) -> None:
    url = f"{srv.ws_base}/api/machines/demo/telemetry"
    before = srv.http.get("/api/service/status").json()["loop"]
    assert srv.proc is not None
    cpu0, own0, t0 = cpu_s(srv.proc.pid), time.process_time(), time.monotonic()
    results = await asyncio.gather(*(subscriber(url, seconds) for _ in range(n)))
    wall = time.monotonic() - t0
    cpu1, own1 = cpu_s(srv.proc.pid), time.process_time()
    after = srv.http.get("/api/service/status").json()["loop"]
    lat = np.concatenate([r.latency_s for r in results]) * 1e3
    frames = sum(r.frames for r in results)
    samples = sum(r.samples for r in results)
    gaps = sum(r.gaps for r in results)
    for o in after["recent_overruns"][len(before["recent_overruns"]) :]:
        print(f"    overrun: woke {o['wake_late_ms']:.1f} ms late, work {o['work_ms']:.1f} ms")
    print(
        f"{n:3d} subscribers: latency p50 {np.percentile(lat, 50):5.1f} ms "
        f"p99 {np.percentile(lat, 99):5.1f} ms max {lat.max():5.1f} ms | "
        f"{frames / wall:6.0f} frames/s {samples / wall:8.0f} samples/s "
        f"({samples / wall / n:5.0f} per client) | gaps {gaps} | "
        f"overruns {after['overruns'] - before['overruns']} | "
        f"CPU service {100 * (cpu1 - cpu0) / wall:3.0f} % "
        f"clients {100 * (own1 - own0) / wall:3.0f} %"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--clients", type=int, nargs="*", default=[1, 10, 50])
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "bench.sqlite").start()
        try:
            srv.command("demo", {"type": "mdi", "block": "M3 S1500"})
            print(
                f"telemetry bench: {len(SIGNALS)} signals per subscriber, 1 kHz, "
                f"{args.seconds:.0f} s per run, {os.cpu_count()} cores"
            )
            for n in args.clients:
                asyncio.run(run(srv, n, args.seconds))
        finally:
            srv.close()


if __name__ == "__main__":
    main()
