"""The owner of the axes' kernel rows: plans, state, job errors, the watchdog, the reference,
the enables; and the one place an axis' kernel events are handled.

Every other part (moves and jog, homing, the spindle) asks this service to plan, stop, fail
or watch instead of writing the kernel itself; it reads the kernel freely (`k`). Kernel
events are dispatched from `on_events` in one order: faults (lag, software limit), the
spindle's mode (loop opened or closed), the sequence the axis runs (`Axis.sequence`), and
last the end of a plain motion.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from nc_sim.axis.dynamics import Dynamics, Motion, emergency_limits, motion_dynamics
from nc_sim.axis.state import Axis
from nc_sim.axis.watchdog import bound_s, plan_s
from nc_sim.errors import Code
from nc_sim.events import Event, Log
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.profiles.plan import new_plan, position_move, velocity_change
from nc_sim.snapshot import AxisState
from nc_sim.units import AxisKind


@dataclass
class ChannelContext:
    """What the axes take from their channel: its HLI control units (override, feedhold,
    reduced_acceleration), the slope type in force (P-CHAN-00071, #SLOPE), the E-stop and
    whether G201 is in force (jog on the path's axes while it runs) [002 §2.6.2]."""

    units: dict[str, int]
    slope: int
    estop: bool = False
    parallel_manual: bool = False


def _no_mode_events(ax: Axis, ev: int) -> None:
    pass


class AxisMotion:
    """Plans, stops, fails and watches axes on a kernel; see the module docstring."""

    def __init__(
        self,
        k: Kernel,
        ctx: ChannelContext,
        log: Log,
        now: Callable[[], int],
        abort: Callable[[Axis], None],
    ) -> None:
        self.k = k
        self.ctx = ctx
        self.log = log
        self._now = now
        self._abort = abort  # the block an axis' motion belongs to ends with it
        # the spindle's reactions to its loop events, set by the spindle part
        self.mode_events: Callable[[Axis, int], None] = _no_mode_events

    # --- job errors and state -----------------------------------------------------------
    def fail(
        self,
        ax: Axis | None,
        code: Code,
        detail: str = "",
        *,
        m: int | None = None,
        gear: int | None = None,
        line: int | None = None,
        cause_kept: bool = False,
    ) -> Event:
        """Log a job error (of program `line`); with an axis it becomes that axis' active job
        error, unless `cause_kept` and the axis has one: a command refused because the axis
        is in error ("reset first") leaves the error that put it there as the one to read."""
        ev = self.log(code, ax.name if ax else "", detail, m=m, gear=gear, line=line)
        if ax is not None and not (cause_kept and ax.error_event is not None):
            self.set_job_error(ax, ev)
        return ev

    def set_job_error(self, ax: Axis, ev: Event | None) -> None:
        """The axis' active job error is this event's (None clears it)."""
        ax.error_event = ev
        self.k.ist[ax.slot, L.I_JOB_ERROR] = ax.job_error

    def set_state(self, ax: Axis, state: AxisState) -> None:
        """The axis' state; at standstill and in error no phase is watched."""
        ax.state = state
        self.k.ist[ax.slot, L.I_STATE] = int(state)
        if state in (AxisState.STANDSTILL, AxisState.ERROR):
            ax.deadline = None

    def monitor_speed(self, ax: Axis, on: bool) -> None:
        """Speed monitoring (speed reached, kenngr.vb_prozent) on or off."""
        self.k.ist[ax.slot, L.I_MON_ACTIVE] = int(on)

    def speed_goal(self, ax: Axis, v: float) -> None:
        """The speed (unit/s) the monitoring compares with."""
        self.k.st[ax.slot, L.S_V_GOAL] = v

    def show_override(self, ax: Axis, fraction: float) -> None:
        """The override in force, as the HLI shows and the recorder keeps it."""
        self.k.st[ax.slot, L.S_OVERRIDE] = fraction

    def check_motion(self, ax: Axis) -> Event | None:
        """The job error that forbids starting a single-axis motion now (the axis moves on
        the program's path, or `drive_refusal`), None when it may start."""
        if self.k.ist[ax.slot, L.I_ROLE] == L.ROLE_PATH_AXIS:
            return self.fail(ax, Code.AXIS_BUSY, f"{ax.name} moves on the program's path")
        return self.drive_refusal(ax)

    def drive_refusal(self, ax: Axis) -> Event | None:
        """Why the axis cannot move now (E-stop, error, enables, drive status), else None."""
        if self.ctx.estop:
            return self.fail(ax, Code.CHANNEL_ERROR_STATE, "emergency stop active", cause_kept=True)
        if ax.state is AxisState.ERROR:
            why = f"{ax.name} in error state"
            return self.fail(ax, Code.CHANNEL_ERROR_STATE, why, cause_kept=True)
        if not ax.enables_ok():
            return self.fail(
                ax, Code.NO_ENABLES, f"{ax.name} lacks {', '.join(ax.missing_enables())}"
            )
        not_ready = ax.drive.missing()
        if not_ready:  # enables set, but the drive has not (yet) reported ready [004 §4.2]
            return self.fail(
                ax, Code.DRIVE_NOT_READY, f"{ax.name} does not report {', '.join(not_ready)}"
            )
        return None

    def dynamics(self, ax: Axis, motion: Motion) -> Dynamics:
        """Accelerations and ramp times (with their sources) of a kind of motion with the
        axis' slope and the channel's reduced acceleration."""
        reduced = bool(self.ctx.units["reduced_acceleration"])
        return motion_dynamics(ax.cfg, ax.gear, motion, ax.slope, reduced)

    def limits(self, ax: Axis, motion: Motion) -> np.ndarray:
        """Planner limits of a kind of motion with the channel's slope and acceleration."""
        return self.dynamics(ax, motion).limits()

    # --- plans --------------------------------------------------------------------------
    def plan_move(self, ax: Axis, limits: np.ndarray, v_max: float, what: str = "") -> None:
        """Position plan to `ax.target` at up to `v_max`; at 0 (feedhold, override 0 %) a
        brake to a hold that keeps the target for later."""
        if v_max <= 0.0:
            self.plan_velocity(ax, 0.0, limits)
            self.unwatch(ax)  # held by the operator, not stuck
            return
        s = ax.slot
        st = self.k.st
        seg = new_plan()
        n = position_move(
            seg,
            st[s, L.S_P_CMD],
            st[s, L.S_V_CMD],
            st[s, L.S_A_CMD],
            ax.target,
            v_max,
            limits,
            self.k.cycle_s,
        )
        self.watch(ax, plan_s(seg, n), what)
        self.k.load_plan(s, seg, n, ax.target)
        if n == 0:  # already on the target at rest: no plan to finish, done at once
            self.on_events(ax, L.EV_PLAN_DONE)

    def plan_velocity(self, ax: Axis, v: float, limits: np.ndarray) -> None:
        """Planned speed change to `v` (unit/s)."""
        s = ax.slot
        st = self.k.st
        seg = new_plan()
        n = velocity_change(seg, 0, st[s, L.S_V_CMD], st[s, L.S_A_CMD], v, limits, self.k.cycle_s)
        self.watch(ax, plan_s(seg, n))
        self.k.load_plan(s, seg, n, math.nan)
        if n == 0:  # already at that speed: the kernel has no plan to finish, done at once
            self.on_events(ax, L.EV_PLAN_DONE)

    def follow_curve(self, ax: Axis, v: float) -> None:
        """Speed change to `v` along the acceleration curve of the gear record (the caller
        has bounded it with `watch`)."""
        self.k.load_curve(ax.slot, v)

    def stop(self, ax: Axis, limits: np.ndarray) -> None:
        """Brake to standstill."""
        # STOPPING first: an axis already at rest ends the stop within plan_velocity
        self.set_state(ax, AxisState.STOPPING)
        self.speed_goal(ax, 0.0)
        self.plan_velocity(ax, 0.0, limits)

    # --- watchdog -----------------------------------------------------------------------
    def watch(self, ax: Axis, expected_s: float, what: str = "", extend: bool = False) -> None:
        """Bound the phase starting now (expected to take `expected_s`, or that much longer
        with `extend`): unless it ended by then, it ends in job error 90023."""
        if ax.state is AxisState.ERROR:
            return  # the error reaction's braking: bounded by physics, nothing waits on it
        now = self._now()
        if extend and ax.deadline is not None:
            expected_s += (ax.deadline - now) * self.k.cycle_s
        bound = bound_s(expected_s)
        ax.deadline_what = what or ax.state.name.lower().replace("_", " ")
        ax.deadline_s = bound
        # a phase that can never end (no speed to search with) fails at once
        cycles = max(0, round(bound / self.k.cycle_s)) if math.isfinite(bound) else 0
        ax.deadline = now + cycles

    def unwatch(self, ax: Axis) -> None:
        """The phase may last: a steady state (rotation at speed) or a hold by the operator."""
        ax.deadline = None

    def check_deadline(self, ax: Axis) -> None:
        """A sequence that did not progress within its bound: job error, brake, in error."""
        if ax.deadline is None or self._now() < ax.deadline:
            return
        how = (
            f"did not end within {ax.deadline_s:g} s"
            if math.isfinite(ax.deadline_s)
            else "could never end"
        )
        self.fail(ax, Code.SEQUENCE_WATCHDOG, f"{ax.name}: {ax.deadline_what} {how}")
        self._abort(ax)
        self.drop_sequence(ax)
        ax.motion, ax.hold = None, False
        self.monitor_speed(ax, False)
        self.speed_goal(ax, 0.0)
        self.set_state(ax, AxisState.ERROR)
        self.plan_velocity(ax, 0.0, emergency_limits(ax.cfg, ax.gear))

    def drop_sequence(self, ax: Axis) -> None:
        """End the sequence the axis runs, if any, and the block that waits on it."""
        self.arm_zero_mark(ax, False)
        if ax.sequence is not None:
            ax.sequence = None
            self._abort(ax)

    # --- kernel events ------------------------------------------------------------------
    def take_events(self, ax: Axis) -> int:
        """The EV_* bits the kernel raised for the axis since the last call."""
        ev = int(self.k.ist[ax.slot, L.I_EVENTS])
        if ev:
            self.k.ist[ax.slot, L.I_EVENTS] = 0
        return ev

    def on_events(self, ax: Axis, ev: int) -> None:
        """Handle kernel events of an axis: faults, the spindle mode, its sequence, the end
        of a plain motion (see the module docstring)."""
        if ev & L.EV_LAG:
            lag = self.k.st[ax.slot, L.S_LAG]
            self.fail(ax, Code.LAG_MONITORING, f"{ax.name} lag {lag:.4f} {ax.pos_unit}")
            self.halt(ax)
            return
        if ev & L.EV_SWLIMIT and ax.state is not AxisState.ERROR:
            pos = self.k.st[ax.slot, L.S_P_CMD]
            self.fail(ax, Code.SOFTWARE_LIMIT, f"{ax.name} at {pos:.4f} {ax.pos_unit}")
            self._abort(ax)
            self.plan_velocity(ax, 0.0, emergency_limits(ax.cfg, ax.gear))
            self.set_state(ax, AxisState.ERROR)
        if ax.kind is AxisKind.SPINDLE:
            if ev & L.EV_SPEED_REACHED:
                self.log(Code.EV_SPEED_REACHED, ax.name)
            self.mode_events(ax, ev)
        if ev & L.EV_PLAN_DONE and ax.jog_on_path:  # G201: the jog on top of the path ended
            ax.jog_on_path = False
            return
        seq = ax.sequence
        if seq is not None and seq.on_event(ev):
            return
        if ev & L.EV_PLAN_DONE:
            self._plan_done(ax)

    def _plan_done(self, ax: Axis) -> None:
        if ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            self.unwatch(ax)  # at speed: endless rotation lasts until the next command
            return
        if ax.hold or ax.state in (AxisState.ERROR, AxisState.STANDSTILL, AxisState.HOMING):
            return  # (homing ends through its sequence)
        away = abs(self.k.st[ax.slot, L.S_P_CMD] - ax.target) > 1e-9
        if ax.state in (AxisState.MOVING, AxisState.JOG) and away:
            return  # braked to a hold at override 0 %: the move resumes with the override
        self.motion_done(ax)

    def motion_done(self, ax: Axis) -> None:
        """The motion has ended at standstill."""
        self.set_state(ax, AxisState.STANDSTILL)
        self.monitor_speed(ax, False)
        ax.motion, ax.block_id = None, None
        self.log(Code.EV_MOTION_DONE, ax.name)

    # --- reference and the spindle's loop -----------------------------------------------
    def forget_reference(self, ax: Axis) -> None:
        """Homing starts: not homed, no software limits until the reference is set."""
        ax.homed = False
        self.k.ist[ax.slot, L.I_HOMED] = 0
        if ax.kind is not AxisKind.SPINDLE:
            self.k.ist[ax.slot, L.I_LIMITS_ON] = 0

    def set_reference(self, ax: Axis, latched: float) -> None:
        """The position latched at the reference mark becomes kenngr.ref_pos: the encoder
        offset and every position of the row shift by the difference."""
        s = ax.slot
        self.shift_positions(ax, ax.cfg.eng("kenngr.ref_pos") - latched)
        ax.homed = True
        self.k.ist[s, L.I_HOMED] = 1
        if ax.kind is AxisKind.SPINDLE:
            self.arm_zero_mark(ax, False)
        else:
            self.k.ist[s, L.I_LIMITS_ON] = int(ax.kind is AxisKind.LINEAR)

    def shift_positions(self, ax: Axis, shift: float) -> None:
        """Every position of the axis' row moves by `shift` (the encoder offset with them):
        a new reference, or a rotary axis' position rebased into 0..360°."""
        s = ax.slot
        self.k.pr[s, L.P_ENC_OFFSET] += shift
        for col in (L.S_P_ACT, L.S_P_CMD, L.S_SEG_P0, L.S_TARGET):
            self.k.st[s, col] += shift

    def arm_zero_mark(self, ax: Axis, on: bool) -> None:
        """Report the encoder's zero mark (EV_CAM) while a spindle searches it."""
        self.k.ist[ax.slot, L.I_MARK_ARMED] = int(on)

    def arm_speed_control(self, ax: Axis, on: bool) -> None:
        """Change over to speed control above P-AXIS-00767 [001 §2.3]."""
        self.k.ist[ax.slot, L.I_SPEED_CTRL_ARMED] = int(on)

    def loop_mode(self, ax: Axis) -> int:
        """The kernel's loop mode (L.LOOP_*)."""
        return int(self.k.ist[ax.slot, L.I_OPEN_LOOP])

    def close_loop(self, ax: Axis) -> None:
        """Back to position control now."""
        self.k.ist[ax.slot, L.I_OPEN_LOOP] = L.LOOP_CLOSED

    def set_feedforward(self, ax: Axis, weight: float) -> None:
        """Feedforward weight 0..1 (G135-G137)."""
        self.k.pr[ax.slot, L.P_FF] = weight

    # --- enables, error reactions, emergency stop ---------------------------------------
    def enables_changed(self, ax: Axis) -> None:
        """Enables or drive status changed: the drive follows the NC only with both."""
        ax.drive.update(self._now(), bool(ax.units["DriveOn"]))
        ok = ax.drive_follows()
        self.k.ist[ax.slot, L.I_ENABLED] = int(ok)
        # a changeover waiting at standstill for the PLC goes on without them [003 §2.3]
        waiting = ax.state is AxisState.CHANGEOVER and self.k.ist[ax.slot, L.I_PLAN_N] == 0
        if not ok and ax.state not in (AxisState.STANDSTILL, AxisState.ERROR) and not waiting:
            self.k.ist[ax.slot, L.I_PLAN_N] = 0
            self.k.ist[ax.slot, L.I_CURVE] = 0
            self.monitor_speed(ax, False)
            self._abort(ax)
            ax.sequence = None
            lost = ax.missing_enables() + ax.drive.missing()  # enables, or the drive's status
            self.fail(ax, Code.ENABLES_LOST, f"{ax.name}: {', '.join(lost)} off")
            self.set_state(ax, AxisState.ERROR)

    def halt(self, ax: Axis) -> None:
        """Error reaction: servo off, axis in error, its block aborted."""
        self.k.ist[ax.slot, L.I_PLAN_N] = 0
        self.k.ist[ax.slot, L.I_ENABLED] = 0
        ax.servo_taken = ax.servo_taken or bool(ax.units["TorquePermission"])
        ax.units["TorquePermission"] = 0
        self._abort(ax)
        ax.motion, ax.sequence = None, None
        self.monitor_speed(ax, False)
        self.set_state(ax, AxisState.ERROR)

    def emergency_stop(self, ax: Axis, stop: Event) -> None:
        """Step-shaped braking at a_emergency, the axis in error with the E-stop's job error;
        at rest (or with the servo already off) its enables go at once."""
        moving = ax.state not in (AxisState.STANDSTILL, AxisState.ERROR)
        ax.motion, ax.hold, ax.sequence = None, False, None
        self.monitor_speed(ax, False)
        self.set_state(ax, AxisState.ERROR)
        self.set_job_error(ax, stop)
        if moving:
            self.plan_velocity(ax, 0.0, emergency_limits(ax.cfg, ax.gear))
            self.speed_goal(ax, 0.0)
        else:
            self.power_off(ax)

    def power_off(self, ax: Axis) -> None:
        """E-stop, stop category 1: once the axis has braked, the PLC takes its enables."""
        for u in ("DriveOn", "TorquePermission"):
            ax.units[u] = 0
        self.enables_changed(ax)

    def settled(self, ax: Axis) -> bool:
        """Braking has ended and the position loop has settled (lag inside
        kenngr.exact_stop_window; in speed control: the drive has stopped turning)."""
        s = ax.slot
        st, ist, pr = self.k.st, self.k.ist, self.k.pr
        if ist[s, L.I_PLAN_N] > 0:
            return False
        if ist[s, L.I_OPEN_LOOP] == L.LOOP_CLOSED:
            return bool(abs(st[s, L.S_LAG]) <= pr[s, L.P_INPOS_WIN])
        return bool(abs(st[s, L.S_V_ACT]) <= pr[s, L.P_INPOS_WIN])
