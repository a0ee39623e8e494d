"""The simulated PLC: switches the drives on at start-up, acknowledges M functions and
answers the spindle/rotary-axis mode requests [003 §4.1]; and the NC's side of that handshake.

Modes: `auto` acknowledges after a delay, `manual` waits for `acknowledge()` (an M function)
or `set_signal()` (ROTMOD_Q/SPMOD_Q), `fault` never answers (the NC then raises a job error
after its timeout) - for training.

`Handshake` is the one way a request goes to the PLC: output (event), acknowledgement (event,
then whoever waits continues) or, after P-CHAN plc.m_ack_timeout, job error 90004 (then whoever
waits is told). A block waits for its M functions, a gear change for its M40-M45, a changeover
for ROTMOD_Q or SPMOD_Q; each hands a `Waiter` with what to do. The mode acknowledgements are
levels, not pulses: the PLC keeps the one of the mode in force set [003 §4.1].
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


MODE_SIGNALS = ("ROTMOD", "SPMOD")  # the NC's mode requests; the PLC answers with <name>_Q


@dataclass
class PendingM:
    """An M function (or a mode request ROTMOD/SPMOD, `signal`) output to the PLC and not yet
    acknowledged."""

    m: int | None
    axis: str
    out_cycle: int
    due_cycle: int | None  # when auto mode will acknowledge it
    signal: str | None = None

    @property
    def what(self) -> str:
        return self.signal if self.signal is not None else f"M{self.m}"


class SimPlc:
    """A PLC program reduced to what commissioning needs from it."""

    def __init__(self, delay_cycles: int, power_on_cycle: int = 5) -> None:
        self.mode = PlcMode.AUTO
        self.delay_cycles = delay_cycles
        self.power_on_cycle = power_on_cycle
        self.pending: list[PendingM] = []
        # a fault of the PLC program (training, nc_sim/faults.py), hidden behind the mode the
        # HLI shows: in auto mode it never acknowledges, or only after its own delay
        self.no_ack = False
        self.slow_ack_cycles: int | None = None
        # the mode acknowledgements the PLC holds: at power-on it reports spindle mode
        self.signals: dict[str, bool] = {"ROTMOD_Q": False, "SPMOD_Q": True}

    def _due(self, since: int) -> int | None:
        """When the PLC program acknowledges a request of cycle `since` on its own."""
        if self.mode is not PlcMode.AUTO or self.no_ack:
            return None
        delay = self.delay_cycles if self.slow_ack_cycles is None else self.slow_ack_cycles
        return since + delay

    def set_mode(self, mode: PlcMode, now: int, delay_cycles: int | None = None) -> None:
        """Switch mode; pending functions get a due cycle in auto mode."""
        self.mode = mode
        if delay_cycles is not None:
            self.delay_cycles = delay_cycles
        for p in self.pending:
            p.due_cycle = self._due(now)

    def set_program_fault(self, no_ack: bool, slow_ack_cycles: int | None, now: int) -> None:
        """The PLC program's fault (training): never acknowledge, or acknowledge
        `slow_ack_cycles` after the request; pending requests follow it (never before now)."""
        self.no_ack, self.slow_ack_cycles = no_ack, slow_ack_cycles
        for p in self.pending:
            due = self._due(p.out_cycle)
            p.due_cycle = None if due is None else max(due, now)

    def output(self, m: int | None, axis: str, now: int, signal: str | None = None) -> PendingM:
        """The NC outputs an M function (or sets a mode request `signal`); returns its
        pending entry."""
        p = PendingM(m, axis, now, self._due(now), signal)
        self.pending.append(p)
        return p

    def acknowledge(self, m: int | None = None) -> list[PendingM]:
        """Manual acknowledgement of one M function (or all with m=None); returns those acked.
        Mode requests are answered by their signal (`answer`), not here."""
        acked = [p for p in self.pending if p.signal is None and (m is None or p.m == m)]
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

    def answer(self, signal: str) -> list[PendingM]:
        """The PLC sets `signal` (ROTMOD_Q/SPMOD_Q) by hand: the request it answers, if any."""
        acked = [p for p in self.pending if p.signal is not None and f"{p.signal}_Q" == signal]
        for p in acked:
            self.pending.remove(p)
        return acked

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

    def request(self, signal: str, axis: str, waiter: Waiter) -> None:
        """Set the mode request `signal` (ROTMOD/SPMOD) for `axis`; `waiter` continues when
        the PLC's acknowledgements read that mode: <signal>_Q set and the other reset (at once
        when they do already: they are levels)."""
        p = self.plc.output(None, axis, self.now(), signal)
        while p.out_cycle in self._waiting:
            p.out_cycle += 1
        self._waiting[p.out_cycle] = waiter
        self._match()

    def withdraw_request(self, signal: str) -> None:
        """A changeover that ended without its answer: its request is pending no more."""
        for p in [p for p in self.plc.pending if p.signal == signal]:
            self.plc.pending.remove(p)
            self._waiting.pop(p.out_cycle, None)

    def acknowledge(self, m: int | None = None) -> int:
        """Manual acknowledgement (of M`m`, or all); returns how many M functions were
        acknowledged (0 when none was pending, e.g. after its 90004 timeout)."""
        acked = self.plc.acknowledge(m)
        for p in acked:
            self._acked(p)
        return len(acked)

    def set_signal(self, signal: str, on: bool, axis: str = "") -> int:
        """The PLC sets or resets a mode acknowledgement (ROTMOD_Q/SPMOD_Q) by hand; setting
        one answers its pending request. Returns how many requests it answered."""
        if on:
            acked = self.plc.answer(signal)
            for p in acked:
                self._acked(p)
            if acked:
                return len(acked)
        self._level(signal, on, axis)
        return self._match()

    def _match(self) -> int:
        """Pending mode requests whose acknowledgement the levels already give (the
        requested one set, the other reset) are answered; returns how many."""
        on = self.plc.signals
        matched = [
            p
            for p in self.plc.pending
            if p.signal is not None
            and on.get(f"{p.signal}_Q")
            and not any(on.get(f"{s}_Q") for s in MODE_SIGNALS if s != p.signal)
        ]
        for p in matched:
            self.plc.pending.remove(p)
            waiter = self._waiting.pop(p.out_cycle, None)
            if waiter is not None:
                waiter.acknowledged()
        return len(matched)

    def _level(self, signal: str, on: bool, axis: str) -> None:
        if self.plc.signals.get(signal) == on:
            return
        self.plc.signals[signal] = on
        code = Code.EV_SIGNAL_ON if on else Code.EV_SIGNAL_OFF
        self.log(code, axis, f"{signal} = {int(on)}", signal=signal, value=int(on))

    def on_cycle(self, cycle: int) -> None:
        """The PLC's acknowledgements due in this cycle, then the timeouts that ran out."""
        for p in self.plc.due(cycle):
            self._acked(p)
        for out, waiter in list(self._waiting.items()):
            if cycle - out >= self.timeout_cycles:
                del self._waiting[out]
                gone = self.plc.withdraw(out)  # timed out means gone: a late ack finds nothing
                what = "" if gone is None else f"of {gone.what} "
                if gone is not None and gone.signal is not None:
                    what = f"{gone.signal}_Q for the request {gone.signal} "
                ev = self.log(
                    Code.PLC_ACK_TIMEOUT,
                    waiter.error_axis,
                    f"no acknowledgement {what}after {self.timeout_cycles * self.cycle_s:g} s",
                    m=gone.m if gone else None,
                    signal=gone.signal if gone else None,
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
        if p.signal is None:
            self.log(Code.EV_M_ACK, "", f"M{p.m} acknowledged", m=p.m)
        else:  # the acknowledgement of the new mode set, then the other one reset
            self._level(f"{p.signal}_Q", True, p.axis)
            for s in MODE_SIGNALS:
                if s != p.signal:
                    self._level(f"{s}_Q", False, p.axis)
        waiter = self._waiting.pop(p.out_cycle, None)
        if waiter is not None:
            waiter.acknowledged()
