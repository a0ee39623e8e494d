"""The Ray transport: a worker is a Ray actor on a cluster node, reached through Ray calls.

The actor wraps a `ThreadedWorker` (its loop thread owns the machines; their rings live in
the actor's private memory). Requests go to the actor one way (`put`, executed in order on
one actor thread). Everything that comes back, replies included, travels in batches: the
gateway keeps one long poll outstanding per actor, which returns at once when a reply is
waiting and otherwise after `POLL_S` with the news of that time and, per machine, the ring
rows stepped since the last poll (`MachineSamples`), which fill the gateway's copy of the
ring. One path back keeps replies and pushes in the order the worker sent them, and a
command's round trip is one message each way (the poll is already waiting for it).

Only the gateway imports this module, and only when a cluster is configured; the kernel is
imported inside the actor, on its node.

Two ways to join: with the head's GCS address `HOST:PORT` the gateway is a driver on a cluster
node, and the actors import our packages as that node does (its install, plus the gateway's
working directory, which Ray puts on their path). With `ray://HOST:PORT` it is a Ray Client
from anywhere: the driver then runs inside the head's client server, whose path has neither,
so the gateway ships its own packages with the job (`py_modules`) and the actors run exactly
the gateway's code whatever the nodes have installed (they need only the dependencies). The
shipped copy is new to numba's cache: the first actor on a node compiles the kernel (≈10 s).
Everything else is the same in both: actor options, node affinity, `ray.get` with a timeout.
"""

from __future__ import annotations

import os

os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # before ray loads: no usage reports
os.environ.setdefault("RAY_ENABLE_AUTO_CONNECT", "0")  # a call after leaving must not rejoin
# a Ray Client rides out a network blip to the same head this long (Ray's default 30 s); a
# head that restarted is a new cluster: the workers are started afresh on it (backend/
# workers/pool.py tries until it is up), the machines rebuilt from the store
os.environ.setdefault("RAY_CLIENT_RECONNECT_GRACE_PERIOD", "10")

import contextlib
import importlib.util
import logging
import signal
import threading
import time
from collections import deque
from typing import Any

import ray
from ray.exceptions import (
    ActorDiedError,
    ActorUnavailableError,
    GetTimeoutError,
    RayActorError,
    RayError,
)
from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

from backend.workers.client import WorkerClient
from backend.workers.protocol import MachineSamples, Push, Reply, Request
from backend.workers.ring import MAX_WRITE

log = logging.getLogger(__name__)

POLL_S = 0.04  # news and samples in batches of 25 per second (a reply comes back at once)
POLL_TIMEOUT_S = 5.0  # a poll unanswered this much longer makes the actor suspect
SUSPECT_POLLS = 3  # polls in a row an actor may be unavailable before it counts as dead
MAX_BUFFERED = 20_000  # pushes an actor keeps for a gateway that stopped polling
SAMPLE_CHUNKS = 4  # rows per machine and poll: at most this many chunks of MAX_WRITE
START_TIMEOUT_S = 120.0  # the actor's process starts and loads the compiled kernel
NODE_CHARS = 8  # node ids are shown shortened, like Ray's own tools do
CONNECT_TRIES = 3  # joining through a Ray Client server, which may fail to start a client's

_connect_lock = threading.Lock()
_homes: dict[int, str] = {}  # id(RayWorker) -> node id, live workers of this gateway
_joined = 0  # how many times this gateway joined: a lost connection is left once, not a new one


SHIPPED = ("nc_sim", "api", "backend")  # what the actors import: the gateway ships it to a client


def connect(address: str) -> int:
    """Join the cluster as a driver (once, or again after `lost`): `HOST:PORT` is the head's
    GCS address (the gateway runs on a cluster node), `ray://HOST:PORT` a Ray Client server
    (the gateway's packages go with the job). Which joining this is (for `lost`)."""
    global _joined
    with _connect_lock:
        if ray.is_initialized():
            return _joined
        _joined += 1
        runtime_env = shipped_code() if address.startswith("ray://") else None
        # ray.init takes over SIGTERM (sys.exit); the server's own shutdown must keep it
        main = threading.current_thread() is threading.main_thread()
        kept = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT)} if main else {}
        for attempt in range(1, CONNECT_TRIES + 1):
            try:
                ray.init(
                    address=address,
                    runtime_env=runtime_env,
                    log_to_driver=False,
                    logging_level=logging.WARNING,
                )
                break
            except ConnectionAbortedError as e:
                # the Ray Client server could not start this client's own server: it reuses
                # the port of a client that just left, whose server may still be ending (a
                # busy machine); a moment later the port is free
                if attempt == CONNECT_TRIES:
                    raise
                log.warning("joining %s failed (%s): again in %g s", address, e, attempt * 2.0)
                ray.shutdown()
                time.sleep(attempt * 2.0)
        for sig, handler in kept.items():
            signal.signal(sig, handler)
        return _joined


