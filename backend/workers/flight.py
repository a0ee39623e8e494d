"""The flight recorder's worker side: each job error's window, copied as the machine steps.

A machine's worker copies the seconds before a job error from its own sample ring in the
cycle it steps past the error, then the seconds after it part by part as it steps them, and
pushes the window once the machine has run past its end. Only the worker knows when a cycle
is stepped: a gateway that copied the window from the ring had to read it before the worker
lapped the ring (a fast simulation laps its 16 s in a fraction of a second), and lost the
seconds after the error whenever it was short of CPU for that long. The gateway saves the
windows (backend/services/flight.py).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from nc_sim.events import Event, EventLog
from nc_sim.signals import CHANNEL, Signal, signal_rows

_MAIN = ("speed_cmd_rpm", "speed_act_rpm", "pos_cmd_", "pos_act_", "lag_", "vel_cmd_", "vel_act_")
_CHANNEL_MAIN = (f"{CHANNEL}.state", f"{CHANNEL}.path_feed_mm_min")


def main_signals(signals: list[Signal]) -> list[Signal]:
    """The signals the recorder keeps: per axis command, actual value, lag and velocity or
    speed; the channel's state and path feed."""
    return [
        s for s in signals if s.name in _CHANNEL_MAIN or s.name.split(".", 1)[-1].startswith(_MAIN)
    ]


@dataclass(frozen=True)
class FlightWindow:
    """The main signals of the cycles first_cycle.. around a job error (the trigger), every
    cycle, with the job errors that fell into it and the events of its cycles."""

    trigger: Event
    errors: list[Event]
    events: list[Event]
    seen_unix: float  # the wall clock of the tick that stepped past the error
    first_cycle: int
    signals: list[Signal]  # the rows of `data`, in order
    data: np.ndarray  # signals × cycles


@dataclass
class _Open:
    trigger: Event
    first: int
    last: int
    errors: list[Event]
    seen_unix: float
    parts: list[np.ndarray] = field(default_factory=list)
    next_cycle: int = 0  # the next cycle to copy

    def copy(self, signals: list[Signal], rows: np.ndarray, head: int) -> None:
        """Copy the cycles up to `head` (at most the window's last) not copied yet."""
        hi = min(self.last, head)
        if hi >= self.next_cycle:
            idx = np.arange(self.next_cycle, hi + 1) % len(rows)
            self.parts.append(signal_rows(signals, rows, idx))
            self.next_cycle = hi + 1


class FlightTaker:
    """One machine's job error windows (its worker's loop thread alone uses it)."""

    def __init__(
        self, signals: list[Signal], before: int, after: int, cursor: int, from_cycle: int
    ) -> None:
        """Windows of `before` cycles before and `after` after each job error logged from
        event `cursor` on; none reaches before `from_cycle` (the first its ring holds)."""
        self.signals = main_signals(signals)
        self.before, self.after = before, after
        self.cursor = cursor
        self.from_cycle = from_cycle
        self.open: list[_Open] = []
        self.done: list[FlightWindow] = []  # complete, not pushed yet

    def step(self, log: EventLog[Event], rows: np.ndarray, head: int) -> None:
        """After the machine stepped up to cycle `head` (its ring's `rows` hold them, and at
        most a ring's length before): open a window for each new job error (one that falls
        into an open window joins it), copy what the open windows miss, complete those that
        end by `head`."""
        if log.cursor != self.cursor:
            read = log.since(self.cursor)
            self.cursor = read.cursor
            for e in read.entries:
                if not e.error:
                    continue
                joined = next((w for w in self.open if e.cycle <= w.last), None)
                if joined is not None:
                    joined.errors.append(e)
                    continue
                oldest = max(self.from_cycle, head - len(rows) + 1)
                first = max(oldest, e.cycle - self.before)
                self.open.append(
                    _Open(e, first, e.cycle + self.after, [e], time.time(), next_cycle=first)
                )
        if not self.open:
            return
        for w in self.open:
            w.copy(self.signals, rows, head)
        for w in [w for w in self.open if w.last <= head]:
            self.open.remove(w)
            events = [x for x in log if w.first <= x.cycle <= w.last]
            data = np.concatenate(w.parts, axis=1)
            window = FlightWindow(
                w.trigger, w.errors, events, w.seen_unix, w.first, self.signals, data
            )
            self.done.append(window)
