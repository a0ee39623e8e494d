"""How the gateway reaches a worker: one interface, two transports (local processes, Ray).

A client numbers its requests and matches replies to them; pushes go to the gateway's
handler as they arrive. When the worker is gone every waiting call fails with `WorkerGone`
and the gateway is told once, so it can rebuild the worker's machines elsewhere.
"""

from __future__ import annotations

import asyncio
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
        self._ids = itertools.count(1)
        self._waiting: dict[int, Future[object]] = {}
        self._lock = threading.Lock()
        self._on_push: PushHandler = lambda _c, _p: None
        self._on_death: DeathHandler = lambda _c: None

    def start(self, on_push: PushHandler, on_death: DeathHandler) -> None:
        """Start the worker; pushes and its death are reported to these handlers."""
        self._on_push, self._on_death = on_push, on_death
        self._launch()
        self.alive = True

    def call(self, request: Request, timeout_s: float = CALL_TIMEOUT_S) -> object:
        """Send a request and wait for its reply value; raises WorkerRefused or WorkerGone."""
        fut = self._submit(request)
        try:
            value = fut.result(timeout_s)
        except FutureTimeout:
            raise self._timed_out(fut, timeout_s) from None
        return self._value(value)

    async def acall(self, request: Request, timeout_s: float = CALL_TIMEOUT_S) -> object:
        """`call` for the event loop: the reply wakes the loop, no thread waits for it."""
        fut = self._submit(request)
        try:
            value = await asyncio.wait_for(asyncio.wrap_future(fut), timeout_s)
        except TimeoutError:
            raise self._timed_out(fut, timeout_s) from None
        return self._value(value)

    def _submit(self, request: Request) -> Future[object]:
        """Register a reply and send the request."""
        fut: Future[object] = Future()
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
        return fut

    def _timed_out(self, fut: Future[object], timeout_s: float) -> WorkerGone:
        with self._lock:
            for req, waiting in list(self._waiting.items()):
                if waiting is fut:
                    del self._waiting[req]
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
                fut.set_result(push.value)
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
            fut.set_exception(WorkerGone(f"worker {self.id} is gone: {why}"))
        self._on_death(self)

    @abstractmethod
    def _launch(self) -> None:
        """Start the worker and whatever reads its messages."""

    @abstractmethod
    def _send(self, req: int, request: Request) -> None: ...

    @abstractmethod
    def stop(self) -> None:
        """End the worker (its machines end with it); no death is reported."""
