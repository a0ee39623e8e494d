"""The simulated PLC: switches the drives on at start-up and acknowledges M functions.

Modes: `auto` acknowledges after a delay, `manual` waits for `acknowledge()`, `fault` never
answers (the NC then raises a job error after its timeout) - for training.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class PlcMode(StrEnum):
    AUTO = "auto"
    MANUAL = "manual"
    FAULT = "fault"


@dataclass
class PendingM:
    """An M function output to the PLC and not yet acknowledged."""

    m: int
    axis: str
    out_cycle: int
    due_cycle: int | None  # when auto mode will acknowledge it


class SimPlc:
    """A PLC program reduced to what commissioning needs from it."""

    def __init__(self, delay_cycles: int, power_on_cycle: int = 5) -> None:
        self.mode = PlcMode.AUTO
        self.delay_cycles = delay_cycles
        self.power_on_cycle = power_on_cycle
        self.pending: list[PendingM] = []

    def set_mode(self, mode: PlcMode, now: int, delay_cycles: int | None = None) -> None:
        """Switch mode; pending functions get a due cycle in auto mode."""
        self.mode = mode
        if delay_cycles is not None:
            self.delay_cycles = delay_cycles
        for p in self.pending:
            p.due_cycle = now + self.delay_cycles if mode is PlcMode.AUTO else None

    def output(self, m: int, axis: str, now: int) -> PendingM:
        """The NC outputs an M function; returns its pending entry."""
        due = now + self.delay_cycles if self.mode is PlcMode.AUTO else None
        p = PendingM(m, axis, now, due)
        self.pending.append(p)
        return p

    def acknowledge(self, m: int | None = None) -> list[PendingM]:
        """Manual acknowledgement of one M function (or all with m=None); returns those acked."""
        acked = [p for p in self.pending if m is None or p.m == m]
        if m is not None:
            acked = acked[:1]
        for p in acked:
            self.pending.remove(p)
        return acked

    def withdraw(self, out_cycle: int) -> PendingM | None:
        """The NC gave up waiting (timeout): the M function is no longer pending anywhere,
        so a late acknowledgement finds nothing to acknowledge."""
        for p in self.pending:
            if p.out_cycle == out_cycle:
                self.pending.remove(p)
                return p
        return None

    def due(self, now: int) -> list[PendingM]:
        """Acknowledgements the PLC gives in this cycle (auto mode)."""
        out = [p for p in self.pending if p.due_cycle is not None and p.due_cycle <= now]
        for p in out:
            self.pending.remove(p)
        return out

    def next_due(self) -> int | None:
        dues = [p.due_cycle for p in self.pending if p.due_cycle is not None]
        return min(dues) if dues else None

    def clear(self) -> None:
        self.pending.clear()
