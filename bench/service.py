"""What several benches share: the service's worker figures over a run, CPU of the gateway and
of its worker processes, and light websocket viewers that time every telemetry sample."""

from __future__ import annotations

import asyncio
import json
import multiprocessing as mp
import os
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from multiprocessing.synchronize import Event
from pathlib import Path
from typing import Any

import httpx
import numpy as np
from websockets.asyncio.client import connect

from api.telemetry import MAGIC
from bench.classroom import Login, ws_ticket

REPORT_WAIT_S = 3.0  # workers report loop figures once a second; give up on one after this
STOP_POLL_S = 0.2  # how soon a viewer notices it should stop
SHOW_OVERRUNS = 5  # the worst overruns of a run, printed with their cause


def cpu_s(pid: int | None) -> float:
    """User + system CPU seconds of a process (Linux /proc); 0 when it is gone or remote."""
    if pid is None:
        return 0.0
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return 0.0
    fields = stat.rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def service_status(http: httpx.Client) -> dict[str, Any]:
    """`GET /api/service/status` as JSON."""
    r = http.get("/api/service/status")
    r.raise_for_status()
    data: dict[str, Any] = r.json()
    return data


def overruns(status: dict[str, Any]) -> int:
    """Loop overruns summed over every worker."""
    return sum(w["loop"]["overruns"] for w in status["workers"] if w["loop"] is not None)


def fresh_status(http: httpx.Client) -> dict[str, Any]:
    """The service status once every live worker has reported again after this call (loop
    figures come about once a second), so the figures include everything up to now."""
    ticks0 = {w["id"]: (w["loop"] or {}).get("ticks") for w in service_status(http)["workers"]}
    deadline = time.monotonic() + REPORT_WAIT_S
    while True:
        status = service_status(http)
        stale = [
            w
            for w in status["workers"]
            if w["alive"] and (w["loop"] or {}).get("ticks") == ticks0.get(w["id"])
        ]
        if not stale or time.monotonic() > deadline:
            return status
        time.sleep(0.05)


@dataclass
class WorkerRun:
    """One worker's figures over a run."""

    id: str
    pid: int | None
    machines: int
    overruns: int
    cpu_s: float
    loop: dict[str, Any]  # its last report: work and wake-up percentiles


@dataclass
class Run:
    """The service over a run: overruns and CPU of every worker, CPU of the gateway."""

    wall_s: float
    gateway_cpu_s: float
    workers: list[WorkerRun]
    overrun_records: list[dict[str, Any]]  # overruns reported during the run

    @property
    def overruns(self) -> int:
        return sum(w.overruns for w in self.workers)

    @property
    def worker_cpu_s(self) -> float:
        return sum(w.cpu_s for w in self.workers)

    def print_workers(self, indent: str = "  ") -> None:
        """One line per worker, then the worst overruns reported during the run (workers
        keep their last 20)."""
        for w in self.workers:
            lp = w.loop
            print(
                f"{indent}worker {w.id} (pid {w.pid}, {w.machines} machines): "
                f"overruns {w.overruns}  work p50 {lp.get('work_p50_ms', 0):.2f} "
                f"p99 {lp.get('work_p99_ms', 0):.2f} max {lp.get('work_max_ms', 0):.2f} ms  "
                f"wake late p99 {lp.get('wake_late_p99_ms', 0):.2f} ms  "
                f"CPU {100 * w.cpu_s / self.wall_s:.0f} %"
            )
        worst = sorted(self.overrun_records, key=lambda o: -o["wake_late_ms"] - o["work_ms"])
        for o in worst[:SHOW_OVERRUNS]:
            print(
                f"{indent}  overrun: woke {o['wake_late_ms']:.1f} ms late, "
                f"work {o['work_ms']:.1f} ms"
            )
        if len(worst) > SHOW_OVERRUNS:
            more = len(worst) - SHOW_OVERRUNS
            print(f"{indent}  ... and {more} more (each worker keeps its last 20)")


