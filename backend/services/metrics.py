"""The service's figures for Prometheus (`GET /metrics`, text exposition format): machines by
pacing, each worker's loop (alive, overruns, missed deadlines, work p99, CPU, calls waiting for
its reply), telemetry clients and frames, the instructor consoles, classes and seats, the
audit's write queue, and a histogram of command latency (a request's arrival to the
worker's answer). The gauges and counters are read from the services when Prometheus asks;
only the command latency is kept here. One registry per service (no global state: a test
runs several)."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from prometheus_client import CollectorRegistry, Histogram, disable_created_metrics, generate_latest
from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily, InfoMetricFamily
from prometheus_client.metrics_core import Metric
from prometheus_client.registry import Collector

from backend import VERSION
from backend.logs import request_arrived
from backend.services.audit import Audit
from backend.services.console import ConsoleHub
from backend.services.machines import MachineService
from backend.services.status import worker_statuses
from backend.services.telemetry import TelemetryHub

disable_created_metrics()  # type: ignore[no-untyped-call]  # `_created`: nothing a scrape needs
# a command's answer comes within a cycle or a few (1 ms) on a loaded worker: ms to a second,
# fine where most commands are
LATENCY_BUCKETS_S = (
    0.0005, 0.001, 0.0015, 0.002, 0.003, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03, 0.05, 0.1,
    0.2, 0.5, 1.0, 2.0, 5.0,
)  # fmt: skip


class Metrics:
    """The registry of one service and its command latency histogram."""

    def __init__(self) -> None:
        self.registry = CollectorRegistry(auto_describe=False)
        self.command_latency = Histogram(
            "inbetrieb_command_latency_seconds",
            "Time from a command's request to its worker's answer, by command type",
            ["type"],
            buckets=LATENCY_BUCKETS_S,
            registry=self.registry,
        )

    def observe_command(self, kind: str) -> Callable[[], None]:
        """Time a command of this type from its request's arrival (what a client waits,
        less the network); call the result when it is answered."""
        t0 = request_arrived()
        return lambda: self.command_latency.labels(kind).observe(time.perf_counter() - t0)

    def attach(self, sources: Sources) -> None:
        """Read these services' figures at each scrape."""
        self.registry.register(_ServiceCollector(sources))

    def render(self) -> bytes:
        return generate_latest(self.registry)


@dataclass(frozen=True)
class Sources:
    """What the figures are read from."""

    transport: str  # local | ray
    started: float  # Unix time
    machines: MachineService
    hub: TelemetryHub
    console: ConsoleHub
    audit: Audit


class _ServiceCollector(Collector):
    def __init__(self, sources: Sources) -> None:
        self.s = sources

    def collect(self) -> Iterator[Metric]:
        s = self.s
        info = InfoMetricFamily("inbetrieb", "The service's version and worker transport")
        info.add_metric([], {"version": VERSION, "transport": s.transport})
        yield info
        yield GaugeMetricFamily(
            "inbetrieb_uptime_seconds", "Since the service started", value=time.time() - s.started
        )
        yield from self._machines()
        yield from self._workers()
        yield from self._telemetry()
        yield from self._training()
        yield GaugeMetricFamily(
            "inbetrieb_audit_queue_depth",
            "Audit entries waiting for the writer",
            value=s.audit.queue_depth(),
        )

    def _machines(self) -> Iterator[Metric]:
        by_mode: dict[str, int] = {"run": 0, "pause": 0, "fast": 0, "building": 0}
        for m in self.s.machines.proxies():
            p = m.link.pacing
            by_mode["building" if p is None else p.mode] += 1
        g = GaugeMetricFamily("inbetrieb_machines", "Machines by pacing", labels=["mode"])
        for mode, n in by_mode.items():
            g.add_metric([mode], n)
        yield g
        yield CounterMetricFamily(
            "inbetrieb_machines_rebuilt",
            "Machines rebuilt after their worker died",
            value=self.s.machines.rebuilt,
        )

    def _workers(self) -> Iterator[Metric]:
        labels = ["worker", "node"]
        up = GaugeMetricFamily("inbetrieb_worker_up", "1 while the worker runs", labels=labels)
        machines = GaugeMetricFamily(
            "inbetrieb_worker_machines", "Machines on the worker", labels=labels
        )
        overruns = CounterMetricFamily(
            "inbetrieb_worker_overruns", "Loop ticks that ran past their deadline", labels=labels
        )
        missed = CounterMetricFamily(
            "inbetrieb_worker_missed_deadlines", "Deadlines skipped after overruns", labels=labels
        )
        work = GaugeMetricFamily(
            "inbetrieb_worker_work_p99_seconds",
            "Loop work per tick, 99th percentile",
            labels=labels,
        )
        cpu = GaugeMetricFamily(
            "inbetrieb_worker_cpu_percent", "CPU of the worker, % of one core", labels=labels
        )
        pending = GaugeMetricFamily(
            "inbetrieb_worker_pending_calls",
            "Requests waiting for the worker's reply",
            labels=labels,
        )
        waiting = {w.id: w.pending_calls for w in self.s.machines.pool.workers}
        for w in worker_statuses(self.s.machines):
            key = [w.id, w.node]
            up.add_metric(key, 1 if w.alive else 0)
            machines.add_metric(key, len(w.machines))
            pending.add_metric(key, waiting.get(w.id, 0))
            loop = w.loop
            if loop is not None:
                overruns.add_metric(key, loop.overruns)
                missed.add_metric(key, loop.missed_deadlines)
                work.add_metric(key, loop.work_p99_ms / 1000.0)
                cpu.add_metric(key, loop.cpu_pct)
        yield from (up, machines, overruns, missed, work, cpu, pending)
        yield CounterMetricFamily(
            "inbetrieb_workers_replaced",
            "Workers started again",
            value=self.s.machines.pool.replaced,
        )

    def _telemetry(self) -> Iterator[Metric]:
        hub = self.s.hub
        st = hub.status()
        yield GaugeMetricFamily(
            "inbetrieb_telemetry_clients", "Telemetry websockets open", value=len(hub.subscribers)
        )
        yield CounterMetricFamily(
            "inbetrieb_telemetry_frames_sent", "Telemetry frames sent", value=st.frames_sent
        )
        yield CounterMetricFamily(
            "inbetrieb_telemetry_clients_dropped",
            "Telemetry clients disconnected (not reading, flooding, failures)",
            value=st.clients_dropped,
        )

    def _training(self) -> Iterator[Metric]:
        running = [c for c in self.s.console.classes.all() if c.ended_unix is None]
        yield GaugeMetricFamily("inbetrieb_classes_running", "Classes running", value=len(running))
        yield GaugeMetricFamily(
            "inbetrieb_seats",
            "Seats of the running classes",
            value=sum(len(c.seats) for c in running),
        )
        yield GaugeMetricFamily(
            "inbetrieb_consoles", "Instructor consoles open", value=len(self.s.console.consoles)
        )
