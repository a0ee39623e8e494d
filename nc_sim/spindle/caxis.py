"""The main spindle with rotary-axis capability [003 §2-§4]: spindle S or rotary axis C, and
the changeover between the two with its PLC handshake, in the order of 003 Fig. 4-1:

1. activate: for a command that needs the other mode (C in G00-G03, #CAX, a jog of C: rotary;
   M3/M4/M5/M19, G33, G63, #CAX OFF, the spindle keys: spindle). A block waits for it;
2. internal: brake to standstill, speed control, the drive parameter record of the mode
   (rotary: P-AXIS-00052 `kenngr.cax_getriebe_stufe`; spindle: the gear stage it had before);
3. external: the request ROTMOD (SPMOD) set and the other reset, then wait for the PLC's
   acknowledgement ROTMOD_Q (SPMOD_Q), a level it keeps while the mode is in force;
4. de-activate;
5. position control with the position rebased into 0..360° (rotary), or speed control;
6. the mode signal to the user interface (EV_ROTARY_MODE / EV_SPINDLE_MODE; the status
   shows C or S1 from then on).

An immediate stop (E-stop, program stop) interrupts a changeover: the spindle brakes, the
request stays pending. A reset aborts it and adopts the mode the PLC acknowledges, as at
power-on; a jog or spindle key aborts it and starts the changeover the key needs [003 §2.3].
A withdrawn acknowledgement of the mode in force is a process error.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from enum import StrEnum
from functools import partial

from nc_sim.axis.params import push_params, speed_controlled
from nc_sim.axis.state import Axis
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.plc import Handshake, Waiter
from nc_sim.snapshot import AxisState
from nc_sim.spindle.control import SpindleControl

Then = Callable[[], Event | None]  # what a key does once the mode it needs is in force


class SpindleMode(StrEnum):
    """What the main spindle with rotary-axis capability is now."""

    SPINDLE = "spindle"  # speed-controlled spindle S (M3/M4/M5/M19, G33, G63)
    ROTARY = "rotary"  # position-controlled rotary axis C (G00-G03, jog)
    NONE = "none"  # neither: changing over, or the PLC acknowledges no mode


class Changeover:
    """One changeover in progress; the axis' sequence while it brakes (phase 2)."""

    def __init__(self, cax: CAxis, rotary: bool, action_id: int | None, then: Then | None):
        self.cax = cax
        self.rotary = rotary
        self.action_id = action_id  # the block waiting for it, None for a key
        self.then = then
        self.phase = "internal"  # internal -> external
        self.interrupted = False

    @property
    def request(self) -> str:
        """The request signal to the PLC: ROTMOD for rotary axis mode, SPMOD for spindle."""
        return "ROTMOD" if self.rotary else "SPMOD"

    def on_event(self, ev: int) -> bool:
        if ev & L.EV_PLAN_DONE and self.phase == "internal":
            self.cax.internal_done(self)
        return bool(ev & L.EV_PLAN_DONE)

    def replan(self) -> bool:
        return True  # braking to standstill: no override acts on it


