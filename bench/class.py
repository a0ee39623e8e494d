"""A class of N busy demo machines on one server: how many hold real time?

For each N, a fresh service (`--no-demo`, workers one per core unless `--workers`) gets N demo
lathes (POST /api/machines). Each machine's spindle turns (`M3 S800`) and its X axis jogs back
and forth on a timer (jog start with a direction and a dead-man `hold_s` longer than the
timer, stop, reverse); each machine has one websocket viewer subscribed to a few signals (all
viewers in one client process, asyncio, frame headers decoded only). After a settling second
the load is held for `--seconds`, then the curve is printed, one line per N: overruns of every
worker during the hold, telemetry sample-to-client p50/p99 (receive time minus
`t0_unix + cycle * cycle_s`, every sample), frames/s per viewer, gaps, the slowest machine's
real-time factor, CPU per machine (worker CPU s / wall s / N, % of a core), of the gateway and
of the load generators (the viewers' process and this one, which jogs),
commands refused or failed; finally the largest N that held real time: 0 overruns and
p99 <= 50 ms. A fresh service per N keeps the steps independent (no leftovers of deleted
machines, workers placed from empty).
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.service import Meter, Viewers, cpu_s, latencies_ms, pct
from tests.backend.server import Server

SIGNALS = ["S1.speed_act_rpm", "S1.lag_deg", "X.pos_act_mm", "X.lag_mm"]
P99_BAR_MS = 50.0
SETUP_CONCURRENCY = 8  # requests in flight while creating and starting the machines


@dataclass
class Step:
    """The figures of one N."""

    n: int
    overruns: int
    p50_ms: float
    p99_ms: float
    frames_per_viewer_s: float
    gaps: int
    rt_factor_min: float
    cpu_per_machine_pct: float
    gateway_pct: float
    clients_pct: float  # the viewers' process and this one (jogging), % of a core
    commands: int
    refused: int
    viewers_failed: int

    @property
    def held(self) -> bool:
        return self.overruns == 0 and self.p99_ms <= P99_BAR_MS and not self.viewers_failed


class Jogging:
    """Every machine's X axis jogging back and forth, driven from a thread of this process."""

    def __init__(
        self, base: str, mids: list[str], period_s: float, headers: dict[str, str]
    ) -> None:
        self.base, self.mids, self.period_s, self.headers = base, mids, period_s, headers
        self.commands = self.refused = 0
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=lambda: asyncio.run(self.main()), daemon=True)

    async def main(self) -> None:
        limits = httpx.Limits(max_connections=64)
        async with httpx.AsyncClient(
            base_url=self.base, timeout=10, limits=limits, headers=self.headers
        ) as http:
            await asyncio.gather(*(self.jog(http, mid) for mid in self.mids))

    async def command(self, http: httpx.AsyncClient, mid: str, body: dict[str, object]) -> None:
        self.commands += 1
        try:
            r = await http.post(f"/api/machines/{mid}/commands", json=body)
            self.refused += r.status_code != 200
        except httpx.HTTPError:
            self.refused += 1

    async def jog(self, http: httpx.AsyncClient, mid: str) -> None:
        """Start, stop after the period, reverse; the lease outlasts the period."""
        await asyncio.sleep(random.uniform(0, self.period_s))  # spread the commands
        direction = 1
        while not self.stopping.is_set():
            start = {"type": "jog", "axis": "X", "action": "start", "direction": direction}
            await self.command(http, mid, {**start, "hold_s": self.period_s + 1.0})
            await asyncio.sleep(self.period_s)
            await self.command(http, mid, {"type": "jog", "axis": "X", "action": "stop"})
            direction = -direction

    def stop(self) -> None:
        self.stopping.set()
        self.thread.join(timeout=30)


async def set_up(base: str, mids: list[str], headers: dict[str, str]) -> None:
    """Create the machines, wait for their drives, turn their spindles."""
    gate = asyncio.Semaphore(SETUP_CONCURRENCY)
    async with httpx.AsyncClient(base_url=base, timeout=60, headers=headers) as http:

        async def one(mid: str) -> None:
            async with gate:
                r = await http.post("/api/machines", json={"id": mid, "demo": True})
                r.raise_for_status()
            deadline = time.monotonic() + 60
            while not (await http.get(f"/api/machines/{mid}/status")).json()["plc"][
                "drives_powered"
            ]:
                if time.monotonic() > deadline:
                    raise RuntimeError(f"{mid}: drives not powered")
                await asyncio.sleep(0.2)
            async with gate:
                body = {"type": "mdi", "block": "M3 S800"}
                r = await http.post(f"/api/machines/{mid}/commands", json=body)
                r.raise_for_status()

        await asyncio.gather(*(one(mid) for mid in mids))


