"""The local transport: a worker is a process on this server, reached through a pipe; its
sample rings are files in shared memory that the gateway maps.

The process is started with "spawn" (a fresh interpreter: the gateway's threads and sockets
are not copied into it) and dies with the gateway: the pipe closes when the gateway ends,
however it ends, and a worker whose pipe closes stops.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing as mp
import os
import threading
import time
from multiprocessing.connection import Connection
from pathlib import Path

from backend.workers.client import WorkerClient
from backend.workers.protocol import Envelope, Push, Request

log = logging.getLogger(__name__)

WORKER_NICE = -10  # the fallback when real-time scheduling is not allowed
WORKER_RT_PRIORITY = 10  # SCHED_FIFO priority (1 lowest, 99 highest) of a worker's loop
MAX_TAKE = 256  # requests one `take` returns at most: the loop keeps its deadlines in a flood


class PipeChannel:
    """A worker's end of the pipe."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.closed = False

    def wait(self, timeout_s: float) -> bool:
        try:
            return self.conn.poll(timeout_s)
        except (EOFError, OSError):
            self.closed = True
            return True  # `take` ends the worker

    def ready(self) -> bool:
        return self.wait(0)

    def take(self) -> list[Envelope]:
        out: list[Envelope] = []
        try:
            while len(out) < MAX_TAKE and self.conn.poll(0):
                out.append(self.conn.recv())
        except (EOFError, OSError):
            self.closed = True
        return out

    def send(self, push: Push) -> None:
        self.conn.send(push)


def realtime_priority() -> str:
    """Run this process ahead of the gateway and the clients: SCHED_FIFO where allowed (root
    or CAP_SYS_NICE; the loop sleeps to every deadline, and Linux keeps 5 % of each second
    for other tasks, so a worker cannot lock a core up), else nice -10, else as it is."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(WORKER_RT_PRIORITY))
        return "fifo"
    except (OSError, AttributeError):
        pass
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, WORKER_NICE)
        return "nice"
    return "normal"


def worker_main(conn: Connection, period_s: float, ring_dir: str, node: str) -> None:
    """The worker process: load the compiled kernel, then pace until the gateway goes."""
    # imported here: the gateway process never loads the kernel
    from backend.workers.warmup import warm_up
    from backend.workers.worker import Worker

    logging.basicConfig(level=logging.WARNING, format="worker %(process)d: %(message)s")
    realtime_priority()
    warm_up()
    channel = PipeChannel(conn)
    worker = Worker(channel, period_s, Path(ring_dir), node)
    conn.send(("ready",))
    try:
        worker.run()
    finally:
        for host in list(worker.hosts.values()):
            host.close()


class LocalWorker(WorkerClient):
    """A worker process on this server."""

    shared_rings = True

    def __init__(self, wid: str, period_s: float, ring_dir: Path, start_timeout_s: float = 60.0):
        super().__init__(wid)
        self.period_s = period_s
        self.ring_dir = ring_dir
        self.start_timeout_s = start_timeout_s
        self._conn: Connection | None = None
        self._proc: mp.process.BaseProcess | None = None
        self._send_lock = threading.Lock()
        self._stopping = False

    def _launch(self) -> None:
        ctx = mp.get_context("spawn")
        ours, theirs = ctx.Pipe(duplex=True)
        proc = ctx.Process(
            target=worker_main,
            args=(theirs, self.period_s, str(self.ring_dir), "local"),
            name=f"inbetrieb-worker-{self.id}",
            daemon=True,
        )
        proc.start()
        theirs.close()
        if not ours.poll(self.start_timeout_s):
            proc.kill()
            raise RuntimeError(f"worker {self.id} did not start")
        ours.recv()  # ("ready",)
        self._conn, self._proc, self.pid = ours, proc, proc.pid
        threading.Thread(target=self._read, name=f"worker-{self.id}-reader", daemon=True).start()

    def _read(self) -> None:
        conn = self._conn
        assert conn is not None
        while not self._stopping:
            try:
                push = conn.recv()
            except (EOFError, OSError):
                break
            except Exception:  # a message we cannot unpickle: a bug, not a dead worker
                if self._stopping:
                    break
                log.exception("worker %s sent an unreadable message", self.id)
                continue
            self._received(push)
        if not self._stopping:
            self._died("its pipe closed (the process ended)")

    def _send(self, req: int, request: Request) -> None:
        assert self._conn is not None
        with self._send_lock:
            self._conn.send((req, request, time.monotonic()))

    def stop(self) -> None:
        self._stopping = True  # an orderly stop is not a death
        self.alive = False
        if self._conn is not None:
            self._conn.close()
        if self._proc is not None:
            self._proc.join(timeout=5)
            if self._proc.is_alive():
                self._proc.kill()
                self._proc.join(timeout=5)