class CAxis:
    """The mode of one main spindle with rotary-axis capability and its changeover."""

    def __init__(
        self,
        sp: SpindleControl,
        ax: Axis,
        c_name: str,
        handshake: Handshake,
        on_path: Callable[[bool], None],
        fail_block: Callable[[Axis], None],
    ) -> None:
        self.sp = sp
        self.ax = ax
        self.c_name = c_name  # P-CHAN-00010
        self.handshake = handshake
        self.on_path = on_path  # the channel's path takes (True) or leaves the axis alone
        self.fail_block = fail_block  # a job error of the axis stops the block it runs for
        self.mode = SpindleMode.NONE
        self.change: Changeover | None = None
        self.spindle_gear = ax.gear  # the spindle's gear stage while it is the C axis
        self.requests = {"ROTMOD": False, "SPMOD": False}  # the NC's outputs to the PLC
        self.adopt()

    # --- what the others ask ------------------------------------------------------------
    @property
    def mode(self) -> SpindleMode:
        """The mode in force: rotary axis, spindle, or none (changing over, no acknowledgement)."""
        return self._mode

    @mode.setter
    def mode(self, mode: SpindleMode) -> None:
        self._mode = mode  # the kernel records it every cycle (`S1.rotary_mode`)
        self.sp.motion.k.ist[self.ax.slot, L.I_ROTARY_MODE] = int(mode is SpindleMode.ROTARY)

    @property
    def rotary(self) -> bool:
        return self.mode is SpindleMode.ROTARY

    @property
    def spindle_mode(self) -> bool:
        return self.mode is SpindleMode.SPINDLE

    @property
    def display_name(self) -> str:
        """The name the user interface shows: C in rotary axis mode, else the spindle's."""
        return self.c_name if self.rotary else self.ax.name

    @property
    def phase(self) -> str | None:
        """The changeover's phase: internal, external, interrupted; None without one."""
        c = self.change
        if c is None:
            return None
        return "interrupted" if c.interrupted else c.phase

    # --- activation -----------------------------------------------------------------------
    def request(
        self, rotary: bool, action_id: int | None = None, then: Then | None = None
    ) -> Event | None:
        """The mode a command needs (rotary axis or spindle); `then` runs once it is in
        force (at once when it is). The job error when the changeover cannot start."""
        c = self.change
        if c is not None and c.interrupted:
            self._abort("a new changeover was commanded")
        elif c is not None and c.rotary == rotary:  # it is on its way: wait for it too
            if action_id is not None:
                c.action_id = self.ax.block_id = action_id
            c.then = then or c.then
            return None
        elif c is not None:
            what = "rotary axis" if c.rotary else "spindle"
            return self.sp.motion.fail(
                self.ax, Code.AXIS_BUSY, f"{self.ax.name} changes over to {what} mode"
            )
        target = SpindleMode.ROTARY if rotary else SpindleMode.SPINDLE
        if self.mode is target:
            return then() if then is not None else None
        err = self._refusal(rotary)
        if err is not None:
            return err
        self._activate(Changeover(self, rotary, action_id, then))
        return None

    def cancel_then(self) -> None:
        """A key released before its changeover ended (jog stop): it no longer follows."""
        if self.change is not None:
            self.change.then = None

    def _refusal(self, rotary: bool) -> Event | None:
        ax, motion = self.ax, self.sp.motion
        err = motion.check_motion(ax)
        if err is not None:
            return err
        if rotary and speed_controlled(ax.cfg):  # the C axis is position-controlled
            why = "no encoder" if ax.cfg.flag("sim.sensorless") else "speed-controlled"
            return motion.fail(
                ax, Code.CHANGEOVER_NOT_POSSIBLE, f"{ax.name} is {why}: no rotary axis mode"
            )
        if ax.state is AxisState.HOMING:
            return motion.fail(ax, Code.AXIS_BUSY, f"{ax.name} is homing")
        return None

    def _activate(self, c: Changeover) -> None:
        """(1) and (2): activate, then brake to standstill under speed control."""
        ax, sp = self.ax, self.sp
        self.change = c
        src, dst = (ax.name, self.c_name) if c.rotary else (self.c_name, ax.name)
        into = "rotary axis" if c.rotary else "spindle"
        sp.motion.log(Code.EV_CHANGEOVER, ax.name, f"changeover {src} → {into} {dst}")
        self.mode = SpindleMode.NONE
        self.on_path(False)
        ax.sequence = None  # a spindle task or jog in progress ends: the drive decelerates
        ax.block_id = c.action_id  # the block waits for it (the channel host's `busy`)
        ax.motion = None
        sp.set_state(ax, AxisState.CHANGEOVER)
        ax.sequence = c
        v = float(sp.motion.k.st[ax.slot, L.S_V_CMD])
        if abs(v) > 0.0:
            sp.motion.plan_velocity(ax, 0.0, sp.limits(ax))
        else:
            self.internal_done(c)

    # --- the phases ---------------------------------------------------------------------
    def internal_done(self, c: Changeover) -> None:
        """(2) done: the drive's parameter record of the new mode; (3) ask the PLC."""
        ax, sp = self.ax, self.sp
        if c is not self.change or c.interrupted:
            return
        sp.switch_back(ax)  # (no speed-control changeover armed from an M3 before)
        if c.rotary:
            self.spindle_gear = ax.gear
            record = int(ax.cfg.raw("kenngr.cax_getriebe_stufe"))
        else:
            record = self.spindle_gear
        if record != ax.gear:
            ax.gear = record
            push_params(sp.motion.k, ax)
        sp.motion.log(
            Code.EV_CHANGEOVER_INTERNAL,
            ax.name,
            f"{ax.name} at standstill in speed control, drive parameter record {record}",
            gear=record,
        )
        c.phase = "external"
        sp.motion.unwatch(ax)  # the PLC's acknowledgement timeout bounds the next phase
        self._outputs(c.rotary)
        waiter = Waiter(partial(self.external_done, c), partial(self._timed_out, c), ax.name)
        self.handshake.request(c.request, ax.name, waiter)

    def external_done(self, c: Changeover) -> None:
        """The PLC acknowledged: (4) de-activate, (5) the control mode, (6) the mode signal."""
        if c is not self.change or c.interrupted:
            return  # the PLC answered an interrupted changeover: a reset adopts its answer
        ax = self.ax
        self.sp.motion.log(
            Code.EV_CHANGEOVER_END,
            ax.name,
            f"{c.request}_Q from the PLC: the changeover is complete and de-activated",
        )
        self.change = None
        ax.sequence, ax.block_id = None, None
        self._enter(SpindleMode.ROTARY if c.rotary else SpindleMode.SPINDLE)
        self.sp.set_state(ax, AxisState.STANDSTILL)
        if c.then is not None:
            c.then()

    def _timed_out(self, c: Changeover, ev: Event) -> None:
        """Fault: no acknowledgement in time. The block stops, the spindle is in no mode."""
        if c is not self.change:
            return
        self._fail(ev)

    # --- interruptions ------------------------------------------------------------------
    def interrupt(self, estop: bool) -> None:
        """Immediate stop: an E-stop, or a program stop while a block waits for the
        changeover. The internal sequence stops, the request to the PLC stays pending."""
        c = self.change
        if c is None or c.interrupted or (not estop and c.action_id is None):
            return
        c.interrupted, c.action_id, c.then = True, None, None
        ax, sp = self.ax, self.sp
        ax.sequence, ax.block_id = None, None
        sp.motion.log(
            Code.EV_CHANGEOVER_INTERRUPTED,
            ax.name,
            f"changeover interrupted in its {c.phase} phase: reset, or a jog or spindle key, "
            "ends it",
        )
        if not estop and ax.state is AxisState.CHANGEOVER:  # (an E-stop brakes by itself)
            if abs(float(sp.motion.k.st[ax.slot, L.S_V_CMD])) > 0.0:
                sp.motion.stop(ax, sp.limits(ax))
            else:
                sp.set_state(ax, AxisState.STANDSTILL)

    def axis_failed(self) -> None:
        """A job error of the drive during a changeover (enables lost while braking, the
        watchdog): it ends unfinished, in no mode; a reset adopts the PLC's."""
        c, self.change = self.change, None
        if c is None or c.interrupted:
            self.change = c
            return
        self.handshake.withdraw_request(c.request)
        self.mode = SpindleMode.NONE

    def reset(self) -> None:
        """Control reset: a changeover ends, the NC adopts the mode the PLC acknowledges."""
        if self.change is not None:
            self._abort("reset")
        self.adopt()

    def _abort(self, why: str) -> None:
        c = self.change
        assert c is not None
        self.change = None
        self.handshake.withdraw_request(c.request)
        ax = self.ax
        if ax.sequence is c:
            ax.sequence, ax.block_id = None, None
        if ax.state is AxisState.CHANGEOVER:
            self.sp.motion.stop(ax, self.sp.limits(ax))
        self.sp.motion.log(
            Code.EV_CHANGEOVER_ABORTED, self.ax.name, f"changeover to {c.request} aborted: {why}"
        )

    def adopt(self) -> None:
        """As at power-on [003 §2.3]: the mode whose acknowledgement the PLC holds (none when
        it holds neither or both; the next command that needs one changes over)."""
        rot, spm = (self.handshake.plc.signals.get(s, False) for s in ("ROTMOD_Q", "SPMOD_Q"))
        mode = SpindleMode.ROTARY if rot and not spm else SpindleMode.NONE
        if spm and not rot:
            mode = SpindleMode.SPINDLE
        if mode is not SpindleMode.NONE:
            self._outputs(mode is SpindleMode.ROTARY)
        if mode is not self.mode:
            self._enter(mode, record=True)

    # --- the PLC --------------------------------------------------------------------------
    def plc_signal(self, signal: str, on: bool) -> int:
        """The PLC sets or resets ROTMOD_Q/SPMOD_Q (manual mode, training). Withdrawing the
        acknowledgement of the mode in force is a process error [003 §4.1]."""
        answered = self.handshake.set_signal(signal, on, self.ax.name)
        in_force = {SpindleMode.ROTARY: "ROTMOD_Q", SpindleMode.SPINDLE: "SPMOD_Q"}
        if not on and in_force.get(self.mode) == signal:
            ev = self.sp.motion.fail(
                self.ax,
                Code.MODE_ACK_WITHDRAWN,
                f"{signal} withdrawn in {self.mode.value} mode of {self.display_name}",
            )
            self._fail(ev)
        return answered

    def _outputs(self, rotary: bool) -> None:
        """(3) The requests to the PLC: the new mode's set, the other's reset."""
        for signal in ("SPMOD", "ROTMOD") if rotary else ("ROTMOD", "SPMOD"):
            on = (signal == "ROTMOD") == rotary
            if self.requests[signal] != on:
                self.requests[signal] = on
                code = Code.EV_SIGNAL_ON if on else Code.EV_SIGNAL_OFF
                self.sp.motion.log(
                    code, self.ax.name, f"{signal} = {int(on)}", signal=signal, value=int(on)
                )

    # --- the modes ------------------------------------------------------------------------
    def _enter(self, mode: SpindleMode, record: bool = False) -> None:
        """(5) and (6): position control in 0..360° as the C axis, or the spindle again;
        with `record` (adopted at a reset) the drive's parameter record as well."""
        ax, motion = self.ax, self.sp.motion
        self.mode = mode
        if mode is SpindleMode.ROTARY:
            if record and ax.gear != int(ax.cfg.raw("kenngr.cax_getriebe_stufe")):
                self.spindle_gear = ax.gear
                ax.gear = int(ax.cfg.raw("kenngr.cax_getriebe_stufe"))
                push_params(motion.k, ax)
            p = float(motion.k.st[ax.slot, L.S_P_CMD])
            motion.shift_positions(ax, -360.0 * math.floor(p / 360.0))
            motion.close_loop(ax)
            p = float(motion.k.st[ax.slot, L.S_P_CMD])
            motion.k.st[ax.slot, L.S_TARGET] = p  # it holds its position: in position there
            motion.log(
                Code.EV_ROTARY_MODE,
                ax.name,
                f"{ax.name} is the rotary axis {self.c_name} in position control at {p:.4f}°",
            )
            self.on_path(True)
            return
        self.on_path(False)
        if mode is SpindleMode.SPINDLE:
            if record and ax.gear != self.spindle_gear:
                ax.gear = self.spindle_gear
                push_params(motion.k, ax)
            motion.log(
                Code.EV_SPINDLE_MODE,
                ax.name,
                f"spindle mode: {self.c_name} is the spindle {ax.name}",
            )

    def _fail(self, ev: Event) -> None:
        """A job error of the changeover or the mode: the spindle brakes and is in error,
        in no mode, the block it ran for stops; a reset adopts the PLC's mode."""
        ax, sp = self.ax, self.sp
        c, self.change = self.change, None
        if c is not None:
            self.handshake.withdraw_request(c.request)
        self.mode = SpindleMode.NONE
        sp.motion.set_job_error(ax, ev)
        ax.sequence = None
        self.fail_block(ax)  # (a path it moved on is left first)
        self.on_path(False)
        ax.block_id, ax.motion = None, None
        sp.set_state(ax, AxisState.ERROR)
        if abs(float(sp.motion.k.st[ax.slot, L.S_V_CMD])) > 0.0:
            sp.motion.plan_velocity(ax, 0.0, sp.limits(ax))
