"""The channel as the operator drives it: MDI blocks, program load, cycle start, stop, and
the interpretation of NC text from where the axes are now.

MDI blocks and programs both run through the channel (nc_sim/channel/channel.py); this
module answers the commands (nc_sim/commands.py) with their outcomes and logs what the
operator sees.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

from nc_sim.channel import canon
from nc_sim.channel.canon import ListSink
from nc_sim.channel.interpreter import interpret_blocks, interpret_steps
from nc_sim.channel.words import ProgramError
from nc_sim.commands import Accepted, Invalid, Outcome, Refused
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.machine.core import MachineCore
from nc_sim.snapshot import ChannelState
from nc_sim.units import AxisKind

PROGRAM_ACTIVE = (ChannelState.RUNNING, ChannelState.HELD, ChannelState.BLOCK_END)


@dataclass(frozen=True)
class Interpretation:
    """A program's text and everything its interpretation depends on (the machine's names
    and positions when it was asked for): `steps` needs nothing else, so a host may run it
    between its other work and hand the machine the result (`ChannelOps.prime`)."""

    text: str
    axes: tuple[str, ...]
    spindles: tuple[str, ...]
    start: tuple[tuple[str, float], ...]
    home: tuple[tuple[str, float], ...]
    c_axis: str | None
    rotary: bool

    @property
    def key(self) -> tuple[object, ...]:
        """What makes two interpretations alike (NaN, an unknown C, equal to itself)."""
        start = tuple((n, None if math.isnan(p) else p) for n, p in self.start)
        return (self.text, self.axes, self.spindles, start, self.home, self.c_axis, self.rotary)

    def steps(self, sink: canon.Sink) -> Iterator[None]:
        """The interpretation into `sink`, a block per step (raises ProgramError)."""
        start, home = dict(self.start), dict(self.home)
        return interpret_steps(
            self.text, sink, self.axes, self.spindles, start, True, home, self.c_axis, self.rotary
        )

    def run(self) -> list[canon.Call] | ProgramError:
        """The program's canonical calls, or the error it stops at."""
        sink = ListSink()
        try:
            for _ in self.steps(sink):
                pass
        except ProgramError as e:
            return e
        return sink.calls


