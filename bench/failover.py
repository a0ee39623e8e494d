"""Failover: a worker killed with SIGKILL while its machines run. Prints how long until the
gateway noticed (the worker shown dead), until every machine of it was rebuilt on a live
worker and answering, and until the replacement worker was up. Bar: noticed within 1 s."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.backend.server import Server


def status(srv: Server) -> dict[str, Any]:
    data: dict[str, Any] = srv.http.get("/api/service/status").json()
    return data


def until(pred: Any, timeout_s: float = 60.0) -> float:
    """Seconds until `pred()` holds (polled every millisecond)."""
    t0 = time.perf_counter()
    while not pred():
        if time.perf_counter() - t0 > timeout_s:
            raise SystemExit("timed out")
        time.sleep(0.001)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--machines", type=int, default=10, help="demo machines besides the demo")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "f.sqlite", "--workers", str(args.workers)).start()
        try:
            for i in range(args.machines):
                r = srv.http.post("/api/machines", json={"id": f"m{i}", "demo": True})
                assert r.status_code == 201, r.text
            until(lambda: all(w["loop"] for w in status(srv)["workers"]))
            victim = max(status(srv)["workers"], key=lambda w: len(w["machines"]))
            lost = victim["machines"]
            t0 = time.perf_counter()
            os.kill(victim["pid"], signal.SIGKILL)
            noticed = until(
                lambda: (
                    not next(w for w in status(srv)["workers"] if w["id"] == victim["id"])["alive"]
                )
            )
            rebuilt = until(lambda: status(srv)["machines_rebuilt"] == len(lost))
            for mid in lost:
                until(lambda mid=mid: srv.http.get(f"/api/machines/{mid}/status").is_success)
            answering = time.perf_counter() - t0
            replaced = until(
                lambda: sum(w["alive"] for w in status(srv)["workers"]) == args.workers
            )
            print(f"worker {victim['id']} killed with {len(lost)} of {args.machines + 1} machines")
            print(f"  noticed dead after        {noticed * 1e3:7.1f} ms   (bar <= 1000 ms)")
            print(f"  all rebuilt after         {(noticed + rebuilt) * 1e3:7.1f} ms")
            print(f"  all answering after       {answering * 1e3:7.1f} ms")
            print(f"  replacement worker after  {(answering + replaced):7.2f} s")
        finally:
            srv.close()


if __name__ == "__main__":
    main()
