"""Spindle sequences [000 §2.3, §2.7, 001 §4.2]: M19, G74, a gear change, M5 with homing.

One `SpindleTask` per sequence, a `Sequence` (nc_sim/axis/state.py) advanced by kernel events:

    back to position control (decelerate to P-AXIS-00768 if the loop is open)
    -> zero mark (homing, or automatic homing before M19 on analogue drives)
    -> position plan to the target in the required direction -> exact stop
    -> gear change only: M4x to the PLC, its acknowledgement, the new gear record, resume
"""

from __future__ import annotations

import math
from enum import IntEnum
from functools import partial

from nc_sim.axis.params import changeover_speeds
from nc_sim.axis.plant import encoder_reading
from nc_sim.axis.state import Axis
from nc_sim.errors import Code
from nc_sim.kernel import layout as L
from nc_sim.plc import Waiter
from nc_sim.snapshot import AxisState
from nc_sim.spindle.gears import m_of
from nc_sim.spindle.interface import SpindleOps

V_EPS = 1e-9


def sign(x: float) -> int:
    return 1 if x > 0 else -1


class TaskPhase(IntEnum):
    DECEL = 1  # down to the switch-back speed before position control resumes
    SEEK_MARK = 2  # rotating until the zero mark passes (homing, automatic homing)
    POSITION = 3  # position plan to the target, then exact stop
    STOP = 4  # braking to standstill (gear change without positioning)
    WAIT_PLC = 5  # gear change: M40-M45 output, waiting for the PLC


