"""A worker on a thread of its own, fed through a queue: the core of a Ray actor (whose
methods run on other threads) and, in this process, a transport for in-process tests.

The worker's loop thread still owns every machine: requests are queued to it, never carried
out on the caller's thread.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path

from backend.workers.client import WorkerClient
from backend.workers.protocol import Envelope, Push, Request
from backend.workers.worker import Worker, realtime_priority


class QueueChannel:
    """Requests in through `put`, replies and pushes out through `deliver`."""

    def __init__(self, deliver: Callable[[Push], None]) -> None:
        self.deliver = deliver
        self.closed = False
        self._inbox: deque[Envelope] = deque()
        self._ready = threading.Condition()

    def put(self, req: int, request: Request, sent_mono: float) -> None:
        with self._ready:
            self._inbox.append((req, request, sent_mono))
            self._ready.notify()

    def close(self) -> None:
        with self._ready:
            self.closed = True
            self._ready.notify()

    def wait(self, timeout_s: float) -> bool:
        with self._ready:
            return self._ready.wait_for(lambda: bool(self._inbox) or self.closed, timeout_s)

    def ready(self) -> bool:
        return bool(self._inbox)

    def take(self) -> list[Envelope]:
        with self._ready:
            out = list(self._inbox)
            self._inbox.clear()
        return out

    def send(self, push: Push) -> None:
        self.deliver(push)

    def flush(self) -> None:
        pass  # every push was delivered at once


class ThreadedWorker:
    """A Worker running on its own thread."""

    def __init__(
        self,
        period_s: float,
        ring_dir: Path | None,
        deliver: Callable[[Push], None],
        node: str,
        realtime: bool = False,
    ) -> None:
        self.realtime = realtime  # the loop thread runs ahead of others (a Ray actor's)
        self.channel = QueueChannel(deliver)
        self.worker = Worker(self.channel, period_s, ring_dir, node)
        self.thread = threading.Thread(target=self._run, name="worker-loop", daemon=True)
        self.failed: BaseException | None = None

    def _run(self) -> None:
        if self.realtime:
            realtime_priority()
        try:
            self.worker.run()
        except BaseException as e:  # the owner learns of it: the worker is dead
            self.failed = e
            raise
        finally:
            for host in list(self.worker.hosts.values()):
                host.close()

    def start(self) -> None:
        self.thread.start()

    def stop(self) -> None:
        self.channel.close()
        self.thread.join(timeout=5)


class InProcessWorker(WorkerClient):
    """A worker thread in this process, its rings in files of `ring_dir` (tests)."""

    shared_rings = True

    def __init__(self, wid: str, period_s: float, ring_dir: Path) -> None:
        super().__init__(wid)
        self.core = ThreadedWorker(period_s, ring_dir, self._received, "in-process")

    def _launch(self) -> None:
        self.core.start()

    def _send(self, req: int, request: Request) -> None:
        if not self.core.thread.is_alive():
            raise RuntimeError("the worker thread ended")
        self.core.channel.put(req, request, time.monotonic())

    def stop(self) -> None:
        self._on_death = lambda _c: None
        self.core.stop()
        self.alive = False
