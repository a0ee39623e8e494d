"""The local transport: a worker is a process on this server, reached through a socket pair; its
sample rings are files in shared memory that the gateway maps.

The process is forked from the worker zygote (backend/workers/zygote.py: a process with the
kernel loaded, none of the gateway's threads or sockets) and dies with the gateway: the socket
closes when the gateway ends, however it ends, and a worker whose socket closes stops.
"""

from __future__ import annotations

import asyncio
import logging
import os
import select
import signal
import socket
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from pathlib import Path

from backend.workers import zygote
from backend.workers.client import WorkerClient
from backend.workers.protocol import Envelope, Push, Reply, Request
from backend.workers.wire import Wire

log = logging.getLogger(__name__)

MAX_TAKE = 256  # requests one `take` returns at most: the loop keeps its deadlines in a flood


class WireChannel:
    """A worker's end of the socket pair: pushes of a tick go out in one write at its end,
    replies at once."""

    def __init__(self, wire: Wire) -> None:
        self.wire = wire

    @property
    def closed(self) -> bool:
        return self.wire.closed

    def wait(self, timeout_s: float) -> bool:
        return self.wire.wait(timeout_s)

    def ready(self) -> bool:
        return self.wire.pending()

    def take(self) -> list[Envelope]:
        return self.wire.take(MAX_TAKE)  # type: ignore[return-value]

    def send(self, push: Push) -> None:
        if isinstance(push, Reply):
            self.wire.send(push)
        else:
            self.wire.queue(push)

    def flush(self) -> None:
        self.wire.flush()


def worker_main(sock: socket.socket, period_s: float, ring_dir: str, node: str) -> None:
    """The worker process (forked from the zygote, the kernel loaded): pace until the
    gateway goes."""
    # imported here: the gateway process never loads the kernel
    from backend.logs import configure_worker
    from backend.workers.worker import Worker, realtime_priority

    configure_worker()
    # Ctrl-C reaches the whole process group, systemd's stop the whole unit: the gateway
    # stops its workers in order (its socket closing ends this one), so they wait for it
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    realtime_priority()
    wire = Wire(sock, write_behind=True)
    worker = Worker(WireChannel(wire), period_s, Path(ring_dir), node)
    wire.send(("ready",))
    try:
        worker.run()
    except (BrokenPipeError, ConnectionResetError):
        pass  # the gateway went away (stopped or killed): nobody is left to tell
    finally:
        for host in list(worker.hosts.values()):
            host.close()


class LocalWorker(WorkerClient):
    """A worker process on this server."""

    shared_rings = True

    def __init__(
        self,
        wid: str,
        period_s: float,
        ring_dir: Path,
        loop: asyncio.AbstractEventLoop | None = None,
        start_timeout_s: float = 60.0,
    ):
        super().__init__(wid)
        self.period_s = period_s
        self.ring_dir = ring_dir
        self.reads_on = loop  # reads the replies and pushes (else a loop of ours)
        self.start_timeout_s = start_timeout_s
        self._wire: Wire | None = None
        self._fd = -1
        self._pidfd = -1  # the worker process: readable once it ended
        self._pidfd_lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._stopping = False

    def _launch(self) -> None:
        ours, theirs = socket.socketpair()
        args = (self.period_s, str(self.ring_dir), "local")
        try:
            pid = zygote.fork_worker(worker_main, theirs, args, self.start_timeout_s)
            self._pidfd = os.pidfd_open(pid)
        except (zygote.ZygoteGone, ProcessLookupError) as e:
            ours.close()
            raise RuntimeError(f"worker {self.id} did not start: {e}") from e
        finally:
            theirs.close()
        wire = Wire(ours)
        if not wire.wait(self.start_timeout_s) or wire.closed:
            self._end(0)
            ours.close()
            raise RuntimeError(f"worker {self.id} did not start")
        wire.take(1)  # ("ready",)
        self._wire, self.pid, self._fd = wire, pid, ours.fileno()
        loop = self.reads_on = self.reads_on or reader_loop()
        on_loop(loop, lambda: loop.add_reader(self._fd, self._readable))

    def _readable(self) -> None:
        """On the loop: everything that arrived, handled at once (no thread hand-over)."""
        wire = self._wire
        assert wire is not None
        for push in wire.take():
            self._received(push)  # type: ignore[arg-type]
        if wire.closed:
            self._close()
            if not self._stopping:
                self._end(None)  # a dead worker is not stopped: its pidfd is closed here
                self._died("its socket closed (the process ended)")

    def _close(self) -> None:
        """On the loop: stop reading, close the socket."""
        assert self.reads_on is not None and self._wire is not None
        self.reads_on.remove_reader(self._fd)
        self._wire.shut()

    def _send(self, req: int, request: Request) -> None:
        assert self._wire is not None
        with self._send_lock:
            self._wire.send((req, request, time.monotonic()))

    def stop(self) -> None:
        self._stopping = True  # an orderly stop is not a death
        self.alive = False
        if self._wire is not None and self.reads_on is not None:
            on_loop(self.reads_on, self._close)
        self._end(5)

    def _end(self, wait_s: float | None) -> None:
        """Wait `wait_s` for the process to end, then kill it (None: it ended); forget it."""
        with self._pidfd_lock:
            if self._pidfd < 0:
                return
            if wait_s is not None and not select.select([self._pidfd], [], [], wait_s)[0]:
                signal.pidfd_send_signal(self._pidfd, signal.SIGKILL)
                select.select([self._pidfd], [], [], 5)
            os.close(self._pidfd)
            self._pidfd = -1


_readers: asyncio.AbstractEventLoop | None = None
_readers_lock = threading.Lock()


def reader_loop() -> asyncio.AbstractEventLoop:
    """An event loop on a thread of its own, reading the workers of a process that runs
    none (tests, scripts); a gateway passes its own loop instead."""
    global _readers
    with _readers_lock:
        if _readers is None:
            loop = asyncio.new_event_loop()
            threading.Thread(target=loop.run_forever, name="worker-readers", daemon=True).start()
            _readers = loop
        return _readers


def on_loop(loop: asyncio.AbstractEventLoop, fn: Callable[[], object]) -> None:
    """Run `fn` on `loop` and wait for it (at once when this is the loop's thread, or when
    the loop runs no more)."""
    try:
        running = asyncio.get_running_loop()
    except RuntimeError:
        running = None
    if running is loop or not loop.is_running():
        fn()
        return
    done: Future[object] = Future()

    def run() -> None:
        try:
            done.set_result(fn())
        except BaseException as e:
            done.set_exception(e)

    loop.call_soon_threadsafe(run)
    done.result(timeout=10)
