"""The simulated PLC: switches the drives on at start-up and acknowledges M functions; and
the NC's side of that handshake.

Modes: `auto` acknowledges after a delay, `manual` waits for `acknowledge()`, `fault` never
answers (the NC then raises a job error after its timeout) - for training.

`Handshake` is the one way an M function goes to the PLC: output (event), acknowledgement
(event, then whoever waits continues) or, after P-CHAN plc.m_ack_timeout, job error 90004
(then whoever waits is told). A block waits for its M functions, a gear change for its
M40-M45; each hands a `Waiter` with what to do.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum

from nc_sim.errors import Code
from nc_sim.events import Event, Log


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


def _nothing() -> None:
    pass


def _ignore(_ev: Event) -> None:
    pass


@dataclass
class Waiter:
    """Who waits on an M function: what continues on its acknowledgement, what happens on its
    timeout (given the job error), and the axis the job error is logged for ("" channel)."""

    acknowledged: Callable[[], None] = _nothing
    timed_out: Callable[[Event], None] = _ignore
    error_axis: str = ""


@dataclass
class Handshake:
    """M function output -> acknowledgement | timeout, between the NC and its PLC."""

    plc: SimPlc
    timeout_cycles: int  # P-CHAN plc.m_ack_timeout in cycles
    cycle_s: float
    log: Log
    now: Callable[[], int]  # the machine's current cycle
    _waiting: dict[int, Waiter] = field(default_factory=dict)  # by output cycle (unique key)

    def output(self, m: int, axis: str, waiter: Waiter, gear: int | None = None) -> None:
        """Output M`m` (for `axis`, "" channel) to the PLC; `waiter` continues on its answer."""
        p = self.plc.output(m, axis, self.now())
        while p.out_cycle in self._waiting:  # one key per output
            p.out_cycle += 1
        self._waiting[p.out_cycle] = waiter
        self.log(Code.EV_M_OUTPUT, axis, f"M{m} output to the PLC", m=m, gear=gear)

    def acknowledge(self, m: int | None = None) -> int:
        """Manual acknowledgement (of M`m`, or all); returns how many M functions were
        acknowledged (0 when none was pending, e.g. after its 90004 timeout)."""
        acked = self.plc.acknowledge(m)
        for p in acked:
            self._acked(p)
        return len(acked)

    def on_cycle(self, cycle: int) -> None:
        """The PLC's acknowledgements due in this cycle, then the timeouts that ran out."""
        for p in self.plc.due(cycle):
            self._acked(p)
        for out, waiter in list(self._waiting.items()):
            if cycle - out >= self.timeout_cycles:
                del self._waiting[out]
                gone = self.plc.withdraw(out)  # timed out means gone: a late ack finds nothing
                ev = self.log(
                    Code.PLC_ACK_TIMEOUT,
                    waiter.error_axis,
                    f"no acknowledgement after {self.timeout_cycles * self.cycle_s:g} s",
                    m=gone.m if gone else None,
                )
                waiter.timed_out(ev)

    def next_wakeup(self) -> int | None:
        """The next cycle an acknowledgement or a timeout is due."""
        times = [out + self.timeout_cycles for out in self._waiting]
        due = self.plc.next_due()
        if due is not None:
            times.append(due)
        return min(times) if times else None

    def clear(self) -> None:
        """Reset: nothing is output any more, nothing waits."""
        self._waiting.clear()
        self.plc.clear()

    def _acked(self, p: PendingM) -> None:
        self.log(Code.EV_M_ACK, "", f"M{p.m} acknowledged", m=p.m)
        waiter = self._waiting.pop(p.out_cycle, None)
        if waiter is not None:
            waiter.acknowledged()
