"""How the gateway reaches a worker: one interface, two transports (local processes, Ray).

A client numbers its requests and matches replies to them; pushes go to the gateway's
handler as they arrive. When the worker is gone every waiting call fails with `WorkerGone`
and the gateway is told once, so it can rebuild the worker's machines elsewhere.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout

from backend.workers.protocol import Failure, Push, Reply, Request

log = logging.getLogger(__name__)

CALL_TIMEOUT_S = 10.0  # a worker that answers nothing for this long is treated as hung


class WorkerGone(RuntimeError):
    """The worker died (or was stopped) before it answered."""


class WorkerRefused(RuntimeError):
    """The worker could not carry out the request (`Failure`)."""

    def __init__(self, failure: Failure) -> None:
        super().__init__(failure.message)
        self.failure = failure


PushHandler = Callable[["WorkerClient", Push], None]
Waiting = Future[object] | asyncio.Future[object]  # a reply's future: a thread's or a loop's
DeathHandler = Callable[["WorkerClient"], None]


class WorkerClient(ABC):
    """One worker as the gateway sees it."""

    shared_rings: bool  # samples are read from shared memory (else pushed: MachineSamples)

    def __init__(self, wid: str) -> None:
        self.id = wid
        self.pid: int | None = None
        self.node = "local"
        self.alive = False
        self.latest: Push | None = None  # the newest WorkerNews
        self.reads_on: asyncio.AbstractEventLoop | None = None  # the loop reading replies, if any
        self._ids = itertools.count(1)
        self._waiting: dict[int, Waiting] = {}
        self._lock = threading.Lock()
        self._on_push: PushHandler = lambda _c, _p: None
        self._on_death: DeathHandler = lambda _c: None

    @property
    def pending_calls(self) -> int:
        """Requests sent and waiting for their reply (a queue that grows: a slow worker)."""
        with self._lock:
            return len(self._waiting)

    def start(self, on_push: PushHandler, on_death: DeathHandler) -> None:
        """Start the worker; pushes and its death are reported to these handlers."""
        self._on_push, self._on_death = on_push, on_death
        self._launch()
        self.alive = True

    def call(self, request: Request, timeout_s: float = CALL_TIMEOUT_S) -> object:
        """Send a request and wait for its reply value; raises WorkerRefused or WorkerGone.
        Not on the loop that reads the replies: the reply could never arrive (use `acall`)."""
        if self.reads_on is not None and _running_loop() is self.reads_on:
            raise RuntimeError("a blocking worker call on the loop reading its reply; use acall")
        fut: Future[object] = Future()
        req = self._submit(request, fut)
        try:
            value = fut.result(timeout_s)
        except FutureTimeout:
            raise self._timed_out(req, timeout_s) from None
        return self._value(value)

    async def acall(self, request: Request, timeout_s: float = CALL_TIMEOUT_S) -> object:
        """`call` for the event loop: the reply resolves a future of this loop (directly when
        the transport reads on this loop), no thread waits for it."""
        fut: asyncio.Future[object] = asyncio.get_running_loop().create_future()
        req = self._submit(request, fut)
        try:
            value = await asyncio.wait_for(fut, timeout_s)
        except TimeoutError:
            raise self._timed_out(req, timeout_s) from None
        return self._value(value)

    def _submit(self, request: Request, fut: Waiting) -> int:
        """Register the reply's future and send the request."""
        with self._lock:
            if not self.alive:
                raise WorkerGone(f"worker {self.id} is not running")
            req = next(self._ids)
            self._waiting[req] = fut
        try:
            self._send(req, request)
        except Exception as e:
            with self._lock:
                self._waiting.pop(req, None)
            self._died(f"send failed: {e}")
            raise WorkerGone(f"worker {self.id}: {e}") from None
        return req

    def _timed_out(self, req: int, timeout_s: float) -> WorkerGone:
        with self._lock:
            self._waiting.pop(req, None)
        return WorkerGone(f"worker {self.id} did not answer within {timeout_s:g} s")

    @staticmethod
    def _value(value: object) -> object:
        if isinstance(value, Failure):
            raise WorkerRefused(value)
        return value

    def post(self, request: Request) -> None:
        """Send a request without waiting for its reply (the reply is dropped)."""
        if not self.alive:
            return
        try:
            self._send(next(self._ids), request)
        except Exception as e:
            self._died(f"send failed: {e}")

    def _received(self, push: Push) -> None:
        """A message from the worker (the transport's reader calls this)."""
        if isinstance(push, Reply):
            with self._lock:
                fut = self._waiting.pop(push.req, None)
            if fut is not None:
                _settle(fut, push.value, None)
            return
        try:
            self._on_push(self, push)
        except Exception:
            log.exception("handling a push from worker %s failed", self.id)

    def _died(self, why: str) -> None:
        """Fail every waiting call and tell the gateway, once."""
        with self._lock:
            if not self.alive:
                return
            self.alive = False
            waiting, self._waiting = self._waiting, {}
        log.warning("worker %s (pid %s) is gone: %s", self.id, self.pid, why)
        for fut in waiting.values():
            _settle(fut, None, WorkerGone(f"worker {self.id} is gone: {why}"))
        self._on_death(self)

    @abstractmethod
    def _launch(self) -> None:
        """Start the worker and whatever reads its messages."""

    @abstractmethod
    def _send(self, req: int, request: Request) -> None: ...

    @abstractmethod
    def stop(self) -> None:
        """End the worker (its machines end with it); no death is reported."""


def _running_loop() -> asyncio.AbstractEventLoop | None:
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def _settle(fut: Waiting, value: object, error: BaseException | None) -> None:
    """Resolve a reply's future from whichever thread read the reply."""
    if isinstance(fut, Future):
        if error is None:
            fut.set_result(value)
        else:
            fut.set_exception(error)
        return
    loop = fut.get_loop()
    if _running_loop() is loop:
        _set(fut, value, error)
    else:
        with contextlib.suppress(RuntimeError):  # that loop is closed: nobody waits
            loop.call_soon_threadsafe(_set, fut, value, error)


def _set(fut: asyncio.Future[object], value: object, error: BaseException | None) -> None:
    if fut.done():  # timed out meanwhile
        return
    if error is None:
        fut.set_result(value)
    else:
        fut.set_exception(error)