class Meter:
    """Measures the service over a run: `start()`, the load, then `stop()`."""

    def __init__(self, http: httpx.Client, gateway_pid: int) -> None:
        self.http = http
        self.gateway_pid = gateway_pid

    def start(self) -> None:
        self.before = fresh_status(self.http)
        self.pids = {w["id"]: w["pid"] for w in self.before["workers"]}
        self.cpu0 = {wid: cpu_s(pid) for wid, pid in self.pids.items()}
        self.gateway0 = cpu_s(self.gateway_pid)
        self.t0 = time.monotonic()
        self.time0 = time.time()

    def stop(self) -> Run:
        wall = time.monotonic() - self.t0
        cpu1 = {wid: cpu_s(pid) for wid, pid in self.pids.items()}
        gateway = cpu_s(self.gateway_pid) - self.gateway0
        t1 = time.time()
        after = fresh_status(self.http)
        old = {w["id"]: w for w in self.before["workers"]}
        workers, records = [], []
        for w in after["workers"]:
            lp = w["loop"] or {}
            lp0 = (old.get(w["id"]) or {}).get("loop") or {}
            workers.append(
                WorkerRun(
                    w["id"],
                    w["pid"],
                    len(w["machines"]),
                    lp.get("overruns", 0) - lp0.get("overruns", 0),
                    cpu1.get(w["id"], 0.0) - self.cpu0.get(w["id"], 0.0),
                    lp,
                )
            )
            records += [
                o for o in lp.get("recent_overruns", []) if self.time0 <= o["time_unix"] <= t1 + 0.1
            ]
        return Run(wall, gateway, workers, records)


# --- viewers ---------------------------------------------------------------------------------
@dataclass
class Viewer:
    """What one telemetry viewer received: per binary frame its receive time and header
    figures (samples are not decoded), and how many JSON messages came."""

    recv_unix: list[float] = field(default_factory=list)
    first_cycle: list[int] = field(default_factory=list)
    count: list[int] = field(default_factory=list)
    stride: list[int] = field(default_factory=list)
    t0_unix: list[float] = field(default_factory=list)
    cycle_s: list[float] = field(default_factory=list)
    gaps: int = 0  # cycles missing between or within frames (stride > 1, skipped cycles)
    status_messages: int = 0
    other_messages: int = 0
    error: str | None = None
    counted_s: float = 0.0  # how long frames were counted

    @property
    def frames(self) -> int:
        return len(self.recv_unix)

    @property
    def samples(self) -> int:
        return sum(self.count)

    def latency_s(self) -> np.ndarray:
        """Receive time minus each sample's nominal wall time `t0_unix + cycle * cycle_s`."""
        if not self.count:
            return np.zeros(0)
        count = np.array(self.count)
        frame = np.repeat(np.arange(len(count)), count)
        k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        cycle = np.array(self.first_cycle)[frame] + np.array(self.stride)[frame] * k
        nominal = np.array(self.t0_unix)[frame] + cycle * np.array(self.cycle_s)[frame]
        latency: np.ndarray = np.array(self.recv_unix)[frame] - nominal
        return latency


def _header(buf: bytes) -> dict[str, Any]:
    """The JSON header of a binary frame, without validating it or touching the samples."""
    if buf[:4] != MAGIC:
        raise ValueError("not a telemetry frame")
    (n,) = struct.unpack_from("<I", buf, 4)
    header: dict[str, Any] = json.loads(buf[8 : 8 + n])
    return header


async def view(
    url: str,
    signals: list[str],
    until: float,
    start: float | None = None,
    stop: Callable[[], bool] | None = None,
    subscribed: Callable[[], None] | None = None,
    headers: dict[str, str] | None = None,
) -> Viewer:
    """Subscribe to `signals` and read every message until monotonic time `until` (or until
    `stop()` says so, checked at least every `STOP_POLL_S`); frames count from monotonic time
    `start` (to skip the first burst after subscribing); `subscribed()` is called once the
    subscription is sent. `headers`: the credentials (an API token)."""
    v = Viewer()
    start = time.monotonic() if start is None else start
    expected: int | None = None
    try:
        async with connect(url, max_size=None, additional_headers=headers) as ws:
            await ws.send(json.dumps({"type": "subscribe", "signals": signals}))
            if subscribed:
                subscribed()
            while (left := until - time.monotonic()) > 0 and not (stop and stop()):
                try:
                    msg = await asyncio.wait_for(ws.recv(), min(left, STOP_POLL_S))
                except TimeoutError:
                    continue
                now = time.time()
                if not isinstance(msg, bytes):
                    if '"status"' in msg[:20]:
                        v.status_messages += 1
                    else:
                        v.other_messages += 1
                    continue
                h = _header(msg)
                first, count, stride = h["first_cycle"], h["count"], h["stride"]
                if time.monotonic() >= start:
                    if expected is not None and first != expected:
                        v.gaps += abs(first - expected)
                    v.gaps += (stride - 1) * max(0, count - 1)
                    v.recv_unix.append(now)
                    v.first_cycle.append(first)
                    v.count.append(count)
                    v.stride.append(stride)
                    v.t0_unix.append(h["t0_unix"])
                    v.cycle_s.append(h["cycle_s"])
                expected = first + count * stride
    except Exception as e:  # a dropped viewer is a figure, not a crash of the bench
        v.error = f"{type(e).__name__}: {e}"
    v.counted_s = max(0.0, time.monotonic() - start)
    return v


