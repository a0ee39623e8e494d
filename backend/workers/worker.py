"""A worker: owns its machines and their time, in one thread.

The loop sleeps to absolute deadlines `t0 + i·period`; while it waits it serves requests as
they arrive (a command acts in the cycle after the one being stepped, never a period later);
at each deadline it steps every machine's due cycles into its sample ring, looking for new
requests between machines so an emergency stop never waits behind the others. Then it pushes
what changed: new events and completed captures of every machine, the status of the watched
ones (staggered over the status period), and about once a second its loop figures. While
no machine is due to step (all paused, or none held) the loop sleeps until a request comes.

Nothing else runs here: no HTTP, no JSON, no SQLite. A channel (a local pipe, or a queue in
a Ray actor) brings requests and takes replies and pushes.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import time
from collections import deque
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Protocol

import numpy as np

from backend.workers.host import MachineHost
from backend.workers.interpreting import (
    INTERPRET_SHARE,
    SLICE_S,
    Interpreting,
    Pending,
    interpretation_needed,
)
from backend.workers.protocol import (
    AddMachine,
    ApplyValues,
    AssistCancel,
    AssistStart,
    Envelope,
    Failure,
    InjectFault,
    LoopFigures,
    MachineNews,
    Pace,
    Push,
    ReadServiceAxes,
    ReadStatus,
    RemoveFault,
    RemoveMachine,
    Reply,
    Request,
    Roll,
    ScopeAct,
    ScopeArm,
    ScopeRoll,
    ScopeState,
    Step,
    Submit,
    Submitted,
    TakeSnapshot,
    Values,
    Watch,
    WorkerNews,
)
from backend.workers.training import training_request
from nc_sim.commands import Accepted, EmergencyStop, JogStart, JogStop
from nc_sim.config import apply_values
from nc_sim.errors import NcUsageError

log = logging.getLogger(__name__)

STATUS_PERIOD_S = 0.05  # watched machines' status: 20 per second, like a display refresh
CLASS_STATUS_PERIOD_S = 0.1  # 10 per second once a worker holds a class of machines
NEWS_PERIOD_S = 1.0  # loop figures and every machine's pacing
SERVE_CHECK_S = 0.0002  # a tick looks for requests this often (a look is a system call)
WORKER_NICE = -10  # the fallback when real-time scheduling is not allowed
WORKER_RT_PRIORITY = 10  # SCHED_FIFO priority (1 lowest, 99 highest) of a worker's loop
MAX_SERVE = 64  # requests carried out at a time before the loop looks at its deadline
MAX_PERIOD_S = 0.01  # the longest loop period (telemetry waits at most this for samples)
# while every machine rests (nothing commanded to move) the loop ticks at MAX_PERIOD_S: a
# resting machine's tick costs as much Python as a moving one's, and at rest its samples
# need not arrive every 2 ms. A request wakes the loop at once (it steps with it now).
MACHINES_PER_PERIOD = 4  # machines per base period before the period grows
CLASS_MACHINES = 16  # a worker holding more runs a class: statuses at CLASS_STATUS_PERIOD_S


class Channel(Protocol):
    """Where requests come from and replies and pushes go."""

    @property
    def closed(self) -> bool:
        """The gateway went away: the worker stops."""

    def wait(self, timeout_s: float) -> bool:
        """Block until a request is there or the timeout passed; true when one is there."""

    def ready(self) -> bool:
        """A request is there (without blocking)."""

    def take(self) -> list[Envelope]:
        """Every request there now, oldest first."""

    def send(self, push: Push) -> None:
        """A reply goes at once; a push may wait for `flush`."""

    def flush(self) -> None:
        """Send the pushes held back (the loop calls this at the end of every tick)."""


class Worker:
    """The machines of one worker and the real-time loop that paces them."""

    def __init__(
        self,
        channel: Channel,
        period_s: float,
        ring_dir: Path | None,
        node: str = "local",
        fast_share: float = 0.4,
    ) -> None:
        self.channel = channel
        self.base_period_s = period_s
        self.fast_share = fast_share  # of a period, for machines running "as fast as possible"
        self.ring_dir = ring_dir
        self.node = node
        self.hosts: dict[str, MachineHost] = {}
        self.steps: list[tuple[int, str]] = []  # (request, machine) answered when its step ends
        self.assists: list[tuple[int, MachineHost]] = []  # live runs, answered when they end
        self.backlog: deque[Envelope] = deque()  # taken from the channel, not yet carried out
        self.interpreting = Interpreting()  # programs interpreted in the loop's spare time
        self.stopped = False
        self.news_due = False  # pacing changed: report at the end of this tick
        self.awake_until = 0.0  # an idle loop served a request: it ticks until then
        self.resting = False  # every machine rested after the last tick (the long period)
        # loop figures, read only by this thread
        self.ticks = self.overruns = self.missed = self.host_failures = 0
        self.status_budget = 0  # statuses this tick may still build
        self.work_s: deque[float] = deque(maxlen=5000)  # per tick: stepping and serving
        self.served_s = 0.0  # serving since the last tick
        self.late_s: deque[float] = deque(maxlen=5000)
        self.recent: deque[tuple[float, float, float]] = deque(maxlen=20)
        self._cpu = (time.monotonic(), time.process_time())
        self._cpu_pct = 0.0

    # --- the loop ---------------------------------------------------------------------------
    def run(self) -> None:
        """Pace until stopped (the gateway closing the channel stops it too)."""
        deadline = time.monotonic()
        next_news = deadline + NEWS_PERIOD_S
        while not (self.stopped or self.channel.closed):
            period = self.period()
            if self.idle():  # nothing to step: sleep until a request or the next news
                remaining = next_news - time.monotonic()
                if remaining > 0 and self.channel.wait(remaining):
                    self._serve_timed()
                    # awake for a status period: what the request changed goes out as usual
                    self.awake_until = time.monotonic() + self.status_period()
                deadline = time.monotonic() - period  # then a pass now
            deadline += period
            interpret_until = deadline - period * (1.0 - INTERPRET_SHARE)
            while (remaining := deadline - time.monotonic()) > 0 and not self.channel.closed:
                if (
                    self.interpreting.working()
                    and time.monotonic() < interpret_until
                    and not (self.backlog or self.channel.ready())
                ):  # a program in the spare time, in slices: a request never waits long
                    self.interpreting.step(min(interpret_until, time.monotonic() + SLICE_S))
                elif self.backlog or self.channel.wait(remaining):
                    self._serve_timed()
                    if period > self.base_period_s and self.resting:  # step with it now
                        self.resting = False
                        deadline = time.monotonic()
            wake = time.monotonic()
            self.tick_machines(deadline, period, wake)
            self._finish_steps()
            self._finish_assists()
            self._finish_interpreting()
            self.resting = all(h.resting() for h in self.hosts.values())
            self.channel.flush()  # the tick's pushes in one write
            done = time.monotonic()
            self._account(deadline, wake, done, deadline + period)
            if done > deadline + period:  # skip the deadlines already passed
                skip = int((done - deadline) / period)
                self.missed += skip
                deadline += skip * period
            if self.news_due or done >= next_news:
                self.news_due = False
                next_news = done + NEWS_PERIOD_S
                self.channel.send(self.news())

    def tick_machines(self, deadline: float, period: float, wake: float) -> None:
        """Step each machine due at `deadline` and push its news, looking for requests (an
        E-stop) between machines every SERVE_CHECK_S. A machine a request served meanwhile
        rebuilt or removed is left: its ring is closed, and the new build ticks next pass."""
        checked = wake
        self.status_budget = self._statuses_per_tick(period)
        for host in list(self.hosts.values()):
            if self.hosts.get(host.id) is not host:
                continue
            self._tick(host, deadline, period)
            now = time.monotonic()
            if now - checked >= SERVE_CHECK_S or self.backlog:
                checked = now
                if self.channel.ready() or self.backlog:
                    self._serve_timed()
            if self.hosts.get(host.id) is host:
                self._push_news(host, wake)

    def period(self) -> float:
        """The loop period for the machines held now: the configured one for a few
        machines, longer for a class of them, at most MAX_PERIOD_S; MAX_PERIOD_S while
        every machine rests. A machine's tick costs
        a kernel call whose Python around it (wake-ups, drive status, the ring) outweighs a
        few cycles: stepped in stretches of 10 cycles, an idle seat costs a few µs per ms.
        Commands never wait for a tick."""
        if self.resting:
            return max(MAX_PERIOD_S, self.base_period_s)
        n = max(1, math.ceil(len(self.hosts) / MACHINES_PER_PERIOD))
        return min(MAX_PERIOD_S, max(self.base_period_s, self.base_period_s * n))

    def idle(self) -> bool:
        """Nothing is due before a request arrives: every machine paused (or none held), no
        step, assistant run, capture or request waiting. An idle worker sleeps instead of
        waking every period (a paused machine's status changes only with a request)."""
        if self.backlog or self.steps or self.assists or self.interpreting:
            return False
        if time.monotonic() < self.awake_until:
            return False
        return all(
            h.pacing.mode == "pause"
            and h.pacing.step_to is None
            and not h.captures
            and not (h.flight and h.flight.done)
            for h in self.hosts.values()
        )

    def status_period(self) -> float:
        """How often a watched machine's status is pushed: 20 times a second, 10 once the
        loop period grows (a class of machines: a status costs the worker, the gateway and
        the viewer more than a tick of the machine; the plots keep their full rate)."""
        many = len(self.hosts) > CLASS_MACHINES
        return CLASS_STATUS_PERIOD_S if many else STATUS_PERIOD_S

    def stop(self) -> None:
        self.stopped = True

    def _serve_timed(self) -> None:
        """Serve, counting the time as the loop's work (a request that took long shows in
        the loop's figures, not only in the lateness of the next tick)."""
        t0 = time.monotonic()
        self.serve()
        self.served_s += time.monotonic() - t0

    def _account(self, deadline: float, wake: float, done: float, next_deadline: float) -> None:
        self.ticks += 1
        self.work_s.append(done - wake + self.served_s)
        self.served_s = 0.0
        self.late_s.append(wake - deadline)
        if done > next_deadline and self.hosts:  # without machines, lateness delays nobody
            self.overruns += 1
            self.recent.append((time.time(), (wake - deadline) * 1e3, (done - wake) * 1e3))

    def _tick(self, host: MachineHost, deadline: float, period: float) -> None:
        try:
            host.tick(deadline, period * self.fast_share)
        except Exception:
            self.host_failures += 1
            log.exception("machine %s failed in the real-time loop; pausing it", host.id)
            host.set_mode("pause")

    def _statuses_per_tick(self, period: float) -> int:
        """Statuses one tick may build: the watched machines' share of a status period, and
        one more. Viewers that subscribed together would otherwise have every status due in
        the same tick (50 of them cost a tick ~10 ms); held over, they spread out."""
        return math.ceil(len(self.hosts) * period / self.status_period()) + 1

    def _push_news(self, host: MachineHost, now: float) -> None:
        events = host.machine.events
        fresh = events.cursor != host.pushed_events
        status_due = host.watched and now >= host.status_due and self.status_budget > 0
        flights = host.flights()
        if not (fresh or host.captures or flights or status_due):
            return
        read = events.since(host.pushed_events)
        host.pushed_events = read.cursor
        status = None
        if status_due:
            self.status_budget -= 1
            status = host.status_read()
            sp = self.status_period()
            # one held over keeps its new phase, so the next round is spread already
            late = now - host.status_due > sp / 2
            host.status_due = now + sp if late else host.status_due + sp
        caps, host.captures = host.captures, []
        self.channel.send(
            MachineNews(host.id, host.epoch, read.entries, read.first_seq, status, caps, flights)
        )

    def _finish_steps(self) -> None:
        waiting = []
        for req, mid in self.steps:
            host = self.hosts.get(mid)
            if host is None:
                self.channel.send(Reply(req, Failure("not_found", f"machine '{mid}'")))
            elif host.pacing.step_to is None:
                self.channel.send(Reply(req, host.pacing_now()))
            else:
                waiting.append((req, mid))
        self.steps = waiting

    def _finish_assists(self) -> None:
        waiting = []
        for req, host in self.assists:
            run = host.live
            if self.hosts.get(host.id) is not host or run is None:
                why = f"machine '{host.id}' was rebuilt or removed during the run"
                self.channel.send(Reply(req, Failure("conflict", why)))
            elif run.done:
                value: object = run.result.as_json() if run.result is not None else None
                if run.error is not None:
                    value = Failure("invalid" if run.fed_cycles == 0 else "conflict", run.error)
                self.channel.send(Reply(req, value))
                host.end_assist()
            else:
                waiting.append((req, host))
        self.assists = waiting

    def news(self) -> WorkerNews:
        now, cpu = time.monotonic(), time.process_time()
        t, c = self._cpu
        if now - t > 0.2:
            self._cpu_pct, self._cpu = 100.0 * (cpu - c) / (now - t), (now, cpu)
        work = np.array(self.work_s) * 1e3 if self.work_s else np.zeros(1)
        late = np.array(self.late_s) * 1e3 if self.late_s else np.zeros(1)
        loop = LoopFigures(
            self.period(),
            self.ticks,
            self.overruns,
            self.missed,
            float(np.percentile(work, 50)),
            float(np.percentile(work, 99)),
            float(work.max()),
            float(np.percentile(late, 99)),
            self._cpu_pct,
            self.host_failures,
            list(self.recent),
        )
        return WorkerNews(
            os.getpid(), self.node, loop, {h.id: h.pacing_now() for h in self.hosts.values()}
        )

    # --- requests ---------------------------------------------------------------------------
    def serve(self) -> None:
        """Carry out every request waiting. An emergency stop goes first, also one that
        arrives while others are being carried out (the channel is looked at before each)."""
        waiting = self.backlog
        for _ in range(MAX_SERVE):  # then a tick: a flood of requests cannot stall the loop
            if not waiting or self.channel.ready():
                fresh = self.channel.take()
                stops = [r for r in fresh if _is_stop(r[1])]
                waiting.extendleft(reversed(stops))
                waiting.extend(r for r in fresh if not _is_stop(r[1]))
            if not waiting:
                return
            req, request, sent_mono = waiting.popleft()
            self._answer(req, request, partial(self.handle, req, request, sent_mono))

    def _answer(self, req: int, request: Request, carry_out: Callable[[], object]) -> None:
        """Carry out a request and send its reply (unless it is deferred)."""
        try:
            value = carry_out()
        except (NcUsageError, ValueError) as e:
            value = Failure("invalid", str(e))
        except Exception as e:  # a bug must not take the loop and the other machines
            log.exception("request %r failed", request)
            value = Failure("internal", f"{type(e).__name__}: {e}")
        if value is not _DEFERRED:
            self.channel.send(Reply(req, value))

    def _host(self, mid: str) -> MachineHost:
        host = self.hosts.get(mid)
        if host is None:
            raise _NotHere(mid)
        return host

    def handle(self, req: int, request: Request, sent_mono: float = 0.0) -> object:
        """Carry out one request sent at `sent_mono`; returns the reply value (or _DEFERRED
        for a step)."""
        try:
            return self._handle(req, request, sent_mono)
        except _NotHere as e:
            return Failure("not_found", f"machine '{e.args[0]}'")

    def _handle(self, req: int, r: Request, sent_mono: float) -> object:
        match r:
            case AddMachine():
                old = self.hosts.pop(r.mid, None)
                if old is not None:
                    old.close()
                path = None if self.ring_dir is None else self.ring_dir / f"{r.mid}.{r.epoch}.ring"
                host = MachineHost(r, path)
                host.set_mode(r.mode)
                self.hosts[r.mid] = host
                self.news_due = True
                return host.info()
            case RemoveMachine():
                gone = self.hosts.pop(r.mid, None)
                if gone is not None:
                    gone.close()
                return None
            case Submit():
                host = self._host(r.mid)
                pending = (req, r, sent_mono)
                if self.interpreting.busy(host.id) and not isinstance(r.cmd, EmergencyStop):
                    self.interpreting.hold(host.id, pending)  # after the program it waits for
                    return _DEFERRED
                return self._submit_or_interpret(host, pending)
            case Pace():
                host = self._host(r.mid)
                host.set_mode(r.mode, r.until_cycle)
                self.news_due = True
                return host.pacing_now()
            case Step():
                self._host(r.mid).start_step(r.cycles)
                self.steps.append((req, r.mid))
                return _DEFERRED
            case ApplyValues():
                host = self._host(r.mid)
                _apply(host, r.values)
                return None
            case ReadStatus():
                return self._host(r.mid).status_read()
            case ReadServiceAxes():
                return self._host(r.mid).service_axes_read()
            case Watch():
                host = self._host(r.mid)
                host.watched, host.status_due = r.on, time.monotonic()  # the first one now
                return None
            case ScopeArm():
                host = self._host(r.mid)
                host.arm_scope(r.setup, r.drive)
                return _scope_state(host)
            case ScopeAct():
                host = self._host(r.mid)
                if r.action == "force":
                    host.scope.force()
                elif r.action == "stop":
                    host.scope.stop()
                    host.stop_drive_scope()
                return _scope_state(host)
            case ScopeRoll():
                return _roll(self._host(r.mid), r.max_points)
            case AssistStart():
                host = self._host(r.mid)
                if host.live_of is not None:
                    return Failure("conflict", f"{host.live_of.name} runs: one run at a time")
                if host.pacing.mode == "pause":  # it would hold the run before its first cycle
                    why = "the machine is paused: run it (Simulation) before a run on it"
                    return Failure("conflict", why)
                run = host.start_assist(r)
                if run.error is not None:  # refused before a cycle: nothing moved
                    host.end_assist()
                    return Failure("invalid", run.error)
                self.assists.append((req, host))
                return _DEFERRED
            case AssistCancel():
                host = self._host(r.mid)
                if host.live is None or host.live.done:
                    return Failure("conflict", "no assistant runs on this machine")
                host.live.cancel(r.why)
                return None
            case InjectFault() | RemoveFault() | TakeSnapshot():
                return training_request(self._host(r.mid), r)
        raise NcUsageError(f"unknown request {r!r}")

    def _submit_or_interpret(self, host: MachineHost, pending: Pending) -> object:
        """Carry out a submit, or first interpret the program it needs in the loop's spare time."""
        _req, r, sent_mono = pending
        job = interpretation_needed(host, r)
        if job is None:
            return self._submit(host, r, sent_mono)
        self.interpreting.start(host, job, pending)
        return _DEFERRED

    def _finish_interpreting(self) -> None:
        """Carry out the submits whose program is interpreted now, and those that waited
        behind them, in order (one may need an interpretation of its own: then the rest wait
        for that)."""
        for host, waiting in self.interpreting.finish(lambda h: self.hosts.get(h.id) is h):
            while waiting:
                pending = waiting.popleft()
                req, r, _sent = pending
                if self.hosts.get(host.id) is not host:
                    self.channel.send(Reply(req, Failure("not_found", f"machine '{host.id}'")))
                    continue
                self._answer(req, r, partial(self._submit_or_interpret, host, pending))
                if self.interpreting.busy(host.id):
                    for later in waiting:
                        self.interpreting.hold(host.id, later)
                    break

    def _submit(self, host: MachineHost, r: Submit, sent_mono: float) -> Submitted:
        outcome = host.machine.submit(r.cmd)
        latency_s = time.monotonic() - sent_mono if sent_mono else 0.0
        if isinstance(outcome, Accepted):
            if isinstance(r.cmd, JogStart | JogStop) and (
                r.jog_hold_s is not None or r.jog_release
            ):
                host.hold_jog(r.cmd.axis, None if r.jog_release else r.jog_hold_s)
            if isinstance(r.cmd, EmergencyStop):
                host.pacing.step_to = None  # stop means stop: a long single step ends here too
                if host.live is not None:
                    host.live.cancel("emergency stop: the assistant's run ended")
            if r.then_apply:
                _apply(host, r.then_apply)
        state = {ax.name: ax.state.name for ax in host.machine.axes}
        return Submitted(outcome, host.cycle, state, latency_s)


def _is_stop(request: Request) -> bool:
    return isinstance(request, Submit) and isinstance(request.cmd, EmergencyStop)


class _NotHere(Exception):
    pass


_DEFERRED = object()


def _apply(host: MachineHost, values: Values) -> None:
    apply_values(host.machine.cfg, values)
    host.machine.refresh_params()


def _scope_state(host: MachineHost) -> ScopeState:
    sc = host.scope
    setup = sc.setup
    return ScopeState(
        sc.state.value,
        host.cycle,
        setup.length_cycles if setup else 0,
        setup.pre_cycles if setup else 0,
        min(sc.filled, setup.length_cycles) if setup else 0,
        sc.trigger_cycle,
    )


def _roll(host: MachineHost, max_points: int) -> Roll | Failure:
    snap = host.scope.snapshot()
    if snap is None:
        return Failure("conflict", "the scope is not recording: arm it first")
    stride = max(1, -(-snap.count // max_points))
    return Roll(snap.first_cycle, stride, [s.name for s in snap.channels], snap.data[:, ::stride])


def realtime_priority() -> str:
    """Run the calling thread (a worker's loop) ahead of the gateway and the clients:
    SCHED_FIFO where allowed (root or CAP_SYS_NICE; the loop sleeps to every deadline, and
    Linux keeps 5 % of each second for other tasks, so a worker cannot lock a core up), else
    nice -10, else as it is. On Linux both act on the calling thread only."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(WORKER_RT_PRIORITY))
        return "fifo"
    except (OSError, AttributeError):
        pass
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, WORKER_NICE)
        return "nice"
    return "normal"
