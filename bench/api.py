"""Command round trip over loopback HTTP: MDI blocks and jog commands against the real
service, one keep-alive connection, each request answered with its acknowledgement.
Prints p50/p99/max per command kind. Bar: p99 <= 10 ms."""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.backend.server import Server

KINDS: dict[str, list[dict[str, object]]] = {
    "MDI": [{"type": "mdi", "block": "M3 S800"}, {"type": "mdi", "block": "M5"}],
    "jog": [
        {"type": "jog", "axis": "Z", "action": "start", "direction": 1},
        {"type": "jog", "axis": "Z", "action": "stop"},
    ],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=2000)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "bench.sqlite").start()
        try:
            for _ in range(50):  # warm the connection and the code paths
                srv.http.get("/api/machines/demo/status")
            print(f"command round trip, {args.requests} requests per kind, loopback HTTP")
            for kind, bodies in KINDS.items():
                rtt = []
                for i in range(args.requests):
                    t0 = time.perf_counter()
                    r = srv.command("demo", bodies[i % len(bodies)])
                    rtt.append(time.perf_counter() - t0)
                    if r.status_code != 200:
                        raise SystemExit(f"{kind}: {r.status_code} {r.text}")
                ms = np.array(rtt) * 1e3
                print(
                    f"{kind:4s}: p50 {np.percentile(ms, 50):5.2f} ms  "
                    f"p99 {np.percentile(ms, 99):5.2f} ms  max {ms.max():6.2f} ms"
                )
            loop = srv.http.get("/api/service/status").json()["loop"]
            print(f"loop overruns meanwhile: {loop['overruns']}")
        finally:
            srv.close()


if __name__ == "__main__":
    main()
