"""One machine in a worker: its simulation, its sample ring, its pacing, its scope.

Only the worker's loop thread touches a host, so nothing here locks. Every cycle the kernel
steps is written into the sample ring and then published, so the gateway's readers never
see a half-written row and telemetry has no gaps unless a reader falls a whole ring behind.
"""

from __future__ import annotations

import bisect
import logging
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from backend.workers.flight import FlightTaker, FlightWindow
from backend.workers.protocol import (
    AddMachine,
    AssistRunning,
    AssistStart,
    MachineInfo,
    Mode,
    Pacing,
    ParamSnapshot,
    ServiceAxesRead,
    StatusRead,
    param_snapshot,
)
from backend.workers.ring import MAX_WRITE, R_COLS, SampleRing
from nc_sim.assist.drive_axis import drive_axis
from nc_sim.assist.procedure import LiveRun
from nc_sim.assist.run import live
from nc_sim.channel.modal import PLANES
from nc_sim.commands import JogStop
from nc_sim.drive_scope import DriveScope, drive_signals
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.machine.service import history_cycles, service_view
from nc_sim.scope import Record, Scope, ScopeSetup
from nc_sim.signals import Signal, machine_signals
from nc_sim.sim import Simulation, restore
from nc_sim.training.checks import ExerciseMonitor
from nc_sim.training.exercise import Exercise

log = logging.getLogger(__name__)

assert R_COLS == L.R_COLS, "the ring's record width must follow the kernel layout"

FAST_CHUNK = MAX_WRITE  # cycles per kernel call in fast mode
CHECK_CYCLES = 500  # an exercise's checks see the records in stretches of about this many
# (a status read feeds them too; each feed costs the same few numpy calls whatever its length)
MAX_CATCH_UP_S = 1.0  # behind by more than this: re-anchor instead of racing to catch up


@dataclass
class PacingState:
    mode: Mode = "run"
    until_cycle: int | None = None
    anchor_mono: float = 0.0  # monotonic time of cycle 0 while running
    slips: int = 0  # times the machine fell > MAX_CATCH_UP_S behind and was re-anchored
    step_to: int | None = None  # single step in progress: advance to this cycle
    # (wall monotonic time a tick's stepping ended, cycle reached): the real-time factor
    history: deque[tuple[float, int]] = field(default_factory=lambda: deque(maxlen=256))


