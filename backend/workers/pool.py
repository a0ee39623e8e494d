"""The gateway's workers: started together, chosen by load, replaced when one dies.

Locally a worker is a process (one per core by default); with a cluster address they are Ray
actors spread over the cluster's nodes. The rest of the gateway sees only `WorkerClient`.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import os
import shutil
import threading
import time
import uuid
from collections.abc import Callable, Sized
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from backend.workers.client import DeathHandler, PushHandler, WorkerClient
from backend.workers.local import LocalWorker
from backend.workers.ring import shm_dir

log = logging.getLogger(__name__)

Factory = Callable[[str, float, Path], WorkerClient]  # (id, loop period, ring folder)
REPLACEMENT_WAIT_S = 10.0  # a dead worker's machines wait this long at most for its successor
# waits between tries to start a successor that failed to start (a Ray head restarting takes
# seconds to a minute): tried again until it runs or the service stops
RETRY_S = (1.0, 2.0, 4.0, 8.0, 15.0, 30.0)


def default_count() -> int:
    """One worker per core this process may use, at least one."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def remove_stale_rings(base: Path) -> None:
    """Remove the ring folders of gateways that are gone (killed before they could clean up:
    the folder is named after the gateway's pid)."""
    for d in base.glob("inbetrieb-*-*"):
        try:
            pid = int(d.name.split("-")[1])
            os.kill(pid, 0)  # raises when no such process
        except ProcessLookupError:
            shutil.rmtree(d, ignore_errors=True)
        except (ValueError, PermissionError):
            continue  # not ours, or another user's live gateway


class NoLiveWorker(RuntimeError):
    """Every worker is gone and none has started in their place yet."""


class WorkerPool:
    """Starts, chooses and replaces workers."""

    def __init__(
        self,
        count: int,
        period_s: float,
        cluster: str | None = None,
        factory: Factory | None = None,
        loop: asyncio.AbstractEventLoop | None = None,
    ) -> None:
        self.count = count or default_count()
        self.loop = loop  # where local workers' messages are read (the gateway's loop)
        self.period_s = period_s
        self.cluster = cluster
        self.factory = factory  # how a worker is made when neither local nor Ray (tests)
        self.workers: list[WorkerClient] = []
        self.ring_dir = shm_dir() / f"inbetrieb-{os.getpid()}-{uuid.uuid4().hex[:6]}"
        self._serial = 0
        self._lock = threading.Lock()
        self._on_push: PushHandler = lambda _c, _p: None
        self._on_death: DeathHandler = lambda _c: None
        self.replaced = 0
        self._replacing: list[threading.Thread] = []  # replacements being started
        self._stopping = False
        self._stopped = threading.Event()  # ends a replacement's wait before its next try
        self._joined = threading.Condition()  # told when a worker joins (or the pool stops)

    @property
    def stopping(self) -> bool:
        """The service stops: a worker lost now is not replaced, its machines not rebuilt."""
        return self._stopping

    @property
    def _on_cluster(self) -> bool:
        return self.factory is None and self.cluster is not None

    def _new(self) -> WorkerClient:
        with self._lock:
            self._serial += 1
            wid = f"w{self._serial}"
        if self.factory is not None:
            return self.factory(wid, self.period_s, self.ring_dir)
        if self.cluster is not None:
            from backend.workers.ray_transport import RayWorker  # only with a cluster

            return RayWorker(wid, self.period_s, self.cluster)
        return LocalWorker(wid, self.period_s, self.ring_dir, self.loop)

    def start(self, on_push: PushHandler, on_death: DeathHandler) -> None:
        """Start every worker (in parallel: each loads the compiled kernel)."""
        self._on_push, self._on_death = on_push, on_death
        remove_stale_rings(self.ring_dir.parent)
        self.ring_dir.mkdir(parents=True, exist_ok=True)
        if self._on_cluster:
            from backend.workers.ray_transport import connect

            connect(self.cluster)  # type: ignore[arg-type]  # once, before the actors
        fresh = [self._new() for _ in range(self.count)]
        with ThreadPoolExecutor(len(fresh)) as ex:
            list(ex.map(lambda w: w.start(on_push, on_death), fresh))
        with self._lock:
            self.workers += fresh

    def alive(self) -> list[WorkerClient]:
        with self._lock:
            return [w for w in self.workers if w.alive]

    def choose(self, machines_on: Callable[[WorkerClient], Sized]) -> WorkerClient:
        """The live worker running the fewest machines."""
        live = self.alive()
        if not live:
            raise NoLiveWorker("no worker is running (one is being started): try again shortly")
        return min(live, key=lambda w: len(machines_on(w)))

    def replace(self, dead: WorkerClient) -> None:
        """Start a worker in place of a dead one and wait until it runs, at most
        REPLACEMENT_WAIT_S (a local one takes a second or two): the dead one's machines are
        rebuilt after it, spread by load over it and the others, so the survivors do not end
        up with all of them. One that takes longer (a Ray actor waiting for a node) joins
        when it is up; the machines do not wait for it."""
        self.replaced += 1
        up = threading.Event()

        def start() -> None:
            for attempt in itertools.count():
                w = self._new()
                try:
                    w.start(self._on_push, self._on_death)
                    break
                except BaseException as e:  # Ray ends a call with SystemExit when it shuts down
                    if self._stopping:
                        return
                    wait_s = RETRY_S[min(attempt, len(RETRY_S) - 1)]
                    log.warning(
                        "the successor of worker %s did not start (%s): again in %g s",
                        dead.id,
                        str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__,
                        wait_s,
                    )
                    if self._stopped.wait(wait_s):
                        return
            if self._stopping:  # came up while the service stops: it goes too
                w.stop()
                return
            with self._lock:
                self.workers = [x for x in self.workers if x is not dead] + [w]
            up.set()
            with self._joined:
                self._joined.notify_all()

        if not self.alive():
            start()  # nothing left to rebuild on: wait for the new one
            return
        t = threading.Thread(target=start, name="worker-replace", daemon=True)
        self._replacing = [r for r in self._replacing if r.is_alive()] + [t]
        t.start()
        up.wait(REPLACEMENT_WAIT_S)

    def wait_for_live(self) -> bool:
        """Wait until a worker runs (True) or the pool stops (False)."""
        with self._joined:
            self._joined.wait_for(lambda: bool(self.alive()) or self._stopping)
        return not self._stopping

    def stop(self) -> None:
        self._stopping = True  # a replacement starting now stops once it is up
        self._stopped.set()
        with self._joined:
            self._joined.notify_all()
        for w in self.workers:
            try:
                w.stop()
            except Exception:
                log.exception("stopping worker %s failed", w.id)
        shutil.rmtree(self.ring_dir, ignore_errors=True)
        if self._on_cluster:
            from backend.workers.ray_transport import disconnect

            disconnect()
        deadline = time.monotonic() + REPLACEMENT_WAIT_S
        for t in self._replacing:  # none outlives the pool (one joining an absent head may)
            t.join(timeout=max(0.0, deadline - time.monotonic()))
