"""One hosted machine: its simulation, a ring buffer of every cycle's samples, and its pacing.

The real-time loop thread calls `tick`; request handlers take `lock` to act between kernel
batches. Every cycle the kernel steps is recorded, so telemetry never has gaps unless a client
falls behind by more than the ring holds.

Nothing holds the lock for long: a step advances in slices of `STEP_SLICE` cycles and hands
the lock over between them, so an emergency stop, a reset, the real-time loop and status
requests wait at most one slice.
"""

from __future__ import annotations

import time
import uuid
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from api.scope import ScopeSetupModel
from backend.services.handover import HandoverLock
from nc_sim.commands import JogStop
from nc_sim.kernel import layout as L
from nc_sim.machine.config import MachineConfig
from nc_sim.machine.machine import Machine
from nc_sim.params import Value
from nc_sim.scope import Record, Scope
from nc_sim.signals import Signal, machine_signals, signal_columns
from nc_sim.sim import Simulation

RING_CYCLES = 1 << 14  # 16.4 s at 1 kHz
FAST_CHUNK = 2000  # cycles per kernel call in fast mode
STEP_SLICE = 1000  # cycles a step advances per turn of the lock (a few ms)
MAX_CATCH_UP_S = 1.0  # behind by more than this: re-anchor instead of racing to catch up
RECENT_CAPTURES = 16  # completed captures kept in memory until saved to the library

# The written parameter lists at capture time: (scope, target) -> {name: value}
ParamSnapshot = dict[tuple[str, str], dict[str, Value]]


@dataclass
class Pending:
    """An accepted value that waits for reset or restart."""

    value: float | int | str
    effect: str


@dataclass
class Capture:
    """A completed scope record with what the machine was at the time."""

    id: str
    record: Record
    params: ParamSnapshot
    created_unix: float


@dataclass
class Pacing:
    mode: str = "run"  # run | pause | fast
    until_cycle: int | None = None
    anchor_mono: float = 0.0  # monotonic time of cycle 0 while running
    slips: int = 0  # times the machine fell > MAX_CATCH_UP_S behind and was re-anchored
    history: deque[tuple[float, int]] = field(default_factory=lambda: deque(maxlen=256))