def lost(joined: int) -> None:
    """The connection of that joining is broken (the head went away): leave it, so the next
    `connect` joins afresh. A worker of an older joining finding out late changes nothing."""
    with _connect_lock:
        if joined == _joined and ray.is_initialized():
            with contextlib.suppress(Exception):  # a client whose server is gone
                ray.shutdown()


def shipped_code() -> dict[str, Any]:
    """The job's runtime env for a Ray Client gateway: the gateway's own packages, from
    wherever it imports them (a checkout or an install), without compiled caches."""
    dirs = []
    for name in SHIPPED:
        spec = importlib.util.find_spec(name)  # found, not imported: no kernel in the gateway
        assert spec is not None and spec.submodule_search_locations, name
        dirs.append(next(iter(spec.submodule_search_locations)))
    return {"py_modules": dirs, "excludes": ["__pycache__"]}


LEAVE_WAIT_S = 5.0  # a stopping gateway waits this long for a join in progress to give up


def disconnect() -> None:
    """Leave the cluster (the actors this gateway owns end with it). While a successor is
    still trying to join a head that does not answer (each try takes up to 30 s), the
    service stops without waiting for it: there is nothing to leave."""
    if not _connect_lock.acquire(timeout=LEAVE_WAIT_S):
        log.warning("left the cluster while still joining it (the head does not answer)")
        return
    try:
        if ray.is_initialized():
            ray.shutdown()
    finally:
        _connect_lock.release()


def _choose_node(worker: RayWorker) -> str:
    """The live node running the fewest of this gateway's workers (then by id): exact and
    even, unlike SPREAD, which is best effort."""
    alive: list[str] = sorted(n["NodeID"] for n in ray.nodes() if n["Alive"])  # type: ignore[no-untyped-call]
    if not alive:
        raise RuntimeError("the cluster has no live node")
    with _connect_lock:
        load = {n: 0 for n in alive}
        for node in _homes.values():
            if node in load:
                load[node] += 1
        node = min(alive, key=lambda n: load[n])
        _homes[id(worker)] = node
    return node


def _release(worker: RayWorker) -> None:
    with _connect_lock:
        _homes.pop(id(worker), None)


@ray.remote(  # type: ignore[call-overload]
    num_cpus=0, max_restarts=0, concurrency_groups={"requests": 1, "poll": 1}
)
class WorkerActor:
    """A worker on a cluster node. Ray runs `put` and `poll` on threads of their own."""

    def __init__(self, period_s: float) -> None:
        # the kernel is loaded here, on the node, never in the gateway
        from backend.workers.threaded import ThreadedWorker
        from backend.workers.warmup import warm_up

        warm_up()
        self.node_id: str = ray.get_runtime_context().get_node_id()
        self._pushes: deque[Push] = deque()
        self._replies = 0  # replies among the buffered pushes: a poll returns at once
        self._cond = threading.Condition()
        self.dropped = 0
        self._sent: dict[str, tuple[int, int]] = {}  # machine -> (epoch, newest cycle sent)
        node = self.node_id[:NODE_CHARS]
        self.core = ThreadedWorker(period_s, None, self._deliver, node, realtime=True)
        self.core.start()

    def _deliver(self, push: Push) -> None:
        """The loop thread's replies and pushes, kept until the next poll."""
        with self._cond:
            if len(self._pushes) >= MAX_BUFFERED:  # nobody polls: drop the oldest
                old = self._pushes.popleft()
                self._replies -= isinstance(old, Reply)
                self.dropped += 1
            self._pushes.append(push)
            if isinstance(push, Reply):
                self._replies += 1
                self._cond.notify()

    def describe(self) -> tuple[int, str]:
        """(pid, node id): answered once the kernel is loaded and the loop runs."""
        return os.getpid(), self.node_id

    @ray.method(concurrency_group="requests")
    def put(self, req: int, request: Request) -> None:
        """A request for the loop; its latency counts from here: the gateway's monotonic
        clock means nothing on another host."""
        self.core.channel.put(req, request, time.monotonic())

    @ray.method(concurrency_group="poll")
    def poll(self, wait_s: float) -> list[Push]:
        """The ring rows stepped since the last poll, then every push since (oldest first);
        waits up to `wait_s` unless a reply is there. Samples come first so a machine's
        cycles are in the gateway's ring when the reply to its step arrives."""
        if not self.core.thread.is_alive():
            raise RuntimeError(f"the worker loop ended: {self.core.failed!r}")
        with self._cond:
            self._cond.wait_for(lambda: self._replies > 0, wait_s)
            pushes, self._pushes, self._replies = self._pushes, deque(), 0
        return [*self._samples(), *pushes]

    def _samples(self) -> list[MachineSamples]:
        out: list[MachineSamples] = []
        hosts = list(self.core.worker.hosts.values())  # the loop thread may add or remove
        for host in hosts:
            epoch, sent = self._sent.get(host.id, (host.epoch, 0))
            if epoch != host.epoch:
                sent = 0  # rebuilt: its cycles start again
            try:
                first, rows = host.ring.since(sent + 1, SAMPLE_CHUNKS * MAX_WRITE)
            except IndexError:  # removed meanwhile (its ring was closed)
                continue
            for k in range(0, rows.shape[0], MAX_WRITE):  # the gateway's reader's margin
                out.append(MachineSamples(host.id, host.epoch, first + k, rows[k : k + MAX_WRITE]))
            self._sent[host.id] = (host.epoch, first + rows.shape[0] - 1)
        for mid in set(self._sent) - {h.id for h in hosts}:
            del self._sent[mid]
        return out


