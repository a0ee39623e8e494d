"""The load of a class, for bench/class.py: logins (an API token, or a student's one-time link
as a browser uses it), machines kept busy by their users (X jogging back and forth), and the
instructor console's grid websocket timed frame by frame."""

from __future__ import annotations

import asyncio
import json
import random
import threading
import time
from collections import Counter
from dataclasses import dataclass, field

import httpx
import numpy as np
from websockets.asyncio.client import connect

from api.auth import CLIENT_HEADER, CSRF_COOKIE, CSRF_HEADER

MAX_CONNECTIONS = 64  # per login: a token's machines share one client, a student has one
STOP_POLL_S = 0.2  # how soon the grid watch notices it should stop


@dataclass(frozen=True)
class Login:
    """What a client sends: headers and cookies (hashable, so machines can share a client)."""

    headers: tuple[tuple[str, str], ...] = ()
    cookies: tuple[tuple[str, str], ...] = ()

    @staticmethod
    def token(headers: dict[str, str]) -> Login:
        """An API token's `Authorization` header."""
        return Login(tuple(headers.items()))

    def client(self, base: str, timeout_s: float = 10.0) -> httpx.AsyncClient:
        return httpx.AsyncClient(
            base_url=base,
            timeout=timeout_s,
            headers=dict(self.headers),
            cookies=dict(self.cookies),
            limits=httpx.Limits(max_connections=MAX_CONNECTIONS),
        )


def student_login(base: str, link: str, tab: str) -> Login:
    """Log in by a seat's one-time link as a browser does: the session cookie, the CSRF token
    echoed in its header on every state-changing request, the tab's id (control is a tab's)."""
    with httpx.Client(base_url=base, timeout=30) as c:
        r = c.get(link.replace(base, ""), follow_redirects=False)
        if r.status_code != 303:
            raise RuntimeError(f"login link refused: {r.status_code} {r.text[:120]}")
        headers = {CSRF_HEADER: c.cookies[CSRF_COOKIE], CLIENT_HEADER: tab}
        return Login(tuple(headers.items()), tuple(dict(c.cookies).items()))


async def ws_ticket(http: httpx.AsyncClient) -> str:
    """A one-time ticket that opens one telemetry websocket as this session."""
    r = await http.post("/api/auth/ws-ticket")
    r.raise_for_status()
    return str(r.json()["ticket"])


class Jogging:
    """Every machine's X axis jogging back and forth as its user, from a thread of this
    process: start with a direction and a dead-man lease that outlasts the period, stop after
    the period, wait `pause_s` (a student reads the lag while the axis comes to rest; an
    axis still stopping refuses a new jog), reverse. Commands refused or failed are counted,
    with their reasons."""

    def __init__(
        self,
        base: str,
        machines: dict[str, Login],
        period_s: float,
        feed_mm_min: float | None = None,
        pause_s: float = 0.0,
    ) -> None:
        self.base, self.machines, self.period_s = base, machines, period_s
        self.pause_s = pause_s
        self.feed_mm_min = feed_mm_min
        self.commands = self.refused = 0
        self.reasons: Counter[str] = Counter()
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=lambda: asyncio.run(self.main()), daemon=True)

    async def main(self) -> None:
        clients = {login: login.client(self.base) for login in set(self.machines.values())}
        try:
            await asyncio.gather(
                *(self.jog(clients[login], mid) for mid, login in self.machines.items())
            )
        finally:
            for c in clients.values():
                await c.aclose()

    async def command(self, http: httpx.AsyncClient, mid: str, body: dict[str, object]) -> None:
        self.commands += 1
        try:
            r = await http.post(f"/api/machines/{mid}/commands", json=body)
            if r.status_code != 200:
                self.refused += 1
                self.reasons[f"{body['type']} {body.get('action', '')}: {r.text[:100]}"] += 1
        except httpx.HTTPError as e:
            self.refused += 1
            self.reasons[f"{body['type']}: {type(e).__name__}"] += 1

    async def jog(self, http: httpx.AsyncClient, mid: str) -> None:
        await asyncio.sleep(random.uniform(0, self.period_s))  # spread the commands
        direction = 1
        feed = {} if self.feed_mm_min is None else {"feed_mm_min": self.feed_mm_min}
        while not self.stopping.is_set():
            start = {"type": "jog", "axis": "X", "action": "start", "direction": direction}
            await self.command(http, mid, {**start, **feed, "hold_s": self.period_s + 1.0})
            await asyncio.sleep(self.period_s)
            await self.command(http, mid, {"type": "jog", "axis": "X", "action": "stop"})
            await asyncio.sleep(self.pause_s)
            direction = -direction

    def stop(self) -> None:
        self.stopping.set()
        self.thread.join(timeout=30)