class SpindleTask:
    """A spindle sequence in progress on one spindle."""

    def __init__(
        self,
        sp: SpindleOps,
        ax: Axis,
        kind: str,
        pos_deg: float,
        direction: int | None,
        speed: float,
        gear: int = 0,
        resume: tuple[int, float] | None = None,
    ) -> None:
        self.sp = sp
        self.ax = ax
        self.kind = kind  # "M19", "G74", "gear", "M5" (homing on the way after the control limit)
        self.pos_deg = pos_deg  # target angle 0..360
        self.direction = direction  # +1 M3, -1 M4, None = shortest way
        self.speed = speed  # positioning speed before override (°/s)
        self.phase = TaskPhase.DECEL
        self.gear = gear  # gear change: the new stage
        self.resume = resume  # gear change: (M3|M4, rpm) to run afterwards

    @property
    def _state(self) -> AxisState:
        if self.kind == "gear":
            return AxisState.GEAR_CHANGE
        return AxisState.HOMING if self.kind in ("G74", "M5") else AxisState.POSITIONING

    def advance(self) -> None:
        """Take the task to its next phase."""
        sp, ax = self.sp, self.ax
        motion = sp.motion
        st = motion.k.st[ax.slot]
        state = self._state
        sp.adopt_tool(ax)
        ax.speed_ctrl = False  # M19 and G74 run position-controlled [001 §2.3]
        motion.arm_speed_control(ax, False)
        v = st[L.S_V_CMD]
        mode = motion.loop_mode(ax)
        if mode != L.LOOP_CLOSED:
            # decelerate to the switch-back speed P-AXIS-00768 (and below the control limit)
            # before position control resumes [001 §4.2]
            v_close = min(
                changeover_speeds(ax.cfg)[1],
                ax.cfg.eng("getriebe.vb_regelgrenze", ax.gear) or math.inf,
            )
            if abs(v) > v_close + V_EPS or mode == L.LOOP_CONTROL_LIMIT:
                self.phase = TaskPhase.DECEL
                sp.set_state(ax, state)
                if abs(v) > v_close + V_EPS:
                    sp.velocity(ax, math.copysign(v_close, v))
                return  # the control limit closes in the kernel: EV_LOOP continues
            sp.switch_back(ax)
        if not ax.homed and (self.kind == "G74" or sp.auto_homing(ax)):
            self.phase = TaskPhase.SEEK_MARK
            motion.arm_zero_mark(ax, True)
            sp.set_state(ax, state)
            d = self.direction or (sign(v) if abs(v) > V_EPS else 1)
            v_seek = ax.cfg.eng("getriebe.vb_refmax", ax.gear)
            if v * d > V_EPS:  # already turning the right way: pass the mark at speed
                v_seek = max(v_seek, min(abs(v), self.speed * sp.override(ax)))
            sp.velocity(ax, d * v_seek)
            # the mark passes once per revolution
            motion.watch(ax, 360.0 / v_seek, "search for the zero mark", extend=True)
            return
        if self.kind == "M5":  # homed on the way: now brake to standstill
            self.phase = TaskPhase.STOP
            sp.set_state(ax, AxisState.STOPPING)
            sp.velocity(ax, 0.0)
            return
        if not ax.homed:
            motion.fail(
                ax,
                Code.SPINDLE_NOT_HOMED,
                f"{ax.name}: {self.kind} needs a reference",
                m=19 if self.kind == "M19" else None,
            )
            sp.cancel_task(ax)
            sp.velocity(ax, 0.0)
            sp.set_state(ax, AxisState.ERROR)
            return
        self.phase = TaskPhase.POSITION
        sp.set_state(ax, state)
        ax.target = sp.target(ax, self.pos_deg, self.direction)
        self._plan_position()

    def _plan_position(self) -> None:
        """Position plan to ax.target at the task speed × override."""
        sp, ax = self.sp, self.ax
        v_max = min(self.speed * sp.override(ax), sp.v_max(ax))
        sp.motion.show_override(ax, sp.override(ax))
        what = f"{self.kind}: positioning to {self.pos_deg:g}°"
        sp.motion.plan_move(ax, sp.limits(ax), v_max, what)

    def replan(self) -> bool:
        """Override changed: a positioning runs on at the new speed."""
        if self.phase is TaskPhase.POSITION:
            self._plan_position()
        return True

    def _latch_zero_mark(self) -> None:
        """The zero mark just passed: the position there becomes ref_pos."""
        ax = self.ax
        motion = self.sp.motion
        k = motion.k
        pr = k.pr[ax.slot]
        cam = pr[L.P_CAM_POS]
        x_edge = cam + round((k.st[ax.slot, L.S_X_MOTOR] - cam) / 360.0) * 360.0
        motion.set_reference(ax, encoder_reading(k, ax.slot, float(x_edge)))
        ax.reference_lost = False
        motion.log(Code.EV_HOMED, ax.name, f"{ax.name} reference at the zero mark")

    def _done(self) -> None:
        sp, ax = self.sp, self.ax
        if self.kind == "gear":
            self.phase = TaskPhase.WAIT_PLC
            sp.set_state(ax, AxisState.GEAR_CHANGE)
            sp.handshake.output(
                m_of(self.gear),
                ax.name,
                Waiter(
                    partial(sp.gears.acknowledged, ax), partial(sp.gears.timed_out, ax), ax.name
                ),
                self.gear,
            )
            # the PLC's own timeout (90004) ends it first; this bounds it as every phase
            timeout = sp.cfg.channel_eng("plc.m_ack_timeout")
            sp.motion.watch(ax, timeout, f"gear change: M{m_of(self.gear)} acknowledgement")
            return
        ax.sequence = None
        sp.set_state(ax, AxisState.STANDSTILL)
        ax.motion, ax.block_id = None, None
        if self.kind == "M5":
            sp.motion.log(Code.EV_MOTION_DONE, ax.name, f"{ax.name} stopped (M5)", m=5)
            return
        sp.motion.log(
            Code.EV_IN_POSITION,
            ax.name,
            f"{ax.name} at {self.pos_deg:g}° ({self.kind})",
            m=19 if self.kind == "M19" else None,  # the in-position that ends M19 [000 §2.3]
            value=self.pos_deg,
        )

    def on_event(self, ev: int) -> bool:
        """Advance on the loop closing, the zero mark, the end of a plan, the exact stop;
        every event of the spindle is the task's while it runs."""
        ax, motion = self.ax, self.sp.motion
        closed = ev & L.EV_LOOP and motion.loop_mode(ax) == L.LOOP_CLOSED
        if closed and self.phase is TaskPhase.DECEL:
            self.advance()
            if ax.sequence is not self:
                return False
        if ev & L.EV_CAM and self.phase is TaskPhase.SEEK_MARK:
            self._latch_zero_mark()
            self.advance()
            return True
        if ev & L.EV_PLAN_DONE:
            if self.phase is TaskPhase.DECEL and motion.loop_mode(ax) != L.LOOP_CONTROL_LIMIT:
                self.advance()
                return True
            elif self.phase is TaskPhase.STOP:
                self._done()
        if ev & L.EV_IN_POS and self.phase is TaskPhase.POSITION:
            self._done()
        return True