class MachineHost:
    """A machine in the service."""

    def __init__(self, mid: str, name: str, source: str, cfg: MachineConfig) -> None:
        self.id = mid
        self.name = name
        self.source = source
        self.lock = HandoverLock()
        self.step_interrupts = 0  # a step in progress ends when this changes
        self.pending: dict[tuple[str, str, str], Pending] = {}
        self.pacing = Pacing()
        self.deleted = False  # telemetry closes its subscribers
        self.jog_leases: dict[str, int] = {}  # axis -> cycle at which a held jog stops
        self.captures: deque[Capture] = deque(maxlen=RECENT_CAPTURES)  # newest last
        self.scope_setup: ScopeSetupModel | None = None  # as the client asked for it
        self.build(cfg)

    def build(self, cfg: MachineConfig) -> None:
        """(Re)create the simulation from a config: power on at cycle 0."""
        with self.lock:
            self.interrupt_steps()  # a step must not go on into the new machine
            self.sim = Simulation(cfg.cycle_s)
            self.machine: Machine = self.sim.add(cfg)
            self.signals: list[Signal] = machine_signals(self.machine.axes)
            self.signal_by_name = {s.name: s for s in self.signals}
            self.ring = np.zeros((RING_CYCLES, self.sim.kernel.n, L.R_COLS))
            self.scope = Scope(self.sim.kernel.cycle_s)  # a power cycle stops the scope
            self.epoch = getattr(self, "epoch", 0) + 1  # telemetry cursors restart with it
            self.jog_leases.clear()  # a power cycle ends every held jog
            self.pacing.anchor_mono = time.monotonic()
            self.pacing.history.clear()

    # --- time ----------------------------------------------------------------------------
    @property
    def cycle(self) -> int:
        """Cycles stepped; samples 1..cycle exist, sample c lives at ring[c % RING_CYCLES]."""
        return self.sim.cycle

    @property
    def cycle_s(self) -> float:
        return self.sim.kernel.cycle_s

    def advance(self, n: int) -> None:
        """Step n cycles, recording each into the ring (caller holds the lock).

        A held jog whose lease runs out stops in exactly the cycle its lease ends, so the
        dead-man works the same in real time, single steps and fast mode."""
        while n > 0:
            self._expire_jogs()
            start_cycle = self.sim.cycle + 1
            start = start_cycle % RING_CYCLES
            part = min(n, RING_CYCLES - start)
            if self.jog_leases:
                part = min(part, max(1, min(self.jog_leases.values()) - self.sim.cycle))
            self.sim.run(part, self.ring[start : start + part])
            if self.scope.active:
                self.scope.feed(self.ring[start : start + part], start_cycle, self.machine.events)
                if self.scope.completed:
                    self._take_captures()
            n -= part
        self._expire_jogs()

    def _take_captures(self) -> None:
        """Keep completed records with the parameter lists as written now (cheap copies)."""
        cfg = self.machine.cfg
        params: ParamSnapshot = {("channel", ""): dict(cfg.channel), ("tool", ""): dict(cfg.tools)}
        for a in cfg.axes:
            params[("axis", a.name)] = dict(a.values)
        for rec in self.scope.completed:
            self.captures.append(Capture(uuid.uuid4().hex[:12], rec, params, time.time()))
        self.scope.completed.clear()

    def history(self, cycles: int) -> np.ndarray:
        """Kernel records of the newest `cycles` cycles the ring holds, oldest first."""
        n = min(cycles, self.sim.cycle, RING_CYCLES - 1)
        idx = np.arange(self.sim.cycle - n + 1, self.sim.cycle + 1) % RING_CYCLES
        return self.ring[idx]

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

    def tick(self, now_mono: float, fast_budget_s: float) -> None:
        """Called by the real-time loop each period: step what is due for the mode."""
        p = self.pacing
        with self.lock:
            if p.mode == "run":
                due = int((now_mono - p.anchor_mono) / self.cycle_s) - self.sim.cycle
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
            if p.mode != "run":  # keep the anchor current so "run" continues from now
                p.anchor_mono = now_mono - self.sim.cycle * self.cycle_s
            p.history.append((now_mono, self.sim.cycle))

    def set_mode(self, mode: str, until_cycle: int | None = None) -> None:
        """Pace the machine (ends a step in progress: the new pacing applies at once)."""
        with self.lock:
            self.interrupt_steps()
            self.pacing.mode = mode
            self.pacing.until_cycle = until_cycle if mode == "fast" else None
            self.pacing.anchor_mono = time.monotonic() - self.sim.cycle * self.cycle_s

    def interrupt_steps(self) -> None:
        """End every step in progress after its current slice (emergency stop, new pacing,
        restart)."""
        with self.lock:
            self.step_interrupts += 1

    def step(self, cycles: int) -> int:
        """Single-step: pause, then advance `cycles`, slice by slice with the lock handed over
        in between. Returns the cycles advanced: fewer when an emergency stop, a pacing change
        or a restart ended the step early. Call without holding the lock."""
        with self.lock:
            self.pacing.mode, self.pacing.until_cycle = "pause", None
            mine = self.step_interrupts
        done = 0
        while done < cycles:
            with self.lock:
                if self.step_interrupts != mine:
                    break
                n = min(cycles - done, STEP_SLICE)
                self.advance(n)
                done += n
                self.pacing.anchor_mono = time.monotonic() - self.sim.cycle * self.cycle_s
            self.lock.hand_over()
        return done

    def rt_factor(self) -> float:
        """Simulated seconds per wall second over about the last second."""
        h = list(self.pacing.history)
        if len(h) < 2:
            return 0.0
        t1, c1 = h[-1]
        old = [x for x in h if t1 - x[0] <= 1.0]
        t0, c0 = old[0] if len(old) > 1 else h[-2]
        return (c1 - c0) * self.cycle_s / (t1 - t0) if t1 > t0 else 0.0

    def t0_unix(self) -> float:
        """Wall time (Unix s) of cycle 0 in the current run."""
        return self.pacing.anchor_mono + (time.time() - time.monotonic())

    # --- reading for telemetry --------------------------------------------------------------
    def samples(
        self, signals: list[Signal], first: int, last: int, stride: int
    ) -> tuple[np.ndarray, int]:
        """Samples of cycles first, first+stride, ... ≤ last as signals × count.

        Returns the data and the first cycle actually present (later than `first` when the
        ring no longer holds the older cycles). Caller holds the lock.
        """
        oldest = max(1, self.sim.cycle - RING_CYCLES + 1)
        if first < oldest:
            first += -(-(oldest - first) // stride) * stride
        idx = np.arange(first, last + 1, stride) % RING_CYCLES
        return signal_columns(signals, self.ring[idx]), first
