"""One simulated machine: a channel with axes and spindles, its HLI and its PLC.

The Python layer of the NC: `submit` takes a command (nc_sim/commands.py) and answers with its
outcome; commands check their preconditions and either plan a motion for the kernel or end as
a job error; kernel events (plan done, lag, limits, cam) drive the sequences (homing, blocks)
forward. Every phase of a sequence carries a deadline from its own
parameters (`watchdog.py`): past it, job error 90023 instead of a hang. Nothing here reads a
clock: time is `cycle · cycle_s`.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import assert_never

import numpy as np

from nc_sim import hli
from nc_sim.axis.drive import READY_FOR_POWER_ON
from nc_sim.axis.dynamics import (
    Motion,
    emergency_limits,
    feedhold_limits,
    motion_limits,
    velocity_limit,
)
from nc_sim.axis.params import power_on, push_params
from nc_sim.axis.state import Axis, HomingPhase, ToolLimits, drive_status
from nc_sim.axis.watchdog import bound_s, plan_s, search_s
from nc_sim.blocks import Block, BlockError, parse_block
from nc_sim.channel.canon import ListSink
from nc_sim.channel.interpreter import interpret
from nc_sim.channel.state import ChannelProgress, LoadedProgram
from nc_sim.channel.words import ProgramError
from nc_sim.commands import (
    Accepted,
    Command,
    CycleStart,
    EmergencyStop,
    Feedhold,
    GearChange,
    HliWrite,
    Home,
    Invalid,
    JogStart,
    JogStep,
    JogStop,
    Mdi,
    Move,
    Outcome,
    PlcAck,
    ProgramLoad,
    ProgramStop,
    Refused,
    Reset,
    SingleBlock,
    SpindlePosition,
    SpindleRun,
)
from nc_sim.commands import (
    PlcMode as SetPlcMode,  # the command; nc_sim.plc.PlcMode is the PLC's behaviour
)
from nc_sim.errors import MESSAGES, Code, NcUsageError, is_error
from nc_sim.events import EVENT_LOG_LEN, OUTCOME_LOG_LEN, Event, EventLog
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.machine.config import MachineConfig
from nc_sim.machine.readout import machine_snapshot
from nc_sim.plc import Handshake, PlcMode, SimPlc, Waiter
from nc_sim.profiles.plan import new_plan, position_move, velocity_change
from nc_sim.snapshot import AxisState, MachineSnapshot
from nc_sim.spindle.control import SpindleControl
from nc_sim.units import AxisKind, Quantity, feed_per_min, to_eng

_FAR = 1e9  # jog target of a spindle (a modulo axis: no position range)
# positions the NC represents: SGN32 in 0.1 µm | 0.0001° (the range of P-AXIS-00177/00178);
# an unhomed axis may go anywhere within it, a target beyond it is meaningless (90003)
POSITION_RANGE = to_eng(Quantity.POSITION, 2**31 - 1)


@dataclass
class _BlockRun:
    id: int
    text: str
    block: Block | None = None
    started: bool = False
    waiting_m: int = 0
    homing: list[list[str]] = field(default_factory=list)  # G74 order groups still to start
    error: Event | None = None  # the job error it failed with while starting


class Machine:
    """A channel with its axes on a shared kernel."""

    def __init__(self, cfg: MachineConfig, kernel: Kernel) -> None:
        if abs(cfg.cycle_s - kernel.cycle_s) > 1e-12:
            raise NcUsageError("machine cycle time differs from the kernel's")
        self.cfg = cfg
        self.k = kernel
        self.cycle = 0
        slots = kernel.claim(len(cfg.axes))
        self.axes = [
            Axis(a, s, drive=drive_status(a, cfg.cycle_s))
            for a, s in zip(cfg.axes, slots, strict=True)
        ]
        self.by_name = {a.name: a for a in self.axes}
        self.main_spindle = cfg.main_spindle
        self.channel_units = hli.channel_units()
        self.slope = int(cfg.channel_raw("prog_start.slope.profile"))
        self.events: EventLog[Event] = EventLog(EVENT_LOG_LEN)  # bounded, read by cursor
        self.plc = SimPlc(self._cycles(cfg.channel_eng("plc.m_ack_delay")))
        # the timeout is read once here and in refresh_params: the cycle boundary runs often
        self.handshake = Handshake(
            self.plc,
            self._cycles(cfg.channel_eng("plc.m_ack_timeout")),
            kernel.cycle_s,
            self.log,
            lambda: self.cycle,
        )
        self._queue: deque[_BlockRun] = deque()
        self._next_id = 1
        self.outcomes: EventLog[Outcome] = EventLog(OUTCOME_LOG_LEN)  # answers to submit
        self.estop = False
        self._powered = False  # power-on done: the PLC has switched every drive on
        self.sp = SpindleControl(self)
        self.channel = ChannelProgress(slope=self.slope)
        for ax in self.axes:
            ax.gear = int(ax.cfg.raw("kenngr.getriebe_stufe")) if ax.cfg.is_spindle else 1
            push_params(kernel, ax)
            power_on(kernel, ax)

    # --- the command surface -----------------------------------------------------------
    def submit(self, cmd: Command) -> Outcome:
        """Carry out one command (nc_sim.commands) and answer with its outcome; the one way
        in for the HMI, scenarios and tests. Never raises for a bad command: misuse (unknown
        axis, not a spindle, unknown HLI unit, a value out of range) is `Invalid`, as a
        process boundary carries answers, not exceptions. Every outcome is also kept in
        `outcomes`."""
        try:
            outcome = self._dispatch(cmd)
        except NcUsageError as e:
            outcome = Invalid(cmd.serial, str(e))
        self.outcomes.append(outcome)
        return outcome

    def _dispatch(self, cmd: Command) -> Outcome:
        answer: Event | int | None = None
        match cmd:
            case Mdi():
                return self._mdi(cmd.block, cmd.serial)
            case ProgramLoad():
                return self._program_load(cmd.name, cmd.text, cmd.serial)
            case CycleStart() | ProgramStop():
                answer = self._fail(
                    None, Code.CHANNEL_ERROR_STATE, "program execution is not available yet"
                )
            case Feedhold():
                self._channel_unit("feedhold", int(cmd.on))
            case SingleBlock():
                self.channel.single_block = cmd.on
            case SpindleRun():
                answer = self._spindle_run(cmd.spindle, cmd.m, cmd.speed_rpm)
            case SpindlePosition():
                answer = self._spindle_position(
                    cmd.spindle, cmd.position_deg, cmd.direction, cmd.speed_rpm
                )
            case GearChange():
                answer = self._spindle_gear(cmd.spindle, cmd.m)
            case Home():
                answer = self._home(cmd.axis)
            case JogStart():
                answer = self._jog_start(cmd.axis, cmd.direction, cmd.feed_mm_min)
            case JogStop():
                self._jog_stop(cmd.axis)
            case JogStep():
                answer = self._jog_step(cmd.axis, cmd.distance, cmd.feed_mm_min)
            case Move():
                answer = self._move(cmd.axis, cmd.target, cmd.rapid, cmd.feed_mm_min)
            case HliWrite():
                self._hli_write(cmd.unit, cmd.value, cmd.axis)
            case SetPlcMode():
                self._plc_mode(cmd.mode, cmd.delay_s)
            case PlcAck():
                answer = self.handshake.acknowledge(cmd.m)
            case Reset():
                self._reset()
            case EmergencyStop():
                self._emergency_stop()
            case _:  # a new command type must get its case here (mypy checks)
                assert_never(cmd)
        if isinstance(answer, Event):
            return Refused(cmd.serial, answer)
        return Accepted(cmd.serial, self.cycle, acknowledged=answer)

    # --- time ---------------------------------------------------------------------------
    def _cycles(self, seconds: float) -> int:
        return max(0, round(seconds / self.k.cycle_s))

    @property
    def t_s(self) -> float:
        return self.cycle * self.k.cycle_s

    def next_wakeup(self) -> int | None:
        """The next cycle at which the machine must act without a kernel event."""
        times = [self.plc.power_on_cycle] if self.cycle < self.plc.power_on_cycle else []
        times += [c for ax in self.axes if (c := ax.drive.next_change()) is not None]
        due = self.handshake.next_wakeup()
        if due is not None:
            times.append(due)
        times += [ax.deadline for ax in self.axes if ax.deadline is not None]
        if self.estop and any(ax.enables_ok() for ax in self.axes):
            times.append(self.cycle + 1)  # watch the braking axes settle (_estop_settled)
        return min(times) if times else None

    def refresh_params(self) -> None:
        """Re-read the configuration after a parameter change (values that apply now)."""
        self.plc.delay_cycles = self._cycles(self.cfg.channel_eng("plc.m_ack_delay"))
        self.handshake.timeout_cycles = self._cycles(self.cfg.channel_eng("plc.m_ack_timeout"))
        for ax in self.axes:
            push_params(self.k, ax)

    @property
    def powered(self) -> bool:
        """Power-on is done and every drive is still switched on, reports ready and has its
        enables, so the machine can move (the moment the headless runner calls time 0).
        Live, not latched: false as soon as an E-stop or the PLC takes a drive's enables."""
        return self._powered and all(ax.drive_follows() for ax in self.axes)

    def snapshot(self) -> MachineSnapshot:
        """Everything a status shows about the machine now, as plain values in engineering
        units (nc_sim/snapshot.py); its events are read from `events` by cursor."""
        return machine_snapshot(self)

    @property
    def queued_blocks(self) -> int:
        """MDI blocks waiting or running."""
        return len(self._queue)

    # --- events -------------------------------------------------------------------------
    def log(
        self,
        code: Code,
        axis: str = "",
        detail: str = "",
        *,
        m: int | None = None,
        gear: int | None = None,
        line: int | None = None,
        column: int | None = None,
    ) -> Event:
        """Record an error (its meaning, then the detail) or an event (its detail, which
        reads as a message of its own, else the meaning), numbered by the event log, with
        the M function and gear stage it concerns as fields."""
        msg = MESSAGES[code]
        if detail:
            msg = f"{msg}: {detail}" if is_error(code) else detail
        ev = Event(
            seq=self.events.cursor,
            cycle=self.cycle,
            t_s=self.t_s,
            axis=axis,
            code=int(code),
            message=msg,
            m=m,
            gear=gear,
            line=line,
            column=column,
        )
        self.events.append(ev)
        return ev

    def _fail(
        self,
        ax: Axis | None,
        code: Code,
        detail: str = "",
        *,
        m: int | None = None,
        gear: int | None = None,
    ) -> Event:
        ev = self.log(code, ax.name if ax else "", detail, m=m, gear=gear)
        if ax is not None:
            self._set_job_error(ax, ev)
        return ev

    def _set_job_error(self, ax: Axis, ev: Event | None) -> None:
        """The axis' active job error is this event's (None clears it)."""
        ax.error_event = ev
        self.k.ist[ax.slot, L.I_JOB_ERROR] = ax.job_error

    # --- lookup -------------------------------------------------------------------------
    def axis(self, name: str) -> Axis:
        """Axis by name; the main spindle also answers to S."""
        if name == "S" and self.main_spindle:
            name = self.main_spindle
        ax = self.by_name.get(name)
        if ax is None:
            raise NcUsageError(f"no axis or spindle '{name}'")
        return ax

    # --- motion primitives --------------------------------------------------------------
    def _set_state(self, ax: Axis, state: AxisState) -> None:
        ax.state = state
        self.k.ist[ax.slot, L.I_STATE] = int(state)
        if state in (AxisState.STANDSTILL, AxisState.ERROR):
            ax.deadline = None

    # --- watchdog -----------------------------------------------------------------------
    def _watch(self, ax: Axis, expected_s: float, what: str = "", extend: bool = False) -> None:
        """Bound the phase starting now (expected to take `expected_s`, or that much longer
        with `extend`): unless it ended by then, it ends in job error 90023."""
        if ax.state is AxisState.ERROR:
            return  # the error reaction's braking: bounded by physics, nothing waits on it
        if extend and ax.deadline is not None:
            expected_s += (ax.deadline - self.cycle) * self.k.cycle_s
        bound = bound_s(expected_s)
        ax.deadline_what = what or ax.state.name.lower().replace("_", " ")
        ax.deadline_s = bound
        # a phase that can never end (no speed to search with) fails at once
        ax.deadline = self.cycle + self._cycles(bound) if math.isfinite(bound) else self.cycle

    def _unwatch(self, ax: Axis) -> None:
        """The phase may last: a steady state (rotation at speed) or a hold by the operator."""
        ax.deadline = None

    def _watchdog_expired(self, ax: Axis) -> None:
        """A sequence did not progress within its bound: job error, brake, axis in error."""
        how = (
            f"did not end within {ax.deadline_s:g} s"
            if math.isfinite(ax.deadline_s)
            else "could never end"
        )
        self._fail(ax, Code.SEQUENCE_WATCHDOG, f"{ax.name}: {ax.deadline_what} {how}")
        self._abort_block(ax)
        if ax.kind is AxisKind.SPINDLE:
            self.sp.cancel_task(ax)
        ax.task, ax.motion, ax.hold, ax.homing = None, None, False, HomingPhase.NONE
        self.k.ist[ax.slot, L.I_MON_ACTIVE] = 0
        self.k.st[ax.slot, L.S_V_GOAL] = 0.0
        self._set_state(ax, AxisState.ERROR)
        self._plan_velocity(ax, 0.0, emergency_limits(ax.cfg, ax.gear))

    def _as_axis(self, ax: Axis) -> bool:
        """Moves like an axis: a linear axis, or a spindle jogged or moved as a rotary axis
        [003 "jogging a spindle"]; then feed override, feedhold and G200 dynamics apply."""
        return ax.kind is not AxisKind.SPINDLE or ax.state in (AxisState.MOVING, AxisState.JOG)

    def _override(self, ax: Axis, motion: Motion | None) -> float:
        """Override in force as a fraction: the spindle override in spindle mode, the
        channel (feed) override for axes and for a spindle moving as a rotary axis."""
        if not self._as_axis(ax):
            return self.sp.override(ax)
        cap = self.cfg.channel_eng("max_vb_override")
        return min(self.channel_units["override"] * 1e-3, cap)

    def _limits(self, ax: Axis, motion: Motion) -> np.ndarray:
        reduced = bool(self.channel_units["reduced_acceleration"])
        return motion_limits(ax.cfg, ax.gear, motion, ax.slope, reduced)

    def _vmax(self, ax: Axis, motion: Motion) -> float:
        v = velocity_limit(ax.cfg, ax.gear, motion, ax.feed) * self._override(ax, motion)
        if ax.units["reduced_speed"]:
            red = ax.cfg.eng(
                "getriebe.rapid_speed_red" if motion is Motion.RAPID else "getriebe.vb_max_red",
                ax.gear,
            ) or ax.cfg.eng("getriebe.vb_max_red", ax.gear)
            if red > 0:
                v = min(v, red)
        return v

    def _plan_move(self, ax: Axis, limits: np.ndarray, v_max: float) -> None:
        if v_max <= 0.0:  # feedhold or override 0 %: brake and hold, keep the target for later
            self._plan_velocity(ax, 0.0, limits)
            self._unwatch(ax)  # held by the operator, not stuck
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
        self._watch(ax, plan_s(seg, n))
        self.k.load_plan(s, seg, n, ax.target)
        if n == 0:  # already on the target at rest: no plan to finish, done at once
            self._axis_events(ax, L.EV_PLAN_DONE)

    def _plan_velocity(self, ax: Axis, v: float, limits: np.ndarray) -> None:
        s = ax.slot
        st = self.k.st
        seg = new_plan()
        n = velocity_change(seg, 0, st[s, L.S_V_CMD], st[s, L.S_A_CMD], v, limits, self.k.cycle_s)
        self._watch(ax, plan_s(seg, n))
        self.k.load_plan(s, seg, n, math.nan)
        if n == 0:  # already at that speed: the kernel has no plan to finish, done at once
            self._axis_events(ax, L.EV_PLAN_DONE)

    def _replan(self, ax: Axis) -> None:
        """Re-plan the active motion from the current state (override, feedhold release)."""
        if not self._as_axis(ax):
            self.sp.replan(ax)
            return
        if ax.motion is None or ax.state in (AxisState.STOPPING, AxisState.ERROR):
            return
        if ax.hold or self.channel_units["feedhold"]:
            return
        if ax.homing in (HomingPhase.TO_CAM, HomingPhase.OFF_CAM):  # a search has no target
            self._homing_search(ax, ax.homing)
            return
        self._plan_move(ax, self._limits(ax, ax.motion), self._vmax(ax, ax.motion))

    def _check_motion(self, ax: Axis) -> Event | None:
        if self.estop:
            return self._fail(ax, Code.CHANNEL_ERROR_STATE, "emergency stop active")
        if ax.state is AxisState.ERROR:
            return self._fail(ax, Code.CHANNEL_ERROR_STATE, f"{ax.name} in error state")
        if not ax.enables_ok():
            return self._fail(
                ax, Code.NO_ENABLES, f"{ax.name} lacks {', '.join(ax.missing_enables())}"
            )
        not_ready = ax.drive.missing()
        if not_ready:  # enables set, but the drive has not (yet) reported ready [004 §4.2]
            return self._fail(
                ax, Code.DRIVE_NOT_READY, f"{ax.name} does not report {', '.join(not_ready)}"
            )
        return None

    def _within_limits(self, ax: Axis, target: float) -> Event | None:
        if ax.kind is AxisKind.SPINDLE:
            return None
        if not ax.homed:  # no software limits yet, but no target beyond what the NC represents
            lo, hi = -POSITION_RANGE, POSITION_RANGE
        else:
            lo, hi = self.k.pr[ax.slot, L.P_SWE_NEG], self.k.pr[ax.slot, L.P_SWE_POS]
        if not lo - 1e-9 <= target <= hi + 1e-9:
            u = ax.pos_unit
            return self._fail(
                ax,
                Code.SOFTWARE_LIMIT,
                f"{ax.name} target {target:.4f} {u} outside {lo:.4f} … {hi:.4f} {u}",
            )
        return None

    def _start_move(
        self,
        ax: Axis,
        target: float,
        motion: Motion,
        feed: float | None,
        block_id: int | None = None,
        state: AxisState = AxisState.MOVING,
    ) -> Event | None:
        err = self._check_motion(ax) or self._within_limits(ax, target)
        if err is None and ax.kind is AxisKind.SPINDLE:
            err = self.sp.as_rotary_axis(ax)
        if err:
            return err
        ax.target, ax.motion, ax.feed, ax.block_id = target, motion, feed, block_id
        ax.slope = self.slope if motion is not Motion.MANUAL else 1
        if motion is Motion.FEED and not feed:
            return self._fail(ax, Code.FEED_MISSING)
        self._set_state(ax, state)
        self._replan(ax)
        return None

    # --- commands: axes -----------------------------------------------------------------
    def _move(
        self, axis: str, target: float, rapid: bool = True, feed_mm_min: float | None = None
    ) -> Event | None:
        """Single-axis G00/G01 move to an absolute position (mm | °); a spindle moves as a
        modulo rotary axis to the angle, the shortest way."""
        ax = self.axis(axis)
        err = self._homing_required(ax)
        if err:
            return err
        feed = feed_mm_min / 60.0 if feed_mm_min else None
        if ax.kind is AxisKind.SPINDLE:
            target = self.sp.target(ax, target % 360.0, None)
        return self._start_move(ax, target, Motion.RAPID if rapid else Motion.FEED, feed)

    def _jog_start(
        self, axis: str, direction: int, feed_mm_min: float | None = None
    ) -> Event | None:
        """Continuous jog (G200 dynamics) towards the software limit until `jog_stop`."""
        ax = self.axis(axis)
        d = 1.0 if direction > 0 else -1.0
        if ax.kind is AxisKind.SPINDLE:
            target = self.k.st[ax.slot, L.S_P_CMD] + d * _FAR
        elif ax.homed:
            target = self.k.pr[ax.slot, L.P_SWE_POS if d > 0 else L.P_SWE_NEG]
        else:  # towards the end of the position range: far, but a move that ends
            target = d * POSITION_RANGE
        feed = feed_mm_min / 60.0 if feed_mm_min else None
        err = self._jog_feed_refused(ax, feed)
        if err:
            return err
        return self._start_move(ax, target, Motion.MANUAL, feed, state=AxisState.JOG)

    def _jog_feed_refused(self, ax: Axis, feed: float | None) -> Event | None:
        """A jog feed above the axis' G200 maximum (P-AXIS-00213) is refused naming that
        limit [002 §2.6.1], not silently cut to it."""
        v_max = ax.cfg.eng("handbetrieb.hb.vb_max")
        if feed is None or feed <= v_max * (1 + 1e-12):
            return None
        f, unit = feed_per_min(feed, ax.kind)
        lim, _ = feed_per_min(v_max, ax.kind)
        return self._fail(
            ax,
            Code.JOG_FEED_TOO_HIGH,
            f"{ax.name} jog feed {round(f, 4):.10g} {unit} is above the manual-mode maximum "
            f"{round(lim, 4):.10g} {unit} (handbetrieb.hb.vb_max, P-AXIS-00213)",
        )

    def _homing_required(self, ax: Axis) -> Event | None:
        """P-AXIS-00277: a programmed motion (G00/G01, `move`) of an unhomed axis is refused
        with 90013; jogging and homing stay possible."""
        if ax.homed or not ax.cfg.flag("kenngr.prog_move_requires_homing"):
            return None
        return self._fail(ax, Code.NOT_HOMED, f"{ax.name} is not homed (P-AXIS-00277): G74 first")

    def _jog_stop(self, axis: str) -> None:
        """Release of the jog key: brake with the manual-mode deceleration."""
        ax = self.axis(axis)
        if ax.state is AxisState.JOG:
            self._stop(ax, self._limits(ax, Motion.MANUAL))

    def _jog_step(
        self, axis: str, distance: float, feed_mm_min: float | None = None
    ) -> Event | None:
        """Incremental jog by `distance` (mm | °) with G200 dynamics."""
        ax = self.axis(axis)
        if ax.state is not AxisState.STANDSTILL:
            return self._fail(ax, Code.AXIS_BUSY)
        target = self.k.st[ax.slot, L.S_P_CMD] + distance
        feed = feed_mm_min / 60.0 if feed_mm_min else None
        return self._jog_feed_refused(ax, feed) or self._start_move(ax, target, Motion.MANUAL, feed)

    def _home(self, axis: str, block_id: int | None = None) -> Event | None:
        """CNC-controlled homing G74: to the cam, off it slowly, zero at the edge, to ref_pos."""
        ax = self.axis(axis)
        if ax.kind is AxisKind.SPINDLE:
            return self.sp.home(ax, block_id)
        err = self._check_motion(ax)
        if err:
            return err
        ax.motion, ax.block_id, ax.slope, ax.homed = Motion.HOMING, block_id, 1, False
        self.k.ist[ax.slot, L.I_HOMED] = 0
        self.k.ist[ax.slot, L.I_LIMITS_ON] = 0
        self._set_state(ax, AxisState.HOMING)
        d = 1.0 if ax.cfg.flag("kenngr.ref_richt") else -1.0
        on_cam = bool(self.k.ist[ax.slot, L.I_CAM]) == (d > 0)
        self._homing_search(ax, HomingPhase.OFF_CAM if on_cam else HomingPhase.TO_CAM)
        return None

    def _homing_search(self, ax: Axis, phase: HomingPhase) -> None:
        """To the cam at vb_refmax, or off it at vb_reflow; also resumes after a feedhold."""
        d = 1.0 if ax.cfg.flag("kenngr.ref_richt") else -1.0
        ax.homing = phase
        if phase is HomingPhase.TO_CAM:
            v, what = d * ax.cfg.eng("getriebe.vb_refmax", ax.gear), "search for the cam"
        else:
            v, what = -d * ax.cfg.eng("getriebe.vb_reflow", ax.gear), "leaving the cam"
        self._plan_velocity(ax, v, self._limits(ax, Motion.HOMING))
        # the cam lies within the travel: a search over the whole of it finds it
        self._watch(ax, search_s(self._travel(ax), abs(v)), f"homing: {what}", extend=True)

    def _travel(self, ax: Axis) -> float:
        """Length of the travel between the software limits (mm)."""
        return float(self.k.pr[ax.slot, L.P_SWE_POS] - self.k.pr[ax.slot, L.P_SWE_NEG])

    def _homing_edge(self, ax: Axis) -> None:
        """Cam edge with zero pulse: the position here becomes ref_pos."""
        s = ax.slot
        pr = self.k.pr
        # the zero pulse latches the position at the edge itself, not one cycle later
        latched = (
            pr[s, L.P_ENC_SIGN] * pr[s, L.P_SIGN_FB] * pr[s, L.P_CAM_POS] + pr[s, L.P_ENC_OFFSET]
        )
        shift = ax.cfg.eng("kenngr.ref_pos") - latched
        self.k.pr[s, L.P_ENC_OFFSET] += shift
        for col in (L.S_P_ACT, L.S_P_CMD, L.S_SEG_P0):
            self.k.st[s, col] += shift
        ax.homed = True
        self.k.ist[s, L.I_HOMED] = 1
        self.k.ist[s, L.I_LIMITS_ON] = int(ax.kind is AxisKind.LINEAR)
        ax.homing = HomingPhase.TO_REF
        ax.target = ax.cfg.eng("kenngr.ref_pos")
        ax.feed = ax.cfg.eng("getriebe.vb_reflow", ax.gear)
        self._plan_move(ax, self._limits(ax, Motion.HOMING), ax.feed)

    def _stop(self, ax: Axis, limits: np.ndarray) -> None:
        if not self._as_axis(ax):
            self.sp.stop(ax)
            return
        # STOPPING first: an axis already at rest ends the stop within _plan_velocity
        self._set_state(ax, AxisState.STOPPING)
        self.k.st[ax.slot, L.S_V_GOAL] = 0.0
        self._plan_velocity(ax, 0.0, limits)

    # --- commands: spindle [000] ---------------------------------------------------------
    def _spindle(self, name: str) -> Axis:
        ax = self.axis(name)
        if ax.kind is not AxisKind.SPINDLE:
            raise NcUsageError(f"{name} is not a spindle")
        return ax

    def spindle_index(self, ax: Axis) -> int | None:
        """Index i of spindel[i] in the channel list for this spindle."""
        for i in range(6):
            if self.cfg.channel.get(f"spindel[{i}].bezeichnung") == ax.name:
                return i
        return None

    def _spindle_run(self, name: str, m: int, speed_rpm: float | None = None) -> Event | None:
        """M3/M4 with speed (rpm), or M5."""
        ax = self._spindle(name)
        if m == 5:
            self.sp.m5(ax)
            return None
        return self.sp.endless(ax, m, speed_rpm)

    def _spindle_position(
        self,
        name: str,
        pos_deg: float,
        direction: int | None = None,
        speed_rpm: float | None = None,
    ) -> Event | None:
        """M19 S.POS=pos_deg with M3 (+1) / M4 (-1) or the shortest way (None)."""
        return self.sp.position(self._spindle(name), pos_deg, direction, speed_rpm)

    def _spindle_gear(self, name: str, m: int) -> Event | None:
        """M40-M45: change gear stage (main spindle with P-CHAN-00052)."""
        if not 40 <= m <= 45:
            raise NcUsageError("gear stage M40..M45")
        ax = self._spindle(name)
        if not self.gear_change_enabled:  # then M40-M45 are free M functions
            self._m_output(m, "", None)
            return None
        return self.sp.gear_only(ax, m - 39, None)

    @property
    def gear_change_enabled(self) -> bool:
        """P-CHAN-00052: M40-M45 change the main spindle's gear; else they are free M functions."""
        return bool(self.cfg.channel_raw("main_spindle_gear_change"))

    def _tool(self, number: int) -> None:
        """D word: the tool's dynamic limits go to its spindle at the next start [000 §2.8.5]."""
        pre = f"wz[{number}]."
        nr = int(self.cfg.tools.get(pre + "log_ax_nr_spdl", 0))
        self.log(Code.EV_TOOL_DYNAMICS, "", f"D{number}")
        if nr == 0:  # the tool carries no spindle dynamics
            return
        target = None
        for ax in self.axes:
            if ax.kind is AxisKind.SPINDLE and int(ax.cfg.raw("kopf.achs_nr")) == nr:
                target = ax
        if target is None:
            return
        vb_max = self.cfg.tool_eng(pre + "vb_max")
        a_max = self.cfg.tool_eng(pre + "a_max")
        target.tool_pending = ToolLimits(self.cfg.tool_eng(pre + "vb_min"), vb_max, a_max)

    def _program_end(self) -> None:
        """M30/M2: spindles stop only with the HLI flag "spindle stop at program end"."""
        self.log(Code.EV_PROGRAM_END)
        for ax in self.axes:
            if ax.kind is AxisKind.SPINDLE and ax.units["spindle_stop_at_program_end"]:
                self.sp.stop(ax)

    # --- HLI ----------------------------------------------------------------------------
    def _hli_write(self, unit: str, value: int, axis: str | None = None) -> None:
        """Write a control unit of the channel (axis=None) or of an axis."""
        if axis is None:
            hli.channel_write(unit, value)
            self._channel_unit(unit, int(value))
            return
        ax = self.axis(axis)
        value = hli.axis_write(unit, value)
        if unit == "spindle_reset" and value:
            self._reset_axis(ax)
            return
        ax.units[unit] = int(value)
        self.log(Code.EV_HLI, ax.name, f"{unit} = {int(value)}")
        if unit in ("DriveOn", "TorquePermission", "ReleaseFeedhold"):
            self._enables_changed(ax)
        elif unit in ("override", "override_valid", "reduced_speed"):
            self._replan(ax)

    def _channel_unit(self, unit: str, value: int) -> None:
        old = self.channel_units[unit]
        self.channel_units[unit] = hli.clamp(unit, value)
        self.log(Code.EV_HLI, "", f"channel {unit} = {value}")
        if unit == "feedhold" and value and not old:
            use_set = bool(self.cfg.channel_raw("use_drive_curr_limit"))
            for ax in self.axes:
                if (
                    self._as_axis(ax)
                    and ax.state in (AxisState.MOVING, AxisState.JOG, AxisState.HOMING)
                    and ax.motion is not None
                ):
                    ax.hold = True
                    lim = feedhold_limits(ax.cfg, ax.gear, ax.motion, ax.slope, use_set)
                    self._plan_move(ax, lim, 0.0)
        elif unit == "feedhold" and not value and old:
            for ax in self.axes:
                if ax.hold:
                    ax.hold = False
                    self._replan(ax)
        else:
            for ax in self.axes:
                if self._as_axis(ax):
                    self._replan(ax)

    def _enables_changed(self, ax: Axis) -> None:
        """Enables or drive status changed: the drive follows the NC only with both."""
        ax.drive.update(self.cycle, bool(ax.units["DriveOn"]))
        ok = ax.drive_follows()
        self.k.ist[ax.slot, L.I_ENABLED] = int(ok)
        if not ok and ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
            self.k.ist[ax.slot, L.I_PLAN_N] = 0
            self.k.ist[ax.slot, L.I_CURVE] = 0
            self.k.ist[ax.slot, L.I_MON_ACTIVE] = 0
            self._abort_block(ax)
            ax.task = None
            self._fail(ax, Code.ENABLES_LOST, f"{ax.name}: {', '.join(ax.missing_enables())} off")
            self._set_state(ax, AxisState.ERROR)

    # --- reset, emergency stop ----------------------------------------------------------
    def _reset_axis(self, ax: Axis) -> None:
        moving = ax.state not in (AxisState.STANDSTILL, AxisState.ERROR)
        spindle = ax.kind is AxisKind.SPINDLE
        keep = spindle and ax.cfg.flag("kenngr.spdl_no_stop_at_reset")
        self._set_job_error(ax, None)
        ax.hold, ax.homing, ax.block_id, ax.task = False, HomingPhase.NONE, None, None
        self.k.ist[ax.slot, L.I_MARK_ARMED] = 0
        if spindle:
            self.sp.switch_back(ax)  # a CNC reset returns to position control [001 §2.3]
        rotating = ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP)
        if moving and not (keep and rotating):
            self._stop(ax, self._limits(ax, ax.motion or Motion.FEED))
        elif ax.state is AxisState.ERROR:
            self._set_state(ax, AxisState.STANDSTILL)

    def _reset(self) -> None:
        """CNC reset: clear errors and the block queue, stop motion (spindles per P-AXIS-00455).
        After an emergency stop the PLC switches the drives on again (their power-up time)."""
        estop, self.estop = self.estop, False
        self._queue.clear()
        self.handshake.clear()
        for ax in self.axes:
            self._reset_axis(ax)
        if estop:
            self._powered = False  # the PLC runs its start-up again: DriveOn, power-up, ...
            self._drive_status()  # DriveOn now; the power-up is then a wake-up of its own
        self.log(Code.EV_RESET)

    def _emergency_stop(self) -> None:
        """Step-shaped braking of every axis at a_emergency; the channel stays in error and
        the PLC removes each axis' enables (DriveOn, TorquePermission) once it has braked and
        settled (stop category 1)."""
        self.estop = True
        self._queue.clear()
        stop = self.log(Code.EMERGENCY_STOP)  # one error, the active one of every axis
        for ax in self.axes:
            moving = ax.state not in (AxisState.STANDSTILL, AxisState.ERROR)
            ax.motion, ax.hold, ax.homing, ax.task = None, False, HomingPhase.NONE, None
            self.k.ist[ax.slot, L.I_MON_ACTIVE] = 0
            self._set_state(ax, AxisState.ERROR)
            self._set_job_error(ax, stop)
            if moving:
                self._plan_velocity(ax, 0.0, emergency_limits(ax.cfg, ax.gear))
                self.k.st[ax.slot, L.S_V_GOAL] = 0.0
            else:
                self._estop_power_off(ax)  # at rest (or servo already off): at once

    # --- PLC ----------------------------------------------------------------------------
    def _plc_mode(self, mode: str, delay_s: float | None = None) -> None:
        if mode not in {p.value for p in PlcMode}:
            raise NcUsageError(f"unknown PLC mode '{mode}' (auto, manual, fault)")
        self.plc.set_mode(
            PlcMode(mode), self.cycle, None if delay_s is None else self._cycles(delay_s)
        )
        self.log(Code.EV_PLC_MODE, "", f"PLC {mode}")

    # --- MDI and the external command channel -------------------------------------------
    def _mdi(self, text: str, serial: int) -> Outcome:
        """Queue one block and start it when the queue is free: a block that does not parse
        is invalid (with the column), one that fails while starting is refused with its job
        error, one that started or waits behind a running block is accepted."""
        bid = self._next_id
        self._next_id += 1
        names = [a.name for a in self.axes if a.kind is not AxisKind.SPINDLE]
        spindles = [a.name for a in self.axes if a.kind is AxisKind.SPINDLE]
        try:
            block = parse_block(text, names, spindles)
        except BlockError as e:
            self.log(Code.BLOCK_SYNTAX, "", f"{e.detail} (column {e.column}) in '{text}'")
            return Invalid(serial, e.detail, e.column, int(Code.BLOCK_SYNTAX))
        run = _BlockRun(bid, text, block)
        self._queue.append(run)
        self._pump()
        if run.error is not None:
            return Refused(serial, run.error)
        return Accepted(serial, self.cycle, block_id=bid)

    def _program_load(self, name: str, text: str, serial: int) -> Outcome:
        """Check a program by interpreting it from here; keep it when it has no error."""
        names = [a.name for a in self.axes if a.kind is not AxisKind.SPINDLE]
        spindles = [a.name for a in self.axes if a.kind is AxisKind.SPINDLE]
        start = {a.name: float(self.k.st[a.slot, L.S_P_CMD]) for a in self.axes}
        try:
            interpret(text, ListSink(), names, spindles, start)
        except ProgramError as e:
            self.log(Code(e.code), "", f"{name}: {e.detail}", line=e.line, column=e.column)
            return Invalid(serial, e.detail, e.column, int(e.code), e.line)
        self.channel.program = LoadedProgram(name, text)
        self.log(Code.EV_PROGRAM_LOADED, "", f"program {name} loaded")
        return Accepted(serial, self.cycle)

    def _abort_block(self, ax: Axis) -> None:
        if ax.block_id is not None and self._queue and self._queue[0].id == ax.block_id:
            self._queue.popleft()
        ax.block_id = None

    def _pump(self) -> None:
        """Start the head block when possible; finish it when its motions and Ms are done."""
        while self._queue:
            run = self._queue[0]
            if not run.started:
                run.started = True
                seen = self.events.cursor
                ok = self._start_block(run)
                aborted = not self._queue or self._queue[0] is not run
                if aborted or not ok:  # the first job error it raised is its refusal
                    run.error = next((e for e in self.events.since(seen).entries if e.error), None)
                if aborted:
                    continue
                if not ok:
                    self._queue.popleft()
                    continue
            mine = [a for a in self.axes if a.block_id == run.id]
            if run.homing and all(a.kind is AxisKind.SPINDLE for a in mine):
                # the previous order group is homed (a spindle homes unsynchronised [000 §2.7])
                if not self._home_next(run):
                    self._queue.popleft()
                continue
            if mine or run.waiting_m > 0:
                return
            self._queue.popleft()
            self.log(Code.EV_BLOCK_DONE, "", run.text)

    def _start_block(self, run: _BlockRun) -> bool:
        b = run.block
        assert b is not None
        if b.slope_type is not None:
            self.slope = b.slope_type
        if b.tool is not None:
            self._tool(b.tool)
        for m in b.m_functions:
            if m in (2, 30):
                self._program_end()
            self._m_output(m, "", run)
        gear = None
        if b.gear is not None:
            if self.gear_change_enabled:
                gear = b.gear - 39
            else:  # M40-M45 are free M functions without gear change (P-CHAN-00052)
                self._m_output(b.gear, "", run)
        main_done = False
        for sc in b.spindles:
            ax = self.axis(sc.spindle)
            is_main = ax.name == self.main_spindle
            main_done |= is_main
            if ax.kind is not AxisKind.SPINDLE:
                self._fail(ax, Code.NOT_A_SPINDLE, f"'{run.text}'")
                return False
            if not self.sp.block(ax, sc, gear if is_main else None, run.id):
                return False
            if sc.m is not None and self._synch_plc(ax, sc.m):
                self._m_output(sc.m, ax.name, run)
        if gear is not None and not main_done:
            if self.main_spindle is None:
                self._fail(None, Code.GEAR_CHANGE_OFF, f"'{run.text}'")
                return False
            if self.sp.gear_only(self.axis(self.main_spindle), gear, run.id):
                return False
        if b.homing:
            # G74 X2 Z1 S1: the lowest order digit first, equal digits together [000 §2.7]
            orders = sorted(set(b.homing.values()))
            run.homing = [[n for n, o in b.homing.items() if o == order] for order in orders]
            if not self._home_next(run):
                return False
        if b.axes:
            motion = Motion.RAPID if (b.motion or 0) == 0 else Motion.FEED
            feed = b.feed / 60.0 if b.feed else None
            for name, value in b.axes.items():
                ax = self.axis(name)
                target = value if b.absolute is not False else self.k.st[ax.slot, L.S_P_CMD] + value
                if self._homing_required(ax) or self._start_move(ax, target, motion, feed, run.id):
                    return False
        return True

    def _home_next(self, run: _BlockRun) -> bool:
        """Start the next G74 order group of a block; False when one of them is refused."""
        return all(self._home(name, run.id) is None for name in run.homing.pop(0))

    def _synch_plc(self, ax: Axis, m: int) -> bool:
        """M3/M4/M5/M19 with the PLC_INFO bit are output to the PLC [000 §2.5]."""
        i = self.spindle_index(ax)
        if i is None or m not in (3, 4, 5, 19):
            return False
        return bool(int(self.cfg.channel_raw(f"spindel[{i}].m{m}_synch")) & 0x20000)

    def _m_output(self, m: int, axis: str, run: _BlockRun | None) -> None:
        """An M function of a block (or a free one) to the PLC; the block waits for its
        acknowledgement and ends with its timeout."""
        if run is None:
            self.handshake.output(m, axis, Waiter())
            return
        run.waiting_m += 1
        bid = run.id

        def acknowledged() -> None:
            if self._queue and self._queue[0].id == bid:
                self._queue[0].waiting_m -= 1

        def timed_out(_ev: Event) -> None:
            if self._queue and self._queue[0].id == bid:
                self._queue.popleft()

        self.handshake.output(m, axis, Waiter(acknowledged, timed_out))

    # --- the cycle boundary --------------------------------------------------------------
    def on_cycle(self, cycle: int) -> None:
        """Handle kernel events and timers after the kernel reached `cycle`."""
        self.cycle = cycle
        self._drive_status()
        self.handshake.on_cycle(cycle)
        for ax in self.axes:
            ev = int(self.k.ist[ax.slot, L.I_EVENTS])
            if ev:
                self.k.ist[ax.slot, L.I_EVENTS] = 0
                self._axis_events(ax, ev)
            if ax.deadline is not None and cycle >= ax.deadline:
                self._watchdog_expired(ax)
        if self.estop:
            self._estop_settled()
        self._pump()

    def _drive_status(self) -> None:
        """Drive status at this cycle, and the PLC program's start-up [004 §4]: DriveOn once
        a drive is ready for power on, TorquePermission and ReleaseFeedhold once it is ready
        for the control loop (drives that report no status at the PLC's start)."""
        for ax in self.axes:
            before = ax.drive.ready()
            ax.drive.update(self.cycle, bool(ax.units["DriveOn"]))
            if ax.drive.ready() != before:
                self._enables_changed(ax)
        if self._powered or self.estop or self.cycle < self.plc.power_on_cycle:
            return  # (no start-up during an E-stop: the reset resumes it)
        for ax in self.axes:
            units = ax.units
            if not units["DriveOn"] and READY_FOR_POWER_ON not in ax.drive.missing():
                units["DriveOn"] = 1
                self._enables_changed(ax)
            if not ax.drive.missing() and not (
                units["TorquePermission"] and units["ReleaseFeedhold"]
            ):
                units["TorquePermission"] = units["ReleaseFeedhold"] = 1
                self._enables_changed(ax)
        if all(ax.drive_follows() for ax in self.axes):
            self._powered = True
            self.log(Code.EV_POWERED)

    def _axis_events(self, ax: Axis, ev: int) -> None:
        if ev & L.EV_LAG:
            lag = self.k.st[ax.slot, L.S_LAG]
            self._fail(ax, Code.LAG_MONITORING, f"{ax.name} lag {lag:.4f} {ax.pos_unit}")
            self._halt(ax)
            return
        if ev & L.EV_SWLIMIT and ax.state is not AxisState.ERROR:
            pos = self.k.st[ax.slot, L.S_P_CMD]
            self._fail(ax, Code.SOFTWARE_LIMIT, f"{ax.name} at {pos:.4f} {ax.pos_unit}")
            self._abort_block(ax)
            self._plan_velocity(ax, 0.0, emergency_limits(ax.cfg, ax.gear))
            self._set_state(ax, AxisState.ERROR)
        if ax.kind is AxisKind.SPINDLE:
            if ev & L.EV_SPEED_REACHED:
                self.log(Code.EV_SPEED_REACHED, ax.name)
            if self.sp.on_events(ax, ev):
                return
        elif ev & L.EV_CAM and ax.state is AxisState.HOMING:
            cam = bool(self.k.ist[ax.slot, L.I_CAM])
            d = 1.0 if ax.cfg.flag("kenngr.ref_richt") else -1.0
            if ax.homing is HomingPhase.TO_CAM and cam == (d > 0):
                self._homing_search(ax, HomingPhase.OFF_CAM)
            elif ax.homing is HomingPhase.OFF_CAM and cam != (d > 0):
                self._homing_edge(ax)
        if ev & L.EV_PLAN_DONE:
            self._plan_done(ax)

    def _halt(self, ax: Axis) -> None:
        """Error reaction: servo off, axis in error, its block aborted."""
        self.k.ist[ax.slot, L.I_PLAN_N] = 0
        self.k.ist[ax.slot, L.I_ENABLED] = 0
        ax.units["TorquePermission"] = 0
        self._abort_block(ax)
        ax.motion, ax.task = None, None
        self.k.ist[ax.slot, L.I_MON_ACTIVE] = 0
        self._set_state(ax, AxisState.ERROR)

    def _estop_power_off(self, ax: Axis) -> None:
        """E-stop, stop category 1: once the axis has braked, the PLC takes its enables."""
        for u in ("DriveOn", "TorquePermission"):
            ax.units[u] = 0
        self._enables_changed(ax)

    def _estop_settled(self) -> None:
        """During an E-stop: take the enables of every axis whose braking has ended and whose
        position loop has settled (lag inside kenngr.exact_stop_window)."""
        st, ist, pr = self.k.st, self.k.ist, self.k.pr
        for ax in self.axes:
            s = ax.slot
            if not ax.enables_ok() or ist[s, L.I_PLAN_N] > 0:
                continue
            if ist[s, L.I_OPEN_LOOP] == L.LOOP_CLOSED:
                settled = abs(st[s, L.S_LAG]) <= pr[s, L.P_INPOS_WIN]
            else:  # speed control: no lag to settle, the drive has stopped turning
                settled = abs(st[s, L.S_V_ACT]) <= pr[s, L.P_INPOS_WIN]
            if settled:
                self._estop_power_off(ax)

    def _plan_done(self, ax: Axis) -> None:
        if ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            self._unwatch(ax)  # at speed: endless rotation lasts until the next command
            return
        if ax.hold or ax.state is AxisState.ERROR:
            return
        away = abs(self.k.st[ax.slot, L.S_P_CMD] - ax.target) > 1e-9
        if ax.state in (AxisState.MOVING, AxisState.JOG) and away:
            return  # braked to a hold at override 0 %: the move resumes with the override
        if ax.state is AxisState.HOMING:
            if ax.homing is not HomingPhase.TO_REF:
                return
            ax.homing = HomingPhase.NONE
            self.log(Code.EV_HOMED, ax.name, f"{ax.name} homed")
        if ax.state is AxisState.STANDSTILL:
            return
        self._set_state(ax, AxisState.STANDSTILL)
        self.k.ist[ax.slot, L.I_MON_ACTIVE] = 0
        ax.motion, ax.block_id = None, None
        self.log(Code.EV_MOTION_DONE, ax.name)
