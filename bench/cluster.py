"""The gateway on a local multi-node Ray cluster (`inbetrieb serve --cluster HOST:PORT`).

Starts a head and two worker nodes on this host, a real gateway with three workers (one actor
per node), and prints:
- the command round trip over loopback HTTP through the gateway to a worker actor and back,
  p50/p99/max per kind (MDI blocks, jog start/stop);
- the class figures for N busy demo machines (spindle turning at 1000 rpm, Z jogging), each
  watched by one websocket viewer: overruns of each worker's loop during the run, telemetry
  sample-to-client latency p50/p99 (receive time minus the sample's nominal wall time), gaps,
  CPU per machine of the workers (their actor processes) and of the gateway.
Figures only, no bars: this host's two cores are shared with Ray's own processes.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.api import KINDS
from bench.telemetry import SIGNALS, cpu_s, subscriber
from tests.backend.raycluster import local_cluster
from tests.backend.server import Server


def service(srv: Server) -> dict[str, Any]:
    data: dict[str, Any] = srv.http.get("/api/service/status").json()
    return data


def round_trip(srv: Server, mid: str, requests: int) -> None:
    node = next(w["node"] for w in service(srv)["workers"] if mid in w["machines"])
    print(f"command round trip, {requests} requests per kind, machine on node {node}")
    for kind, bodies in KINDS.items():
        rtt = []
        for i in range(requests):
            t0 = time.perf_counter()
            r = srv.command(mid, bodies[i % len(bodies)])
            rtt.append(time.perf_counter() - t0)
            if r.status_code != 200:
                raise SystemExit(f"{kind}: {r.status_code} {r.text}")
        ms = np.array(rtt) * 1e3
        print(
            f"  {kind:4s}: p50 {np.percentile(ms, 50):5.2f} ms  "
            f"p99 {np.percentile(ms, 99):5.2f} ms  max {ms.max():6.2f} ms"
        )


def add_busy(srv: Server, mid: str) -> None:
    r = srv.http.post("/api/machines", json={"id": mid, "demo": True})
    if r.status_code != 201:
        raise SystemExit(f"{mid}: {r.status_code} {r.text}")
    srv.wait_powered(mid, 30)
    srv.command(mid, {"type": "mdi", "block": "M3 S1000"})
    jog = {"type": "jog", "axis": "Z", "action": "start", "direction": -1, "feed_mm_min": 60}
    r = srv.command(mid, jog)
    if r.status_code != 200:
        raise SystemExit(f"{mid} jog: {r.status_code} {r.text}")


async def class_run(srv: Server, ids: list[str], seconds: float) -> None:
    before = service(srv)
    pids = {w["id"]: w["pid"] for w in before["workers"] if w["alive"]}
    assert srv.proc is not None
    cpu0 = {wid: cpu_s(pid) for wid, pid in pids.items()}
    gw0, t0 = cpu_s(srv.proc.pid), time.monotonic()
    urls = [f"{srv.ws_base}/api/machines/{m}/telemetry" for m in ids]
    results = await asyncio.gather(*(subscriber(u, seconds) for u in urls))
    wall = time.monotonic() - t0
    gw1 = cpu_s(srv.proc.pid)
    cpu1 = {wid: cpu_s(pid) for wid, pid in pids.items()}
    after = service(srv)
    overruns = []
    for w in after["workers"]:
        old = next((b for b in before["workers"] if b["id"] == w["id"]), None)
        if old is None or w["loop"] is None or old["loop"] is None:
            continue
        runs = w["loop"]["overruns"] - old["loop"]["overruns"]
        ticks = w["loop"]["ticks"] - old["loop"]["ticks"]
        overruns.append(f"{w['id']}@{w['node']}:{len(w['machines'])}m {runs}/{ticks}")
    lat = np.concatenate([r.latency_s for r in results]) * 1e3
    gaps = sum(r.gaps for r in results)
    workers_pct = 100 * sum(cpu1[w] - cpu0[w] for w in pids) / wall
    n = len(ids)
    print(
        f"  N={n:2d}: telemetry p50 {np.percentile(lat, 50):5.1f} ms "
        f"p99 {np.percentile(lat, 99):6.1f} ms | gaps {gaps} | "
        f"CPU per machine: workers {workers_pct / n:4.1f} % "
        f"gateway {100 * (gw1 - gw0) / wall / n:4.1f} % | "
        f"overruns/ticks per worker: {', '.join(overruns)}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=500, help="per command kind")
    parser.add_argument("--machines", type=int, nargs="*", default=[3, 6, 9])
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    t_start = time.monotonic()
    with local_cluster(2) as cluster, tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "bench.sqlite", "--cluster", cluster.address, "--workers", "3")
        srv.start()
        try:
            workers = service(srv)["workers"]
            print(
                f"cluster bench: head + 2 nodes on this host, {len(workers)} worker actors on "
                f"nodes {sorted(w['node'] for w in workers)} (up in "
                f"{time.monotonic() - t_start:.1f} s)"
            )
            srv.wait_powered("demo")
            for _ in range(50):  # warm the connection and the code paths
                srv.http.get("/api/machines/demo/status")
            round_trip(srv, "demo", args.requests)
            srv.http.delete("/api/machines/demo")
            print(
                f"class figures: N busy machines (M3 S1000, Z jogging), one viewer each "
                f"({len(SIGNALS)} signals), {args.seconds:.0f} s per run"
            )
            ids: list[str] = []
            for n in args.machines:
                while len(ids) < n:
                    ids.append(f"m{len(ids) + 1}")
                    add_busy(srv, ids[-1])
                time.sleep(1.0)  # a fresh news report per worker before the run
                asyncio.run(class_run(srv, ids, args.seconds))
        finally:
            srv.close()


if __name__ == "__main__":
    main()