def step(n: int, seconds: float, jog_s: float, extra: list[str]) -> Step:
    with tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "bench.sqlite", "--no-demo", *extra).start()
        assert srv.proc is not None
        try:
            mids = [f"c{i:03d}" for i in range(n)]
            t0 = time.monotonic()
            asyncio.run(set_up(srv.base, mids, srv.auth))
            setup_s = time.monotonic() - t0
            jogging = Jogging(srv.base, mids, jog_s, srv.auth)
            jogging.thread.start()
            urls = [f"{srv.ws_base}/api/machines/{mid}/telemetry" for mid in mids]
            viewers = Viewers(urls, SIGNALS, settle_s=1.0, headers=srv.auth).start()
            meter = Meter(srv.http, srv.proc.pid)
            meter.start()
            c0, r0 = jogging.commands, jogging.refused
            clients0 = cpu_s(viewers.proc.pid) + cpu_s(os.getpid())
            time.sleep(seconds)
            clients_s = cpu_s(viewers.proc.pid) + cpu_s(os.getpid()) - clients0
            service = meter.stop()
            commands, refused = jogging.commands - c0, jogging.refused - r0
            received = viewers.stop()
            jogging.stop()
            machines = srv.http.get("/api/service/status").json()["machines"]
            lat = latencies_ms(received)
            counted = [v for v in received if v.counted_s > 0]
            s = Step(
                n=n,
                overruns=service.overruns,
                p50_ms=pct(lat, 50),
                p99_ms=pct(lat, 99),
                frames_per_viewer_s=sum(v.frames / v.counted_s for v in counted) / n,
                gaps=sum(v.gaps for v in received),
                rt_factor_min=min(m["rt_factor"] for m in machines.values()),
                cpu_per_machine_pct=100 * service.worker_cpu_s / service.wall_s / n,
                gateway_pct=100 * service.gateway_cpu_s / service.wall_s,
                clients_pct=100 * clients_s / service.wall_s,
                commands=commands,
                refused=refused,
                viewers_failed=sum(1 for v in received if v.error),
            )
            print(f"  N={n}: set up in {setup_s:.1f} s; workers during the hold:")
            service.print_workers("    ")
            return s
        finally:
            srv.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--machines", default="20,50,100,150,200", help="N list, e.g. 20,50")
    parser.add_argument("--seconds", type=float, default=60.0, help="hold per N")
    parser.add_argument("--jog-s", type=float, default=2.0, help="jog time per direction")
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    args = parser.parse_args()
    ns = [int(n) for n in args.machines.split(",") if n]
    extra = ["--workers", str(args.workers)] if args.workers else []
    print(
        f"class bench: N demo lathes, each M3 S800 and X jogging {args.jog_s:g} s each way, "
        f"one viewer of {len(SIGNALS)} signals each; {args.seconds:g} s hold per N, "
        f"a fresh service per N, {os.cpu_count()} cores"
    )
    steps = []
    for n in ns:
        steps.append(step(n, args.seconds, args.jog_s, extra))
    print(
        "    N  overruns  p50 ms  p99 ms  frames/s/viewer  gaps  rt min  "
        "CPU/machine %  gateway %  clients %  commands refused  viewers failed"
    )
    for s in steps:
        print(
            f"{s.n:5d}  {s.overruns:8d}  {s.p50_ms:6.1f}  {s.p99_ms:6.1f}  "
            f"{s.frames_per_viewer_s:15.1f}  {s.gaps:4d}  {s.rt_factor_min:6.3f}  "
            f"{s.cpu_per_machine_pct:13.2f}  {s.gateway_pct:9.0f}  {s.clients_pct:9.0f}  "
            f"{s.commands:8d} {s.refused:7d}  {s.viewers_failed:14d}"
        )
    held = [s.n for s in steps if s.held]
    print(
        f"largest N that held real time (0 overruns, p99 <= {P99_BAR_MS:g} ms): "
        + (str(max(held)) if held else "none")
    )


if __name__ == "__main__":
    main()
