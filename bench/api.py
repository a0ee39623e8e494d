"""Command round trip over loopback HTTP with 50 viewers attached: MDI blocks and jog
commands against the real service (gateway and workers), one keep-alive connection, each
request answered with its acknowledgement, while 50 websocket viewers (a separate client
process) stream a few signals of the same machine and read everything.

Prints per command kind the round trip p50/p99/max and the `latency_ms` the service reports
(gateway hand-over to the kernel on the worker) p50/p99/max, and the buckets of the service's
own command latency histogram (`GET /metrics`, scraped before and after the kind) that hold
its p50 and p99, beside the buckets the round trip's fall in; then what the viewers received
meanwhile, overruns summed over every worker and one line per worker.
Bar: round trip p99 <= 5 ms and 0 overruns.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from prometheus_client.parser import text_string_to_metric_families

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.service import Meter, Viewers, latencies_ms, pct
from tests.backend.server import Server

KINDS: dict[str, list[dict[str, object]]] = {
    "jog": [
        {"type": "jog", "axis": "Z", "action": "start", "direction": 1},
        {"type": "jog", "axis": "Z", "action": "stop"},
    ],
    "MDI": [{"type": "mdi", "block": "M3 S800"}, {"type": "mdi", "block": "M5"}],
}
SIGNALS = ["S1.speed_act_rpm", "S1.lag_deg", "Z.pos_act_mm", "Z.lag_mm"]


def latency_buckets(srv: Server, command: str) -> dict[float, float]:
    """The command latency histogram's cumulative counts by upper bound (s), as scraped."""
    out: dict[float, float] = {}
    for family in text_string_to_metric_families(srv.http.get("/metrics").text):
        if family.name != "inbetrieb_command_latency_seconds":
            continue
        for sample in family.samples:
            if sample.name.endswith("_bucket") and sample.labels["type"] == command:
                out[float(sample.labels["le"])] = sample.value
    return out


def bucket_of(bounds: list[float], value_s: float) -> int:
    """The index of the bucket (by upper bound) a value falls in."""
    return next((i for i, le in enumerate(bounds) if value_s <= le), len(bounds) - 1)


def histogram_line(before: dict[float, float], after: dict[float, float], rtt_s: np.ndarray) -> str:
    """Where the histogram puts p50 and p99 of this kind's commands, and the round trip's."""
    bounds = sorted(after)
    counts = [after[le] - before.get(le, 0.0) for le in bounds]
    total = counts[-1]
    parts = []
    for q in (50, 99):
        mine = next(i for i, c in enumerate(counts) if c >= total * q / 100)
        theirs = bucket_of(bounds, pct(rtt_s, q))
        low = bounds[mine - 1] * 1e3 if mine else 0.0
        parts.append(
            f"p{q} in ({low:g}, {bounds[mine] * 1e3:g}] ms, "
            f"round trip {'same bucket' if mine == theirs else f'{theirs - mine:+d} bucket(s)'}"
        )
    return f"/metrics ({total:.0f} commands): " + "; ".join(parts)


def figures(ms: np.ndarray) -> str:
    return f"p50 {pct(ms, 50):5.2f} ms  p99 {pct(ms, 99):5.2f} ms  max {pct(ms, 100):6.2f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=2000, help="per command kind")
    parser.add_argument("--viewers", type=int, default=50)
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    args = parser.parse_args()
    extra = ["--workers", str(args.workers)] if args.workers else []
    with tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "bench.sqlite", *extra).start()
        assert srv.proc is not None
        try:
            srv.wait_powered("demo")
            for _ in range(50):  # warm the connection and the code paths
                srv.http.get("/api/machines/demo/status")
            url = f"{srv.ws_base}/api/machines/demo/telemetry"
            viewers = Viewers([url] * args.viewers, SIGNALS, headers=srv.auth).start()
            print(
                f"command round trip, {args.requests} requests per kind, loopback HTTP, "
                f"{args.viewers} viewers of {len(SIGNALS)} signals attached"
            )
            meter = Meter(srv.http, srv.proc.pid)
            meter.start()
            t0 = time.monotonic()
            for kind, bodies in KINDS.items():
                command = str(bodies[0]["type"])
                scraped = latency_buckets(srv, command)
                rtt, handover = [], []
                for i in range(args.requests):
                    t = time.perf_counter()
                    r = srv.command("demo", bodies[i % len(bodies)])
                    rtt.append(time.perf_counter() - t)
                    if r.status_code != 200:
                        raise SystemExit(f"{kind}: {r.status_code} {r.text}")
                    handover.append(r.json()["latency_ms"])
                    # a jog starts only once the last one's braking ended (not timed)
                    stopped = bodies[i % len(bodies)].get("action") == "stop"
                    while stopped and srv.axis("Z")["state"] != "STANDSTILL":
                        time.sleep(0.001)
                print(f"  {kind:4s} round trip  {figures(np.array(rtt) * 1e3)}")
                print(f"  {kind:4s} hand-over   {figures(np.array(handover))}  (latency_ms)")
                after = latency_buckets(srv, command)
                print(f"  {kind:4s} {histogram_line(scraped, after, np.array(rtt))}")
            seconds = time.monotonic() - t0
            received = viewers.stop()
            service = meter.stop()
            lat = latencies_ms(received)
            failed = [v.error for v in received if v.error]
            print(
                f"viewers meanwhile: sample to client p99 {pct(lat, 99):.1f} ms, "
                f"{sum(v.frames for v in received) / seconds / len(received):.1f} frames/s "
                f"per viewer, gaps {sum(v.gaps for v in received)}"
                + (f", {len(failed)} failed: {failed[0]}" if failed else "")
            )
            print(
                f"overruns of every worker during the run: {service.overruns} | CPU gateway "
                f"{100 * service.gateway_cpu_s / service.wall_s:.0f} % workers "
                f"{100 * service.worker_cpu_s / service.wall_s:.0f} %"
            )
            service.print_workers()
        finally:
            srv.close()


if __name__ == "__main__":
    main()
