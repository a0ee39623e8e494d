"""The gateway on a local multi-node Ray cluster (`inbetrieb serve --cluster HOST:PORT`).

Starts a head and two worker nodes on this host and, against real gateways with three workers
(one actor per node), prints:
- the command round trip over loopback HTTP through the gateway to a worker actor and back,
  p50/p99/max per kind (MDI blocks, jog start/stop), on the demo machine;
- the class figures of `bench/class.py` for a few N (a fresh gateway per N on the same
  cluster): N busy demo lathes (M3 S800, X jogging back and forth), one websocket viewer
  each; overruns of every worker, sample-to-client p50/p99, gaps, CPU per machine of the
  worker actors' processes and of the gateway.
Figures only, no bars: this host's two cores are shared with Ray's own processes.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.api import KINDS
from tests.backend.raycluster import local_cluster
from tests.backend.server import Server

class_bench: Any = importlib.import_module("bench.class")  # `class` is a keyword


def round_trip(srv: Server, mid: str, requests: int) -> None:
    workers = srv.http.get("/api/service/status").json()["workers"]
    node = next(w["node"] for w in workers if mid in w["machines"])
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=500, help="per command kind")
    parser.add_argument("--machines", default="3,6,12", help="N list, e.g. 3,6")
    parser.add_argument("--seconds", type=float, default=10.0, help="hold per N")
    parser.add_argument("--workers", type=int, default=3, help="worker actors")
    args = parser.parse_args()
    t_start = time.monotonic()
    with local_cluster(2) as cluster, tempfile.TemporaryDirectory() as tmp:
        extra = ["--cluster", cluster.address, "--workers", str(args.workers)]
        srv = Server(Path(tmp) / "bench.sqlite", *extra).start()
        try:
            workers = srv.http.get("/api/service/status").json()["workers"]
            print(
                f"cluster bench: head + 2 nodes on this host, {len(workers)} worker actors on "
                f"nodes {sorted(w['node'] for w in workers)} (cluster and gateway up in "
                f"{time.monotonic() - t_start:.1f} s)"
            )
            srv.wait_powered("demo")
            for _ in range(50):  # warm the connection and the code paths
                srv.http.get("/api/machines/demo/status")
            round_trip(srv, "demo", args.requests)
        finally:
            srv.close()
        print(
            f"class figures: N demo lathes (M3 S800, X jogging 2 s each way), one viewer of "
            f"{len(class_bench.SIGNALS)} signals each, {args.seconds:g} s hold per N"
        )
        steps = []
        for n in [int(n) for n in args.machines.split(",") if n]:
            steps.append(class_bench.step(n, args.seconds, 2.0, extra))
        print("    N  overruns  p50 ms  p99 ms  gaps  rt min  CPU/machine %  gateway %")
        for s in steps:
            print(
                f"{s.n:5d}  {s.overruns:8d}  {s.p50_ms:6.1f}  {s.p99_ms:6.1f}  {s.gaps:4d}  "
                f"{s.rt_factor_min:6.3f}  {s.cpu_per_machine_pct:13.2f}  {s.gateway_pct:9.0f}"
            )


if __name__ == "__main__":
    main()
