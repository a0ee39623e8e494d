"""The scope: records chosen signals every cycle and captures a record around a trigger.

Pure and cycle-exact like the kernel. The owner feeds it each block of kernel records as the
simulation produces them (`feed`), with the machine's event log; it never reads a clock.

A capture of `length` cycles with `pre` pre-trigger cycles holds cycles
`trigger - pre … trigger - pre + length - 1`, so the trigger sample sits at index `pre`.
On arming, the pre-trigger history is filled at once from the owner's recent samples, so a
trigger right after arming still gets its full pre-trigger; a trigger that comes before `pre`
cycles of history exist is ignored (the scope waits for the next one), except within the
first `pre` cycles after power-on, where it is taken with the history there is.

Modes: `roll` records continuously without a trigger; `normal` re-arms after each capture;
`single` stops after one. Triggers: a level crossing of any signal (rising or falling, with
hysteresis: the signal must first be beyond `level ∓ hysteresis` before a crossing counts) or
an event of the NC. Event triggers fire in the first cycle whose samples show the event: what
the NC raises between two cycles (an M function starting, a PLC acknowledgement changing the
gear, a job error) shows from the cycle after the last one completed; what the kernel detects
within a cycle (speed reached, the in-position edge that ends M19) shows in that cycle.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np

from nc_sim.errors import Code, is_error
from nc_sim.events import Event, EventLog
from nc_sim.signals import Signal, signal_columns

MAX_CHANNELS = 16
MAX_LENGTH_CYCLES = 60_000  # 60 s at 1 kHz


class ScopeMode(StrEnum):
    ROLL = "roll"
    NORMAL = "normal"
    SINGLE = "single"


class ScopeState(StrEnum):
    IDLE = "idle"  # not recording
    ROLL = "roll"  # free running
    ARMED = "armed"  # waiting for the trigger
    TRIGGERED = "triggered"  # recording the post-trigger part
    DONE = "done"  # single capture complete


class EventKind(StrEnum):
    M_START = "m_start"
    M19_DONE = "m19_done"
    GEAR_CHANGE = "gear_change"
    JOB_ERROR = "job_error"
    SPEED_REACHED = "speed_reached"


@dataclass(frozen=True)
class LevelTrigger:
    """Fire when `signal` crosses `level` (display units) on the given edge."""

    signal: Signal
    level: float
    rising: bool = True
    hysteresis: float = 0.0

    def describe(self) -> str:
        edge = "rising" if self.rising else "falling"
        hyst = f" (hysteresis {self.hysteresis:g})" if self.hysteresis else ""
        return f"{self.signal.name} {edge} through {self.level:g} {self.signal.unit}{hyst}".strip()


@dataclass(frozen=True)
class EventTrigger:
    """Fire on an NC event of one axis (or any axis), e.g. the start of M19 on S1."""

    kind: EventKind
    axis: str | None = None
    m: int | None = None  # M_START only: which M function (None: any)

    def describe(self) -> str:
        what = {
            EventKind.M_START: f"M{self.m} start" if self.m is not None else "M function start",
            EventKind.M19_DONE: "M19 done",
            EventKind.GEAR_CHANGE: "gear change",
            EventKind.JOB_ERROR: "job error",
            EventKind.SPEED_REACHED: "speed reached",
        }[self.kind]
        return f"{what} on {self.axis}" if self.axis else what

    def cycle_of(self, ev: Event) -> int | None:
        """The trigger cycle this event gives, or None when it does not match (by its code,
        axis and M function: never by its message)."""
        if self.axis is not None and ev.axis != self.axis:
            return None
        if self.kind is EventKind.M_START:
            ok = ev.code == Code.EV_M_START and (self.m is None or ev.m == self.m)
            return ev.cycle + 1 if ok else None
        if self.kind is EventKind.GEAR_CHANGE:
            return ev.cycle + 1 if ev.code == Code.EV_GEAR_CHANGED else None
        if self.kind is EventKind.M19_DONE:  # the in-position that ends an M19 positioning
            ok = ev.code == Code.EV_IN_POSITION and ev.m == 19
            return ev.cycle if ok else None
        if self.kind is EventKind.SPEED_REACHED:
            return ev.cycle if ev.code == Code.EV_SPEED_REACHED else None
        return ev.cycle + 1 if is_error(ev.code) else None


Trigger = LevelTrigger | EventTrigger


@dataclass(frozen=True)
class ScopeSetup:
    """What to record and when to capture."""

    channels: Sequence[Signal]
    length_cycles: int
    pretrigger_pct: float = 20.0
    mode: ScopeMode = ScopeMode.SINGLE
    trigger: Trigger | None = None

    @property
    def pre_cycles(self) -> int:
        return round(self.length_cycles * self.pretrigger_pct / 100.0)

    def check(self) -> None:
        """Raise ValueError naming what is out of range."""
        if not 1 <= len(self.channels) <= MAX_CHANNELS:
            raise ValueError(f"channels: 1 … {MAX_CHANNELS}, got {len(self.channels)}")
        if not 2 <= self.length_cycles <= MAX_LENGTH_CYCLES:
            raise ValueError(
                f"record length: 2 … {MAX_LENGTH_CYCLES} cycles, got {self.length_cycles}"
            )
        if not 0.0 <= self.pretrigger_pct <= 100.0:
            raise ValueError(f"pre-trigger: 0 … 100 %, got {self.pretrigger_pct:g}")
        if self.mode is not ScopeMode.ROLL and self.trigger is None:
            raise ValueError(f"{self.mode.value} mode needs a trigger")
        if isinstance(self.trigger, LevelTrigger) and self.trigger.hysteresis < 0:
            raise ValueError("hysteresis: ≥ 0")


@dataclass
class Record:
    """A captured record: channels × samples of consecutive cycles, with its trigger."""

    channels: list[Signal]
    data: np.ndarray  # channels × samples, display units
    first_cycle: int
    cycle_s: float
    trigger_cycle: int | None
    trigger: str  # description, "" for a roll snapshot
    forced: bool = False
    events: list[Event] = field(default_factory=list)

    @property
    def count(self) -> int:
        return int(self.data.shape[1])

    @property
    def cycles(self) -> np.ndarray:
        return np.arange(self.first_cycle, self.first_cycle + self.count)

    @property
    def pre_cycles(self) -> int:
        return 0 if self.trigger_cycle is None else self.trigger_cycle - self.first_cycle


class Scope:
    """One machine's scope. Feed it every block of records; collect `completed` records."""

    def __init__(self, cycle_s: float) -> None:
        self.cycle_s = cycle_s
        self.setup: ScopeSetup | None = None
        self.state = ScopeState.IDLE
        self.completed: list[Record] = []  # the owner takes them away
        self._ring = np.zeros((0, 0))
        self._head = 0  # last cycle written into the ring
        self._oldest = 1  # first cycle the ring holds
        self._trigger_cycle: int | None = None
        self._forced = False
        self._search_from = 0  # triggers before this cycle do not count
        self._primed = False  # level trigger: the signal was beyond the hysteresis band
        self._event_cursor = 0  # sequence number of the next event to look at
        self._level_column: list[Signal] = []

    @property
    def active(self) -> bool:
        return self.state in (ScopeState.ROLL, ScopeState.ARMED, ScopeState.TRIGGERED)

    @property
    def trigger_cycle(self) -> int | None:
        return self._trigger_cycle

    @property
    def filled(self) -> int:
        """Cycles of history the ring holds (at most the record length)."""
        return 0 if self.setup is None else self._head - self._oldest + 1

    def arm(
        self,
        setup: ScopeSetup,
        head: int,
        history: np.ndarray,
        events: EventLog[Event],
    ) -> None:
        """Start recording after cycle `head`. `history` holds kernel records of the cycles
        just before (up to `head`, oldest first) to fill the pre-trigger from."""
        setup.check()
        self.setup = setup
        n = setup.length_cycles
        self._ring = np.zeros((len(setup.channels), n))
        keep = min(history.shape[0], n - 1, head)
        self._head, self._oldest = head, head - keep + 1
        if keep:
            self._write(signal_columns(list(setup.channels), history[-keep:]), head - keep + 1)
        self._trigger_cycle, self._forced = None, False
        self._search_from = head + 1
        self._event_cursor = events.cursor
        trig = setup.trigger
        self._level_column = [trig.signal] if isinstance(trig, LevelTrigger) else []
        # a crossing in the first cycle after arming counts when the cycle before was below
        self._primed = False
        if isinstance(trig, LevelTrigger) and keep:
            x = float(signal_columns([trig.signal], history[-1:])[0, 0])
            v, s = (x, trig.level) if trig.rising else (-x, -trig.level)
            self._primed = v < s - trig.hysteresis
        self.state = ScopeState.ROLL if setup.mode is ScopeMode.ROLL else ScopeState.ARMED

    def stop(self) -> None:
        """Stop recording; a capture in progress is dropped."""
        self.state = ScopeState.IDLE
        self._trigger_cycle = None

    def force(self) -> None:
        """Trigger now, at the newest cycle (the pre-trigger may be shorter than asked)."""
        if self.state is ScopeState.ARMED:
            self._trigger_cycle, self._forced = self._head, True
            self.state = ScopeState.TRIGGERED

    def feed(self, rec: np.ndarray, first_cycle: int, events: EventLog[Event]) -> None:
        """Take the kernel records of cycles first_cycle … first_cycle + len(rec) - 1."""
        if not self.active or self.setup is None or rec.shape[0] == 0:
            return
        n = self.setup.length_cycles
        cols = signal_columns(list(self.setup.channels), rec)
        level = signal_columns(self._level_column, rec)[0] if self._level_column else None
        last = first_cycle + rec.shape[0] - 1
        pos = first_cycle
        # Write only as far as a capture needs before taking it: a block may be longer
        # than the ring, and the ring must still hold the record's first cycle at its end.
        while pos <= last:
            if self.state is ScopeState.ARMED:
                t = self._find_trigger(level, first_cycle, pos, last, events)
                if t is None:
                    break
                self._trigger_cycle, self.state = t, ScopeState.TRIGGERED
            if self.state is not ScopeState.TRIGGERED:
                break
            end = self._record_first() + n - 1
            stop = min(end, last)
            self._write(cols[:, pos - first_cycle : stop - first_cycle + 1], pos)
            pos = stop + 1
            if stop == end:
                self._complete(end, events)
        if pos <= last and self.active:
            self._write(cols[:, pos - first_cycle :], pos)

    def snapshot(self) -> Record | None:
        """The newest record length of a running roll (or whatever the ring holds)."""
        if self.setup is None or self.filled <= 0:
            return None
        first = max(self._oldest, self._head - self.setup.length_cycles + 1)
        return Record(
            list(self.setup.channels), self._read(first, self._head), first, self.cycle_s, None, ""
        )

    # --- inside -----------------------------------------------------------------------------
    def _write(self, cols: np.ndarray, first_cycle: int) -> None:
        n = self._ring.shape[1]
        if cols.shape[1] > n:  # only the newest record length survives
            first_cycle += cols.shape[1] - n
            cols = cols[:, -n:]
        idx = np.arange(first_cycle, first_cycle + cols.shape[1]) % n
        self._ring[:, idx] = cols
        self._head = first_cycle + cols.shape[1] - 1
        self._oldest = max(self._oldest, self._head - n + 1)

    def _read(self, first: int, last: int) -> np.ndarray:
        """A copy of cycles first … last: one or two contiguous slices of the ring (a 60 s
        record completes inside the real-time loop, so no index arrays)."""
        n = self._ring.shape[1]
        a, b = first % n, last % n
        if a <= b and last - first < n:
            return self._ring[:, a : b + 1].copy()
        return np.concatenate((self._ring[:, a:], self._ring[:, : b + 1]), axis=1)

    def _record_first(self) -> int:
        assert self.setup is not None and self._trigger_cycle is not None
        return max(self._oldest, self._trigger_cycle - self.setup.pre_cycles)

    def _accepts(self, t: int) -> bool:
        """A trigger counts once the full pre-trigger history exists for it, or when the
        history reaches back to power-on (cycle 1): no more can ever exist, and an event just
        after start-up is better caught with a shorter pre-trigger than missed."""
        assert self.setup is not None
        if t < self._search_from:
            return False
        return t - self.setup.pre_cycles >= self._oldest or self._oldest <= 1

    def _find_trigger(
        self,
        level: np.ndarray | None,
        first_cycle: int,
        pos: int,
        last: int,
        events: EventLog[Event],
    ) -> int | None:
        trig = self.setup.trigger if self.setup else None
        if isinstance(trig, EventTrigger):
            read = events.since(self._event_cursor)
            self._event_cursor = read.first_seq  # events the log dropped are gone for us too
            for ev in read.entries:
                t = trig.cycle_of(ev)
                if t is not None and t > last:
                    return None  # acts in a later block: look again then
                self._event_cursor += 1
                if t is not None and t >= pos and self._accepts(t):
                    return t
            return None
        if isinstance(trig, LevelTrigger) and level is not None:
            return self._level_crossing(trig, level, first_cycle, pos)
        return None

    def _level_crossing(
        self, trig: LevelTrigger, x: np.ndarray, first_cycle: int, pos: int
    ) -> int | None:
        s = trig.level if trig.rising else -trig.level
        v = x if trig.rising else -x  # a falling edge is a rising edge of -x
        i = max(0, pos - first_cycle, self._search_from - first_cycle)
        while i < v.size:
            if not self._primed:
                below = np.flatnonzero(v[i:] < s - trig.hysteresis)
                if below.size == 0:
                    return None
                i += int(below[0])
                self._primed = True
            above = np.flatnonzero(v[i:] >= s)
            if above.size == 0:
                return None
            i += int(above[0])
            self._primed = False
            if self._accepts(first_cycle + i):
                return first_cycle + i
        return None

    def _complete(self, end: int, events: EventLog[Event]) -> None:
        setup = self.setup
        assert setup is not None and self._trigger_cycle is not None
        first = self._record_first()
        window: list[Event] = []
        for e in reversed(events):  # the log is in cycle order; the window is near its end
            if e.cycle < first:
                break
            if e.cycle <= end:
                window.append(e)
        window.reverse()
        desc = setup.trigger.describe() if setup.trigger else ""
        self.completed.append(
            Record(
                list(setup.channels),
                self._read(first, end),
                first,
                self.cycle_s,
                self._trigger_cycle,
                "forced" if self._forced else desc,
                self._forced,
                window,
            )
        )
        self._search_from = end + 1
        self._trigger_cycle, self._forced = None, False
        self._primed = False
        self.state = ScopeState.DONE if setup.mode is ScopeMode.SINGLE else ScopeState.ARMED
