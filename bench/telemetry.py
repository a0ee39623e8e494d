"""Telemetry fan-out: 1, 10 and 50 websocket viewers of one machine at 1 kHz.

Starts the real service (uvicorn and its workers, demo lathe, spindle turning), connects the
viewers from this process (headers decoded, samples not) and prints per run: sample-to-client
latency p50/p99/max (receive time minus the sample's nominal wall time
`t0_unix + cycle * cycle_s`, for every sample), frames and samples per second received, status
messages per second per viewer, gaps in the cycle indices, overruns summed over every worker
during the run, CPU of the gateway, of the workers and of this client process; then one line
per worker (its overruns, work and wake-up percentiles, CPU). Bars: p99 <= 30 ms, no gaps, no
overruns with 50.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.service import Meter, Viewer, latencies_ms, pct, view
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
SETTLE_S = 0.5  # frames in the first half second after subscribing (backlog) are not counted


async def viewers(url: str, n: int, seconds: float, headers: dict[str, str]) -> list[Viewer]:
    start = time.monotonic() + SETTLE_S
    return await asyncio.gather(
        *(view(url, SIGNALS, start + seconds, start, headers=headers) for _ in range(n))
    )


def run(srv: Server, n: int, seconds: float) -> None:
    assert srv.proc is not None
    meter = Meter(srv.http, srv.proc.pid)
    meter.start()
    own0 = time.process_time()
    url = f"{srv.ws_base}/api/machines/demo/telemetry"
    results = asyncio.run(viewers(url, n, seconds, srv.auth))
    own = time.process_time() - own0
    service = meter.stop()
    wall = service.wall_s
    lat = latencies_ms(results)
    frames = sum(v.frames for v in results)
    samples = sum(v.samples for v in results)
    errors = [v.error for v in results if v.error]
    print(
        f"{n:3d} viewers: latency p50 {pct(lat, 50):5.1f} ms p99 {pct(lat, 99):5.1f} ms "
        f"max {pct(lat, 100):5.1f} ms | {frames / seconds:6.0f} frames/s "
        f"{samples / seconds:8.0f} samples/s ({samples / seconds / n:5.0f} per viewer) | "
        f"status {sum(v.status_messages for v in results) / seconds / n:4.1f}/s per viewer | "
        f"gaps {sum(v.gaps for v in results)} | overruns {service.overruns} | "
        f"CPU gateway {100 * service.gateway_cpu_s / wall:3.0f} % "
        f"workers {100 * service.worker_cpu_s / wall:3.0f} % clients {100 * own / wall:3.0f} %"
        + (f" | {len(errors)} viewers failed: {errors[0]}" if errors else "")
    )
    service.print_workers("    ")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--clients", type=int, nargs="*", default=[1, 10, 50])
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    args = parser.parse_args()
    extra = ["--workers", str(args.workers)] if args.workers else []
    with tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "bench.sqlite", *extra).start()
        try:
            srv.command("demo", {"type": "mdi", "block": "M3 S1500"})
            print(
                f"telemetry bench: {len(SIGNALS)} signals per viewer, 1 kHz, "
                f"{args.seconds:.0f} s per run, {os.cpu_count()} cores"
            )
            for n in args.clients:
                run(srv, n, args.seconds)
        finally:
            srv.close()


if __name__ == "__main__":
    main()