class RayWorker(WorkerClient):
    """A worker actor on a cluster node, placed evenly over the live nodes."""

    shared_rings = False

    def __init__(self, wid: str, period_s: float, cluster: str) -> None:
        super().__init__(wid)
        self.period_s = period_s
        self.cluster = cluster
        self.actor: Any = None  # the actor handle
        self._stopping = False
        self._poller: threading.Thread | None = None
        self._joined = 0  # the joining of the cluster its actor belongs to

    def _launch(self) -> None:
        self._joined = connect(self.cluster)
        try:
            node = _choose_node(self)
        except Exception:
            lost(self._joined)  # a connection whose head went away: the next try joins afresh
            raise
        strategy = NodeAffinitySchedulingStrategy(node, soft=False)
        actor = WorkerActor.options(scheduling_strategy=strategy).remote(  # type: ignore[attr-defined]
            self.period_s
        )
        try:
            pid, node_id = ray.get(actor.describe.remote(), timeout=START_TIMEOUT_S)
        except Exception as e:
            _release(self)
            ray.kill(actor)
            raise RuntimeError(f"worker {self.id} did not start on node {node}: {e}") from None
        self.actor, self.pid, self.node = actor, pid, node_id[:NODE_CHARS]
        self._poller = threading.Thread(target=self._poll, name=f"worker-{self.id}-poller")
        self._poller.daemon = True
        self._poller.start()

    def _send(self, req: int, request: Request) -> None:
        self.actor.put.remote(req, request)

    def _poll(self) -> None:
        """Take the actor's pushes in batches until it is gone or stopped."""
        suspect = 0
        why = ""
        broken = False  # the connection to the cluster, not only this actor
        while not self._stopping:
            try:
                batch = ray.get(self.actor.poll.remote(POLL_S), timeout=POLL_S + POLL_TIMEOUT_S)
            except ActorDiedError as e:
                why = f"its actor died ({_first_line(e)})"
                break
            except (ActorUnavailableError, GetTimeoutError) as e:
                suspect += 1  # a node that does not answer may be back soon, or dead
                if suspect < SUSPECT_POLLS:
                    continue
                why = f"its actor did not answer {suspect} polls ({_first_line(e)})"
                break
            except (RayActorError, RayError) as e:  # the loop ended, or an actor error
                why = f"{_first_line(e)}"
                break
            except Exception as e:  # a Ray Client whose head went away: ConnectionError
                why, broken = f"the cluster connection broke ({_first_line(e)})", True
                break
            suspect = 0
            for push in batch:
                self._received(push)
        if self._stopping:
            return
        _release(self)
        if broken:  # its replacement joins afresh (when the head is back)
            lost(self._joined)
        else:
            with contextlib.suppress(Exception):  # a hung or failed actor must not keep running
                ray.kill(self.actor)
        self._died(why)

    def stop(self) -> None:
        self._stopping = True  # an orderly stop is not a death
        self.alive = False
        _release(self)
        if self.actor is not None:
            try:
                ray.kill(self.actor)
            except Exception:
                log.debug("killing worker %s's actor failed", self.id, exc_info=True)
        if self._poller is not None and self._poller is not threading.current_thread():
            self._poller.join(timeout=POLL_S + POLL_TIMEOUT_S)  # before the gateway leaves


def _first_line(e: BaseException) -> str:
    text = str(e).strip().splitlines()
    return f"{type(e).__name__}: {text[0] if text else ''}"