def latencies_ms(viewers: list[Viewer]) -> np.ndarray:
    """Sample-to-client latency of every sample every viewer received, ms."""
    parts = [v.latency_s() for v in viewers]
    return np.concatenate(parts) * 1e3 if parts else np.zeros(0)


def pct(a: np.ndarray, q: float) -> float:
    """Percentile, NaN for no data."""
    return float(np.percentile(a, q)) if len(a) else float("nan")


def _viewers_main(
    urls: list[str],
    signals: list[str],
    settle_s: float,
    stop: Event,
    ready: Any,
    out: Any,
    headers: dict[str, str] | None,
    sessions: list[Login] | None,
) -> None:
    """Child process: one viewer per URL until `stop` is set; counts subscriptions (and
    viewers that failed before one) in `ready`, puts the results to `out`."""

    def done() -> None:
        with ready.get_lock():
            ready.value += 1

    async def one(url: str, session: Login | None, start: float, until: float) -> Viewer:
        counted = False

        def subscribed() -> None:
            nonlocal counted
            counted = True
            done()

        if session is not None:  # as a page does: a ticket of its session just before
            try:
                async with session.client(http_base(url)) as http:
                    url = f"{url}?ticket={await ws_ticket(http)}"
            except httpx.HTTPError as e:
                done()
                return Viewer(error=f"no ticket: {type(e).__name__}: {e}")
        v = await view(url, signals, until, start, stop.is_set, subscribed, headers)
        if not counted:
            done()
        return v

    async def main() -> list[Viewer]:
        start = time.monotonic() + settle_s
        until = time.monotonic() + 24 * 3600
        each: list[Login | None] = [*sessions] if sessions else [None] * len(urls)
        return await asyncio.gather(
            *(one(u, s, start, until) for u, s in zip(urls, each, strict=True))
        )

    out.put(asyncio.run(main()))


def http_base(ws_url: str) -> str:
    """`http://host:port` of a `ws://host:port/...` URL."""
    scheme, rest = ws_url.split("://", 1)
    return f"{'https' if scheme == 'wss' else 'http'}://{rest.split('/', 1)[0]}"


class Viewers:
    """Telemetry viewers in a separate client process (so they do not compete with the
    bench's own timing for this interpreter): one per URL, from `start()` until `stop()`.
    Credentials: `headers` (an API token) for all, or a login `sessions` each (a ticket of
    that session is fetched just before its socket opens, as the HMI does)."""

    def __init__(
        self,
        urls: list[str],
        signals: list[str],
        settle_s: float = 0.5,
        headers: dict[str, str] | None = None,
        sessions: list[Login] | None = None,
    ) -> None:
        ctx = mp.get_context("spawn")
        self.stopping = ctx.Event()
        self.ready: Any = ctx.Value("i", 0)
        self.out: Any = ctx.Queue()
        self.proc = ctx.Process(
            target=_viewers_main,
            args=(urls, signals, settle_s, self.stopping, self.ready, self.out, headers, sessions),
        )
        self.n = len(urls)
        self.settle_s = settle_s

    def start(self, timeout_s: float = 60.0) -> Viewers:
        """Start the viewers; return once all have subscribed (or failed: a figure of
        `stop()`) and their first burst passed."""
        self.proc.start()
        deadline = time.monotonic() + timeout_s
        while self.ready.value < self.n:
            if time.monotonic() > deadline or not self.proc.is_alive():
                self.proc.terminate()  # our own child
                raise RuntimeError(f"only {self.ready.value} of {self.n} viewers subscribed")
            time.sleep(0.05)
        time.sleep(self.settle_s)
        return self

    def stop(self) -> list[Viewer]:
        """Stop the viewers; what each received."""
        self.stopping.set()
        viewers: list[Viewer] = self.out.get(timeout=60)
        self.proc.join(timeout=10)
        return viewers