class ChannelOps:
    """Commands to the channel of one machine."""

    def __init__(self, m: MachineCore) -> None:
        self.m = m
        self.next_block = 1  # MDI block numbers
        # the last interpretation's key and result: reused while the axes have not moved
        self._interpreted: tuple[tuple[object, ...], list[canon.Call] | ProgramError] | None
        self._interpreted = None

    @property
    def _names(self) -> tuple[list[str], list[str]]:
        """The channel's path axes and the spindles, as NC text names them."""
        m = self.m
        spindles = [a.name for a in m.axes if a.kind is AxisKind.SPINDLE]
        return list(m.channel.axes), spindles

    def home_positions(self) -> dict[str, float]:
        """Where G74 leaves each path axis: its reference position (kenngr.ref_pos)."""
        return {a.name: a.cfg.eng("kenngr.ref_pos") for a in self.m.ch_host.path_axes}

    def _busy(self, serial: int) -> Refused | None:
        """A refusal when a program runs or a stopped one's path is still braking."""
        ch = self.m.channel
        fail = self.m.motion.fail
        if ch.state in PROGRAM_ACTIVE and not ch.progress.mdi:
            return Refused(serial, fail(None, Code.AXIS_BUSY, "a program is running"))
        if ch.braking:
            return Refused(serial, fail(None, Code.AXIS_BUSY, "the stopped path is still braking"))
        return None

    # --- MDI ------------------------------------------------------------------------------
    def mdi(self, text: str, serial: int) -> Outcome:
        """Interpret a block with the modal words the MDI blocks before it left and queue it
        on the channel: a block with an error is invalid (line and column), one that fails
        while starting is refused with its job error, one that started or waits behind the
        running ones is accepted."""
        m = self.m
        refused = self._busy(serial)
        if refused is not None:
            return refused
        modal = m.channel.mdi_modal()
        modal.home_position = self.home_positions()
        cax = m.cax
        if cax is not None and not m.channel.progress.mdi:  # from the machine's mode now
            modal.rotary = cax.rotary
            if not cax.rotary:
                modal.position[cax.c_name] = math.nan
        sink = ListSink()
        axes, spindles = self._names
        try:
            interpret_blocks(text, sink, modal, axes, spindles, cax.c_name if cax else None)
        except ProgramError as e:
            m.log(Code(e.code), "", f"{e.detail} (column {e.column}) in '{text}'")
            return Invalid(serial, e.detail, e.column, int(e.code), e.line)
        bid = self.next_block
        self.next_block += 1
        err = m.channel.run_mdi(bid, text, sink.calls)
        if err is not None:
            return Refused(serial, err)
        return Accepted(serial, m.cycle, block_id=bid)

    # --- programs -------------------------------------------------------------------------
    def interpretation(self, text: str) -> Interpretation:
        """How `text` interprets from where the axes are now."""
        m = self.m
        start = {a.name: float(m.k.st[a.slot, L.S_P_CMD]) for a in m.axes}
        cax = m.cax
        if cax is not None:  # C where the rotary axis is; unknown while a spindle
            start[cax.c_name] = start[cax.ax.name] if cax.rotary else math.nan
        axes, spindles = self._names
        return Interpretation(
            text,
            tuple(axes),
            tuple(spindles),
            tuple(start.items()),
            tuple(self.home_positions().items()),
            cax.c_name if cax else None,
            cax.rotary if cax else False,
        )

    def interpreted(self, text: str) -> bool:
        """Whether `text` from here is interpreted already (a load or a start takes no time)."""
        done = self._interpreted
        return done is not None and done[0] == self.interpretation(text).key

    def prime(self, job: Interpretation, result: list[canon.Call] | ProgramError) -> None:
        """Keep a result its host got by running `job` elsewhere (another thread)."""
        self._interpreted = (job.key, result)

    def interpret_here(self, text: str) -> list[canon.Call]:
        """A program's canonical calls from where the axes are now (raises ProgramError);
        the last result is reused while the axes have not moved since."""
        job = self.interpretation(text)
        if self._interpreted is None or self._interpreted[0] != job.key:
            self._interpreted = (job.key, job.run())
        result = self._interpreted[1]
        if isinstance(result, ProgramError):
            raise result
        return result

    def program_load(self, name: str, text: str, serial: int) -> Outcome:
        """Check a program by interpreting it from here; keep it when it has no error."""
        m = self.m
        refused = self._busy(serial)
        if refused is None and m.channel.progress.mdi:
            refused = Refused(serial, m.motion.fail(None, Code.AXIS_BUSY, "MDI blocks run"))
        if refused is not None:
            return refused
        try:
            self.interpret_here(text)
        except ProgramError as e:
            m.log(Code(e.code), "", f"{name}: {e.detail}", line=e.line, column=e.column)
            return Invalid(serial, e.detail, e.column, int(e.code), e.line)
        m.channel.load(name, text)
        m.log(Code.EV_PROGRAM_LOADED, "", f"program {name} loaded")
        return Accepted(serial, m.cycle)

    def cycle_start(self) -> Event | None:
        """Run the loaded program, or continue after feedhold or a single-block stop."""
        m = self.m
        ch = m.channel
        fail = m.motion.fail
        if ch.state in (ChannelState.HELD, ChannelState.BLOCK_END):
            if m.channel_units["feedhold"]:
                return fail(None, Code.FEEDHOLD_ACTIVE)
            ch.resume()
            return None
        if ch.progress.mdi:
            return fail(None, Code.AXIS_BUSY, "MDI blocks are running")
        if ch.state is ChannelState.RUNNING:
            return None
        if m.estop:
            return fail(None, Code.CHANNEL_ERROR_STATE, "emergency stop active")
        if ch.state is ChannelState.IDLE:
            return fail(None, Code.CHANNEL_ERROR_STATE, "no program loaded")
        if ch.state is ChannelState.ERROR:
            return fail(None, Code.CHANNEL_ERROR_STATE, "reset first")
        if ch.braking:
            return fail(None, Code.AXIS_BUSY, "the stopped program's path is still braking")
        m.modal_at_program_start()
        try:
            ch.start()
        except ProgramError as e:
            return m.log(Code(e.code), "", e.detail, line=e.line, column=e.column)
        name = ch.progress.program.name if ch.progress.program else ""
        m.log(Code.EV_PROGRAM_START, "", f"program {name}")
        # the start may have ended in a job error at once (an axis not ready, a limit)
        return ch.progress.error

    def stop(self) -> None:
        """Program stop (or the end of the MDI blocks): brake on the path and rewind."""
        if self.m.channel.state in PROGRAM_ACTIVE:
            if self.m.cax is not None:  # a mode change interrupts a changeover [003 §2.3]
                self.m.cax.interrupt(estop=False)
            self.m.channel.stop()
            self.m.log(Code.EV_PROGRAM_STOP)
