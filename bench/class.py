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

`--class-run`: a real class instead. A fresh service with an instructor, who creates a class
of `--seats` seats (default 50) of `--exercise` (default multi-gain; every seat its own
machine from the exercise's template, with its faults and checks). Each student logs in by
their seat's one-time link (a session per student: cookie, CSRF header, a tab id), turns the
spindle (`M3 S800`) and jogs X back and forth at `--feed`, a second's pause at each end
(taking control of the free seat machine with the first command), and opens their seat's
telemetry websocket with a ticket (`POST /api/auth/ws-ticket`, as the HMI does) subscribed to
4 signals; the instructor opens the console's grid websocket. After `--settle-s` the load is
held for `--seconds`, then:
worker overruns during the hold, telemetry sample-to-client p50/p99, the grid's update latency
p50/p99 (receive time minus each running seat's `status_unix`, split into the status' age
when the gateway built the frame and the frame's delivery), the grid's frame interval p50/p99
and frames/s, commands refused (with the reasons), CPU of workers, gateway and load
generators, and a verdict: real time held when 0 overruns, telemetry p99 <= 50 ms, grid
latency p99 <= 500 ms (a frame every 250 ms showing statuses pushed every 50-100 ms) and at
least 90 % of the grid's nominal frames arrived.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import httpx
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from api.auth import Role
from backend.services.console import GRID_S
from bench.classroom import GridFrames, GridWatch, Jogging, Login, student_login
from bench.service import Meter, Run, Viewers, cpu_s, latencies_ms, pct
from tests.backend.server import Server, add_users, bearer

SIGNALS = ["S1.speed_act_rpm", "S1.lag_deg", "X.pos_act_mm", "X.lag_mm"]
SPIN = "M3 S800"
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


async def power_and_spin(http: httpx.AsyncClient, mid: str, gate: asyncio.Semaphore) -> None:
    """Wait for the machine's drives, then turn its spindle (`M3 S800`)."""
    deadline = time.monotonic() + 60
    while not (await http.get(f"/api/machines/{mid}/status")).json()["plc"]["drives_powered"]:
        if time.monotonic() > deadline:
            raise RuntimeError(f"{mid}: drives not powered")
        await asyncio.sleep(0.2)
    async with gate:
        r = await http.post(f"/api/machines/{mid}/commands", json={"type": "mdi", "block": SPIN})
        r.raise_for_status()


async def set_up(base: str, mids: list[str], headers: dict[str, str]) -> None:
    """Create the machines, wait for their drives, turn their spindles."""
    gate = asyncio.Semaphore(SETUP_CONCURRENCY)
    async with httpx.AsyncClient(base_url=base, timeout=60, headers=headers) as http:

        async def one(mid: str) -> None:
            async with gate:
                r = await http.post("/api/machines", json={"id": mid, "demo": True})
                r.raise_for_status()
            await power_and_spin(http, mid, gate)

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
            token = Login.token(srv.auth)
            jogging = Jogging(srv.base, dict.fromkeys(mids, token), jog_s)
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


# --- a class run --------------------------------------------------------------------------
INSTRUCTOR = "trainer"
CLASS_ID = "bench"
GRID_P99_BAR_MS = 500.0
GRID_FRAMES_SHARE = 0.9  # of the nominal 1 / GRID_S frames per second
PAUSE_S = 1.0  # a student between a jog's stop and the next jog the other way
VIEWERS_START_S = 300.0  # a loaded service may take minutes to let 50 students in


@dataclass
class ClassRun:
    """The figures of a class run."""

    seats: int
    service: Run
    telemetry_ms: np.ndarray
    viewers_failed: int
    gaps: int
    grid: GridFrames
    rt_factor_min: float
    commands: int
    refused: int
    reasons: list[tuple[str, int]]
    clients_pct: float

    def verdict(self) -> list[str]:
        """What missed real time (nothing: it held)."""
        missed = []
        if self.service.overruns:
            missed.append(f"{self.service.overruns} overruns")
        if not pct(self.telemetry_ms, 99) <= P99_BAR_MS:
            missed.append(f"telemetry p99 > {P99_BAR_MS:g} ms")
        if self.viewers_failed:
            missed.append(f"{self.viewers_failed} viewers failed")
        if not pct(self.grid.latency_ms(), 99) <= GRID_P99_BAR_MS:
            missed.append(f"grid latency p99 > {GRID_P99_BAR_MS:g} ms")
        if self.grid_fps() < GRID_FRAMES_SHARE / GRID_S:
            missed.append(f"grid frames/s < {GRID_FRAMES_SHARE / GRID_S:g}")
        if self.grid.error:
            missed.append(f"grid failed ({self.grid.error})")
        return missed

    def grid_fps(self) -> float:
        return len(self.grid.recv_unix) / self.grid.counted_s if self.grid.counted_s else 0.0

    def print(self) -> None:
        s, g, wall = self.service, self.grid, self.service.wall_s
        print("workers during the hold:")
        s.print_workers("  ")

        def ms(a: np.ndarray) -> str:
            return (
                f"p50 {pct(a, 50):6.1f}  p99 {pct(a, 99):6.1f}  max {np.max(a, initial=0):6.1f} ms"
            )

        print(f"overruns:                  {s.overruns}")
        print(
            f"telemetry sample-to-client {ms(self.telemetry_ms)}  (gaps {self.gaps}, "
            f"viewers failed {self.viewers_failed} of {self.seats})"
        )
        print(f"grid update latency        {ms(g.latency_ms())}  (receive - seat status_unix)")
        print(f"  status age at build      {ms(g.staleness_ms())}")
        print(f"  frame delivery           {ms(g.delivery_ms())}")
        print(f"grid frame interval        {ms(g.interval_ms())}  (nominal {GRID_S * 1e3:g} ms)")
        print(
            f"grid frames/s              {self.grid_fps():.2f}  ({g.seats} seats a frame, "
            f"{g.bytes / max(1, len(g.recv_unix)) / 1e3:.1f} kB)"
        )
        print(f"slowest seat rt factor     {self.rt_factor_min:.3f}")
        print(
            f"commands                   {self.commands} sent, {self.refused} refused or failed "
            "during the hold; reasons over the whole run:"
        )
        for reason, n in self.reasons[:5]:
            print(f"  {n:5d} x {reason}")
        print(
            f"CPU (% of a core)          workers {100 * s.worker_cpu_s / wall:.0f} "
            f"({100 * s.worker_cpu_s / wall / self.seats:.2f} per seat), "
            f"gateway {100 * s.gateway_cpu_s / wall:.0f}, load generators {self.clients_pct:.0f}"
        )
        missed = self.verdict()
        print(
            f"verdict: {self.seats} seats "
            + ("held real time" if not missed else "did NOT hold real time: " + ", ".join(missed))
        )


async def seats_busy(base: str, logins: dict[str, Login]) -> None:
    """Every student waits for their machine's drives and turns its spindle."""
    gate = asyncio.Semaphore(SETUP_CONCURRENCY)

    async def one(mid: str, login: Login) -> None:
        async with login.client(base, 60) as http:
            await power_and_spin(http, mid, gate)

    await asyncio.gather(*(one(mid, login) for mid, login in logins.items()))


def class_run(
    seats: int,
    exercise: str,
    seconds: float,
    settle_s: float,
    jog_s: float,
    feed: float,
    extra: list[str],
) -> ClassRun:
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "bench.sqlite"
        srv = Server(db, "--no-demo", *extra)
        instructor = bearer(add_users(db, {INSTRUCTOR: Role.INSTRUCTOR})[INSTRUCTOR])
        srv.start()
        assert srv.proc is not None
        try:
            t0 = time.monotonic()
            body = {"id": CLASS_ID, "exercises": [exercise], "seats": seats}
            r = srv.http.post("/api/classes", json=body, headers=instructor, timeout=300)
            if r.status_code != 201:
                raise RuntimeError(f"class not created: {r.status_code} {r.text[:300]}")
            created = r.json()
            t_class = time.monotonic() - t0
            machines = {s["n"]: s["machine"] for s in created["info"]["seats"]}
            logins = {
                machines[link["n"]]: student_login(srv.base, link["url"], f"tab-{link['n']}")
                for link in created["links"]
            }
            asyncio.run(seats_busy(srv.base, logins))
            print(
                f"class of {seats} created in {t_class:.1f} s, students logged in and "
                f"spindles turning after {time.monotonic() - t0:.1f} s"
            )
            jogging = Jogging(srv.base, logins, jog_s, feed, PAUSE_S)
            jogging.thread.start()
            grid = GridWatch(f"{srv.ws_base}/api/classes/{CLASS_ID}/grid", instructor).start()
            urls = [f"{srv.ws_base}/api/machines/{mid}/telemetry" for mid in logins]
            t_view = time.monotonic()
            viewers = Viewers(urls, SIGNALS, settle_s, sessions=list(logins.values()))
            viewers.start(VIEWERS_START_S)
            print(f"viewers subscribed in {time.monotonic() - t_view - settle_s:.1f} s")
            meter = Meter(srv.http, srv.proc.pid)
            meter.start()
            grid.count()
            c0, r0 = jogging.commands, jogging.refused
            clients0 = cpu_s(viewers.proc.pid) + cpu_s(os.getpid())
            time.sleep(seconds)
            clients_s = cpu_s(viewers.proc.pid) + cpu_s(os.getpid()) - clients0
            service = meter.stop()
            frames = grid.stop()
            commands, refused = jogging.commands - c0, jogging.refused - r0
            received = viewers.stop()
            jogging.stop()
            status = srv.http.get("/api/service/status").json()["machines"]
            return ClassRun(
                seats=seats,
                service=service,
                telemetry_ms=latencies_ms(received),
                viewers_failed=sum(1 for v in received if v.error),
                gaps=sum(v.gaps for v in received),
                grid=frames,
                rt_factor_min=min(m["rt_factor"] for m in status.values()),
                commands=commands,
                refused=refused,
                reasons=jogging.reasons.most_common(),
                clients_pct=100 * clients_s / service.wall_s,
            )
        finally:
            srv.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--machines", default="20,50,100,150,200", help="N list, e.g. 20,50")
    parser.add_argument("--seconds", type=float, default=60.0, help="hold per N")
    parser.add_argument("--jog-s", type=float, default=2.0, help="jog time per direction")
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    parser.add_argument("--class-run", action="store_true", help="a class of students instead")
    parser.add_argument("--seats", type=int, default=50, help="class run: seats (1..60)")
    parser.add_argument("--exercise", default="multi-gain", help="class run: exercise id")
    parser.add_argument("--feed", type=float, default=1000.0, help="class run: jog mm/min")
    parser.add_argument("--settle-s", type=float, default=2.0, help="class run: settling time")
    args = parser.parse_args()
    extra = ["--workers", str(args.workers)] if args.workers else []
    if args.class_run:
        print(
            f"class run: {args.seats} seats of '{args.exercise}', each student M3 S800 and X "
            f"jogging {args.jog_s:g} s each way ({PAUSE_S:g} s pause) at {args.feed:g} mm/min, "
            "one viewer of "
            f"{len(SIGNALS)} signals each, the instructor's grid; {args.settle_s:g} s settling, "
            f"{args.seconds:g} s hold, {os.cpu_count()} cores"
        )
        class_run(
            args.seats, args.exercise, args.seconds, args.settle_s, args.jog_s, args.feed, extra
        ).print()
        return
    ns = [int(n) for n in args.machines.split(",") if n]
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