# --- the instructor's grid -------------------------------------------------------------------
@dataclass
class GridFrames:
    """What the grid websocket delivered: per frame its receive time, the time the gateway
    built it, and the wall time of every running seat's status shown in it."""

    recv_unix: list[float] = field(default_factory=list)
    built_unix: list[float] = field(default_factory=list)
    status_unix: list[list[float]] = field(default_factory=list)
    seats: int = 0  # seats in the last frame
    bytes: int = 0
    error: str | None = None
    counted_s: float = 0.0

    def latency_ms(self) -> np.ndarray:
        """Receive time minus each seat's status time, every seat of every frame, ms."""
        return self._per_seat(self.recv_unix)

    def staleness_ms(self) -> np.ndarray:
        """Build time minus each seat's status time: how old the status was when the gateway
        built the frame, ms."""
        return self._per_seat(self.built_unix)

    def delivery_ms(self) -> np.ndarray:
        """Receive time minus build time per frame, ms."""
        delivery: np.ndarray = (np.array(self.recv_unix) - np.array(self.built_unix)) * 1e3
        return delivery

    def interval_ms(self) -> np.ndarray:
        """Time between frames received, ms."""
        interval: np.ndarray = np.diff(np.array(self.recv_unix)) * 1e3
        return interval

    def _per_seat(self, at: list[float]) -> np.ndarray:
        parts = [np.asarray(t) - np.asarray(s) for t, s in zip(at, self.status_unix, strict=True)]
        return np.concatenate(parts) * 1e3 if parts else np.zeros(0)


class GridWatch:
    """The instructor console's grid websocket, read in a thread of this process from
    `start()` until `stop()`; frames count from `count()` on (after the settling time)."""

    def __init__(self, url: str, headers: dict[str, str]) -> None:
        self.url, self.headers = url, headers
        self.frames = GridFrames()
        self.counting = threading.Event()
        self.stopping = threading.Event()
        self.connected = threading.Event()
        self.thread = threading.Thread(target=lambda: asyncio.run(self.main()), daemon=True)

    def start(self, timeout_s: float = 30.0) -> GridWatch:
        self.thread.start()
        if not self.connected.wait(timeout_s) or self.frames.error:
            raise RuntimeError(f"grid websocket did not connect: {self.frames.error}")
        return self

    def count(self) -> None:
        self.t_count = time.monotonic()
        self.counting.set()

    def stop(self) -> GridFrames:
        self.frames.counted_s = time.monotonic() - self.t_count if self.counting.is_set() else 0
        self.stopping.set()
        self.thread.join(timeout=30)
        return self.frames

    async def main(self) -> None:
        f = self.frames
        try:
            async with connect(self.url, max_size=None, additional_headers=self.headers) as ws:
                self.connected.set()
                while not self.stopping.is_set():
                    try:
                        msg = await asyncio.wait_for(ws.recv(), STOP_POLL_S)
                    except TimeoutError:
                        continue
                    now = time.time()
                    if not self.counting.is_set():
                        continue
                    frame = json.loads(msg)
                    seats = frame["seats"]
                    f.recv_unix.append(now)
                    f.built_unix.append(frame["t_unix"])
                    f.status_unix.append(
                        [s["status_unix"] for s in seats if s["status_unix"] is not None]
                    )
                    f.seats = len(seats)
                    f.bytes += len(msg)
        except Exception as e:  # a dropped grid is a figure, not a crash of the bench
            f.error = f"{type(e).__name__}: {e}"
            self.connected.set()
