"""One hosted machine: its simulation, a ring buffer of every cycle's samples, and its pacing.

The real-time loop thread calls `tick`; request handlers take `lock` to act between kernel
batches. Every cycle the kernel steps is recorded, so telemetry never has gaps unless a client
falls behind by more than the ring holds.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from api.scope import ScopeSetupModel
from nc_sim.kernel import layout as L
from nc_sim.machine.config import MachineConfig
from nc_sim.machine.machine import Machine
from nc_sim.params import Value
from nc_sim.scope import Record, Scope
from nc_sim.signals import Signal, machine_signals, signal_columns
from nc_sim.sim import Simulation

RING_CYCLES = 1 << 14  # 16.4 s at 1 kHz
FAST_CHUNK = 2000  # cycles per kernel call in fast mode
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
        self.lock = threading.RLock()
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
            self.sim = Simulation(cfg.cycle_s)
            self.machine: Machine = self.sim.add(cfg)
            self.signals: list[Signal] = machine_signals(self.machine)
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
                self.machine.jog_stop(axis)

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
        with self.lock:
            self.pacing.mode = mode
            self.pacing.until_cycle = until_cycle if mode == "fast" else None
            self.pacing.anchor_mono = time.monotonic() - self.sim.cycle * self.cycle_s

    def step(self, cycles: int) -> None:
        """Single-step: pause, then advance exactly `cycles`."""
        with self.lock:
            self.pacing.mode, self.pacing.until_cycle = "pause", None
            self.advance(cycles)
            self.pacing.anchor_mono = time.monotonic() - self.sim.cycle * self.cycle_s

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