class MachineHost:
    """A machine owned by a worker."""

    def __init__(self, r: AddMachine, ring_path: Path | None) -> None:
        """The machine of an AddMachine: powered on at cycle 0, or restored from its state;
        then its training faults injected and its exercise's checks set up."""
        self.id = r.mid
        self.name = r.name
        self.epoch = r.epoch
        if r.state is not None:
            self.sim = restore(r.state)
            self.machine: Machine = self.sim.machines[0]
        else:
            self.sim = Simulation(r.cfg.cycle_s)
            self.machine = self.sim.add(r.cfg)
        for fault, trigger in r.faults:
            self.machine.inject(fault, trigger)
        self.monitor = None
        if isinstance(r.exercise, Exercise):  # its checks count from this build on
            self.monitor = ExerciseMonitor(r.exercise.checks, self.machine)
        self.monitor_fed = self.sim.cycle  # records up to here went to the monitor
        self.signals: list[Signal] = machine_signals(
            self.machine.axes, self.machine.channel_slot, self.machine.rotary_spindle
        )
        self.signal_by_name = {s.name: s for s in self.signals}
        self.drive_signals = [
            sig for ax in self.machine.axes for sig in drive_signals(ax.name, ax.kind, ax.slot)
        ]
        self.ring = SampleRing.create(ring_path, self.sim.kernel.n)
        self.scope = Scope(self.sim.kernel.cycle_s)
        self.drive_scope: DriveScope | None = None  # a drive-rate capture's ring
        self.captures: list[tuple[Record, ParamSnapshot]] = []  # completed, not yet pushed
        self.flight: FlightTaker | None = None  # the flight recorder's job error windows
        if r.flight_s is not None:
            before, after = (round(s / self.cycle_s) for s in r.flight_s)
            cursor = self.machine.events.cursor  # errors of a restored log are not this ring's
            self.flight = FlightTaker(self.signals, before, after, cursor, self.cycle + 1)
        self.jog_leases: dict[str, int] = {}  # axis -> cycle at which a held jog stops
        self.pacing = PacingState(anchor_mono=time.monotonic())
        self.clock: Callable[[], float] = time.monotonic  # wall time (a test's own clock)
        self.watched = False
        self.status_due = 0.0  # monotonic time of the next status push while watched
        # events up to here went out: none yet, the gateway's copy (new for each build) is
        # the machine's own log, a restored one's included
        self.pushed_events = self.machine.events.first_seq
        self.live: LiveRun | None = None  # a live assistant run, until it is answered
        self.live_of: AssistStart | None = None

    def info(self) -> MachineInfo:
        path = self.ring.path
        return MachineInfo(
            self.id,
            self.epoch,
            self.cycle_s,
            [ax.name for ax in self.machine.axes],
            self.signals,
            self.sim.kernel.n,
            str(path) if path is not None else None,
            self.pacing_now(),
            self.machine.faults(),
            self.drive_signals,
        )

    @property
    def cycle(self) -> int:
        """Cycles stepped; samples 1..cycle exist in the ring."""
        return self.sim.cycle

    @property
    def cycle_s(self) -> float:
        return self.sim.kernel.cycle_s

    def advance(self, n: int) -> None:
        """Step n cycles, recording each into the ring.

        A held jog whose lease runs out stops in exactly the cycle its lease ends, so the
        dead-man works the same in real time, single steps and fast mode."""
        rows = self.ring.rows
        while n > 0:
            self._expire_jogs()
            start_cycle = self.sim.cycle + 1
            start = start_cycle % self.ring.cycles
            part = min(n, self.ring.cycles - start, MAX_WRITE)
            if self.jog_leases:
                part = min(part, max(1, min(self.jog_leases.values()) - self.sim.cycle))
            if self.drive_scope is not None:  # its record must still be in the ring
                part = min(part, DriveScope.FEED_CYCLES)
            live = self.live if self.live is not None and not self.live.done else None
            if live is not None:  # it sees each cycle it asked for before the next one runs
                part = min(part, live.want())
            self.sim.run(part, rows[start : start + part])
            self.ring.publish(self.sim.cycle)
            if self.flight is not None:  # before the next part can lap what it must copy
                self.flight.step(self.machine.events, rows, self.sim.cycle)
            if live is not None:
                live.feed(rows[start : start + part])
            if self.monitor is not None and self.sim.cycle - self.monitor_fed >= CHECK_CYCLES:
                self.feed_monitor()
            if self.scope.active:
                self.scope.feed(rows[start : start + part], start_cycle, self.machine.events)
                if self.scope.completed:
                    self._take_captures()
            n -= part
        self._expire_jogs()

    def flights(self) -> list[FlightWindow]:
        """The job error windows completed since the last call."""
        if self.flight is None or not self.flight.done:
            return []
        done, self.flight.done = self.flight.done, []
        return done

    def params_now(self) -> ParamSnapshot:
        """The parameter lists as written now (cheap copies)."""
        return param_snapshot(self.machine.cfg)

    def arm_scope(self, setup: ScopeSetup, drive: list[Signal]) -> None:
        """(Re)arm the scope; with `drive` channels (one axis' drive signals) its captures are
        those at the drive's rate. ValueError naming why a drive-rate capture cannot run."""
        self.stop_drive_scope()
        history = self.history(setup.length_cycles)
        if drive:  # the axis on the drive cascade, its probe free (ExperimentError: why not)
            ax, _ = drive_axis(self.machine, drive[0].axis, "a drive-rate capture")
            self.drive_scope = DriveScope(
                self.sim.kernel, self.sim.cycle, ax.slot, drive, setup.length_cycles
            )
            history = history[:0]  # the ring starts now: no pre-trigger before it
        self.scope.arm(setup, self.cycle, history, self.machine.events)

    def stop_drive_scope(self) -> None:
        if self.drive_scope is not None:
            self.drive_scope.stop()
            self.drive_scope = None

    def _take_captures(self) -> None:
        """Keep completed records with the parameter lists as written now (at the drive's
        rate for a drive-rate capture: the span the NC record found, cut from the ring)."""
        params = self.params_now()
        for rec in self.scope.completed:
            if self.drive_scope is not None:
                drive_rec = self.drive_scope.record(rec)
                if drive_rec is None:
                    log.warning("%s: a drive-rate capture fell out of its ring", self.id)
                    continue
                rec = drive_rec
            self.captures.append((rec, params))
        self.scope.completed.clear()
        if not self.scope.active:  # a single capture done: the ring ends with it
            self.stop_drive_scope()

    def start_assist(self, r: AssistStart) -> LiveRun:
        """Start a live assistant run (one at a time); ValueError (an ExperimentError) when
        it cannot run live or as asked, KeyError for an unknown name. A run refused at once
        (its motion refused) comes back done, with its error."""
        self.live = LiveRun(self.machine, live(r.name, r.args), self.cycle_s)
        self.live_of = r
        return self.live

    def end_assist(self) -> None:
        """The run's answer went out: the machine is free for the next."""
        self.live = self.live_of = None

    def assist_running(self) -> AssistRunning | None:
        live, of = self.live, self.live_of
        if live is None or of is None or live.done:
            return None
        phase, elapsed_s, planned_s = live.progress()
        axis = str(of.args.get("axis", ""))
        if not axis and of.args.get("plane") in PLANES:  # the circle: the plane's two axes
            axis = "".join(PLANES[int(str(of.args["plane"]))][:2])
        return AssistRunning(of.name, axis, phase, elapsed_s, planned_s, of.by)

    def feed_monitor(self) -> None:
        """Hand the exercise's checks the records since they last saw them (in stretches:
        a call per cycle would cost 50 seats more than their kernel)."""
        if self.monitor is None or self.sim.cycle == self.monitor_fed:
            return
        n = self.sim.cycle - self.monitor_fed
        self.monitor.feed(self.machine, self.history(n), self.sim.cycle - n + 1)
        self.monitor_fed = self.sim.cycle

    def history(self, cycles: int) -> np.ndarray:
        """Kernel records of the newest `cycles` cycles the ring holds, oldest first."""
        n = min(cycles, self.sim.cycle, self.ring.cycles - 1)
        idx = np.arange(self.sim.cycle - n + 1, self.sim.cycle + 1) % self.ring.cycles
        rows: np.ndarray = self.ring.rows[idx]
        return rows

    def hold_jog(self, axis: str, hold_s: float | None) -> None:
        """Renew (or with None drop) the dead-man lease of a continuous jog."""
        if hold_s is None:
            self.jog_leases.pop(axis, None)
        else:
            self.jog_leases[axis] = self.sim.cycle + max(1, round(hold_s / self.cycle_s))

    def _expire_jogs(self) -> None:
        for axis, end in list(self.jog_leases.items()):
            if self.sim.cycle >= end:
                del self.jog_leases[axis]
                self.machine.submit(JogStop(axis))  # the dead-man released the key

    def resting(self) -> bool:
        """Nothing is commanded to move in the newest cycle (no set-point speed on any axis
        or spindle), no jog held, no assistant, capture or step under way: the loop may step
        this machine in longer stretches (what it records is the same, only sent in fewer
        batches)."""
        p = self.pacing
        if p.mode != "run" or p.step_to is not None or self.jog_leases or self.scope.active:
            return p.mode == "pause" and p.step_to is None
        if self.live is not None:
            return False
        newest = self.ring.rows[self.sim.cycle % self.ring.cycles]
        return not newest[:, L.R_V_CMD].any()

    def due_cycle(self, now_mono: float) -> int:
        """The cycle real time calls for now (while running)."""
        return int((now_mono - self.pacing.anchor_mono) / self.cycle_s)

    def tick(self, now_mono: float, fast_budget_s: float) -> None:
        """Step what is due for the pacing mode (the loop calls this every period)."""
        p = self.pacing
        if p.step_to is not None:
            self.advance(min(p.step_to - self.sim.cycle, FAST_CHUNK))
            if self.sim.cycle >= p.step_to:
                p.step_to = None
        elif p.mode == "run":
            due = self.due_cycle(now_mono) - self.sim.cycle
            limit = int(MAX_CATCH_UP_S / self.cycle_s)
            if due > limit:
                p.slips += 1
                p.anchor_mono += (due - limit) * self.cycle_s
                due = limit
            if due > 0:
                self.advance(due)
        elif p.mode == "fast":
            end = time.monotonic() + fast_budget_s
            while time.monotonic() < end:
                n = FAST_CHUNK
                if p.until_cycle is not None:
                    n = min(n, p.until_cycle - self.sim.cycle)
                    if n <= 0:
                        p.mode, p.until_cycle = "pause", None
                        break
                self.advance(n)
        if p.mode != "run" or p.step_to is not None:  # "run" continues from now
            p.anchor_mono = now_mono - self.sim.cycle * self.cycle_s
        # when the stepping ended, not the deadline it stepped to: cycles per deadline are
        # 1.0 by construction, a starved or slipping worker shows only against the wall
        p.history.append((self.clock(), self.sim.cycle))

    def set_mode(self, mode: Mode, until_cycle: int | None = None) -> None:
        """Pace the machine; a single step in progress ends (the new pacing applies at once)."""
        p = self.pacing
        p.step_to = None
        p.mode = mode
        p.until_cycle = until_cycle if mode == "fast" else None
        p.anchor_mono = time.monotonic() - self.sim.cycle * self.cycle_s

    def start_step(self, cycles: int) -> int:
        """Pause and advance `cycles` over the next ticks; returns the cycle to reach."""
        self.set_mode("pause")
        self.pacing.step_to = self.sim.cycle + cycles
        return self.pacing.step_to

    def rt_factor(self) -> float:
        """Simulated seconds per wall second over about the last second (stepping ends
        against the wall clock: below 1 while the worker falls behind or slips)."""
        h = self.pacing.history
        if len(h) < 2:
            return 0.0
        t1, c1 = h[-1]
        i = bisect.bisect_left(h, t1 - 1.0, key=lambda x: x[0])  # the oldest within 1 s
        t0, c0 = h[i] if len(h) - i > 1 else h[-2]
        return (c1 - c0) * self.cycle_s / (t1 - t0) if t1 > t0 else 0.0

    def pacing_now(self) -> Pacing:
        p = self.pacing
        mode: Mode = "pause" if p.step_to is not None else p.mode
        return Pacing(
            mode,
            self.sim.cycle,
            self.cycle_s,
            self.rt_factor(),
            p.until_cycle,
            p.anchor_mono + (time.time() - time.monotonic()),
            p.slips,
        )

    def status_read(self) -> StatusRead:
        """The machine's snapshot and pacing now."""
        checks: list[object] = []
        if self.monitor is not None:
            self.feed_monitor()
            checks = list(self.monitor.results())
        return StatusRead(
            self.machine.snapshot(),
            self.pacing_now(),
            self.assist_running(),
            self.machine.faults(),
            checks,
        )

    def service_axes_read(self) -> ServiceAxesRead:
        """The service-axis view of every axis, with the measured gain from the ring's newest
        records (enough for its settling and averaging window)."""
        rec = self.history(history_cycles(self.machine))
        return ServiceAxesRead(self.sim.cycle, service_view(self.machine, rec))

    def close(self) -> None:
        """Remove the machine's ring file (the gateway unmaps its side)."""
        path = self.ring.path
        self.ring.close()
        if path is not None:
            path.unlink(missing_ok=True)
