"""One simulated machine: a channel with axes and spindles, its HLI and its PLC.

The Python layer of the NC, composed of its parts: `AxisMotion` (nc_sim/axis/motion.py) owns
the axes' kernel rows and handles their kernel events, `Moves` the single-axis commands (jog,
moves, homing), `SpindleControl` the spindle (nc_sim/spindle/), `Handshake` the M functions
to the PLC (nc_sim/plc.py). `submit` takes a command (nc_sim/commands.py) and answers with
its outcome; kernel events drive the sequences (homing, spindle tasks, blocks) forward, each
phase bounded by the watchdog (nc_sim/axis/watchdog.py). Nothing here reads a clock: time is
`cycle · cycle_s`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import assert_never

from nc_sim import hli
from nc_sim.axis.drive import READY_FOR_POWER_ON
from nc_sim.axis.motion import AxisMotion, ChannelContext
from nc_sim.axis.moves import Moves
from nc_sim.axis.params import power_on, push_params
from nc_sim.axis.state import Axis, drive_status
from nc_sim.channel.channel import Channel
from nc_sim.channel.path import Path
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
    PlcSignal,
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
from nc_sim.config import MachineConfig
from nc_sim.errors import MESSAGES, Code, NcUsageError, is_error
from nc_sim.events import EVENT_LOG_LEN, OUTCOME_LOG_LEN, Event, EventLog
from nc_sim.faults import NOW, Fault, FaultState, Trigger
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.machine.channel_host import MachineChannelHost
from nc_sim.machine.channel_ops import PROGRAM_ACTIVE, ChannelOps
from nc_sim.machine.fault_injection import FaultInjection
from nc_sim.machine.panel import Panel
from nc_sim.machine.readout import machine_snapshot
from nc_sim.plc import Handshake, PlcMode, SimPlc
from nc_sim.snapshot import AxisState, MachineSnapshot
from nc_sim.spindle.caxis import CAxis
from nc_sim.spindle.control import SpindleControl
from nc_sim.units import AxisKind


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
        self.ctx = ChannelContext(
            hli.channel_units(), int(cfg.channel_raw("prog_start.slope.profile"))
        )
        self.events: EventLog[Event] = EventLog(EVENT_LOG_LEN)  # bounded, read by cursor
        self.plc = SimPlc(self._cycles(cfg.channel_eng("plc.m_ack_delay")))
        # the timeout is read once here and in refresh_params: the cycle boundary runs often
        self.handshake = Handshake(
            self.plc,
            self._cycles(cfg.channel_eng("plc.m_ack_timeout")),
            kernel.cycle_s,
            self.log,
            self.now,
        )
        self.outcomes: EventLog[Outcome] = EventLog(OUTCOME_LOG_LEN)  # answers to submit
        self._powered = False  # power-on done: the PLC has switched every drive on
        self.motion = AxisMotion(kernel, self.ctx, self.log, self.now, self._axis_failed)
        self.sp = SpindleControl(self.motion, cfg, self.handshake)
        self.moves = Moves(self.motion, self.sp, cfg)
        path_axes = [a for a in self.axes if a.kind is not AxisKind.SPINDLE]
        # a main spindle with a rotary-axis name (P-CHAN-00010) is also the path axis C
        c_name = str(cfg.channel_raw("default_ax_name_of_spindle") or "").strip().upper()
        c_spindle = self.by_name.get(self.main_spindle or "") if c_name else None
        if c_spindle is not None:
            path_axes.append(c_spindle)
        path_axes = path_axes[: L.MAX_PATH_AXES]
        names = [c_name if a is c_spindle else a.name for a in path_axes]
        self.channel_slot = kernel.claim(1)[0]
        self.ch_host = MachineChannelHost(self, path_axes)
        self.ops = ChannelOps(self)
        self.panel = Panel(self)
        path = Path(kernel, self.channel_slot, [a.slot for a in path_axes])
        self.channel = Channel(
            path,
            self.ch_host,
            tuple(names),
            self.ops.interpret_here,
            cfg.cycle_s,
            int(cfg.channel_raw("lookahead_blocks")),
            rotary_axes=frozenset([c_name]) if c_spindle in path_axes else frozenset(),
        )
        for ax in self.axes:
            ax.gear = int(ax.cfg.raw("kenngr.getriebe_stufe")) if ax.cfg.is_spindle else 1
            push_params(kernel, ax)
            power_on(kernel, ax)
        self.injection = FaultInjection(self)  # training faults (nc_sim/faults.py)
        self.cax: CAxis | None = None
        if c_spindle is not None and c_spindle in path_axes:
            slot = c_spindle.slot
            self.cax = CAxis(
                self.sp,
                c_spindle,
                c_name,
                self.handshake,
                partial(path.set_on_path, slot),
                self._axis_failed,
            )

    @property
    def channel_units(self) -> dict[str, int]:
        """The channel's HLI control units (override, feedhold, reduced_acceleration)."""
        return self.ctx.units

    @property
    def rotary_spindle(self) -> str | None:
        """The configured name of the main spindle with rotary-axis capability (the C axis
        in rotary axis mode, P-CHAN-00010), None without one."""
        return self.cax.ax.name if self.cax is not None else None

    @property
    def slope(self) -> int:
        """Slope type in force (P-CHAN-00071, #SLOPE[TYPE=...])."""
        return self.ctx.slope

    @slope.setter
    def slope(self, value: int) -> None:
        self.ctx.slope = value

    def modal_at_program_start(self) -> None:
        """Back to the profile every program starts with (P-CHAN-00071) and exclusive manual
        mode G200: a #SLOPE or G201 of an earlier program or MDI block holds only until the
        next start or reset [002 §2.2.1, §2.6]."""
        self.ctx.slope = int(self.cfg.channel_raw("prog_start.slope.profile"))
        self.ctx.parallel_manual = False

    @property
    def estop(self) -> bool:
        """An emergency stop is active (until the reset)."""
        return self.ctx.estop

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
        # what a block waited for may be done now (a manual acknowledgement): it goes on from
        # this cycle boundary, not from the next wake-up
        self.channel.pump()
        self.injection.tick()  # a motion it started starts a fault's count
        self.outcomes.append(outcome)
        return outcome

    def _dispatch(self, cmd: Command) -> Outcome:
        answer: Event | int | None = None
        match cmd:
            case Mdi():
                return self.ops.mdi(cmd.block, cmd.serial)
            case ProgramLoad():
                return self.ops.program_load(cmd.name, cmd.text, cmd.serial)
            case CycleStart():
                answer = self.ops.cycle_start()
            case ProgramStop():
                self.ops.stop()
            case Feedhold():
                self.panel.channel_unit("feedhold", int(cmd.on))
            case SingleBlock():
                self.channel.set_single_block(cmd.on)
            case SpindleRun():
                answer = self._as(
                    cmd.spindle,
                    False,
                    partial(self.panel.spindle_run, cmd.spindle, cmd.m, cmd.speed_rpm),
                )
            case SpindlePosition():
                answer = self._as(
                    cmd.spindle,
                    False,
                    partial(
                        self.panel.spindle_position,
                        cmd.spindle,
                        cmd.position_deg,
                        cmd.direction,
                        cmd.speed_rpm,
                    ),
                )
            case GearChange():
                answer = self._as(
                    cmd.spindle, False, partial(self.panel.spindle_gear, cmd.spindle, cmd.m)
                )
            case Home():
                answer = self.moves.home(self.axis(cmd.axis))
            case JogStart():
                ax = self.axis(cmd.axis)
                answer = self._as(
                    cmd.axis,
                    True,
                    partial(self.moves.jog_start, ax, cmd.direction, cmd.feed_mm_min),
                )
            case JogStop():
                ax = self.axis(cmd.axis)
                if self.cax is not None and ax is self.cax.ax:
                    self.cax.cancel_then()
                self.moves.jog_stop(ax)
            case JogStep():
                ax = self.axis(cmd.axis)
                answer = self._as(
                    cmd.axis, True, partial(self.moves.jog_step, ax, cmd.distance, cmd.feed_mm_min)
                )
            case Move():
                ax = self.axis(cmd.axis)
                answer = self._as(
                    cmd.axis,
                    True,
                    partial(self.moves.move, ax, cmd.target, cmd.rapid, cmd.feed_mm_min),
                )
            case HliWrite():
                self.panel.hli_write(cmd.unit, cmd.value, cmd.axis)
            case SetPlcMode():
                self._plc_mode(cmd.mode, cmd.delay_s)
            case PlcAck():
                answer = self.handshake.acknowledge(cmd.m)
            case PlcSignal():
                answer = self._plc_signal(cmd.signal, cmd.on)
            case Reset():
                self._reset()
            case EmergencyStop():
                self._emergency_stop()
            case _:  # a new command type must get its case here (mypy checks)
                assert_never(cmd)
        if isinstance(answer, Event):
            return Refused(cmd.serial, answer)
        return Accepted(cmd.serial, self.cycle, acknowledged=answer)

    def _as(self, name: str, rotary: bool, then: Callable[[], Event | None]) -> Event | None:
        """A key of the main spindle with rotary-axis capability: jog and moves need rotary
        axis mode, the spindle keys spindle mode; `then` runs once it is in force [003 §4.2]."""
        cax = self.cax
        if cax is None or self.axis(name) is not cax.ax:
            return then()
        ax = cax.ax
        if rotary and not cax.rotary and ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
            # a key never stops a turning spindle to make it an axis: M5 first
            what = ax.state.name.lower().replace("_", " ")
            return self.motion.fail(ax, Code.AXIS_BUSY, f"{ax.name} is {what}: M5 first")
        return cax.request(rotary, None, then)

    def _plc_signal(self, signal: str, on: bool) -> int:
        if signal not in ("ROTMOD_Q", "SPMOD_Q"):
            raise NcUsageError(f"unknown PLC signal '{signal}' (ROTMOD_Q, SPMOD_Q)")
        if self.cax is None:
            raise NcUsageError("no spindle with rotary-axis capability (P-CHAN-00010)")
        return self.cax.plc_signal(signal, on)

    # --- time ---------------------------------------------------------------------------
    def _cycles(self, seconds: float) -> int:
        return max(0, round(seconds / self.k.cycle_s))

    def now(self) -> int:
        """The machine's current cycle (a bound method: the parts keep it, and it copies)."""
        return self.cycle

    @property
    def t_s(self) -> float:
        return self.cycle * self.k.cycle_s

    def next_wakeup(self) -> int | None:
        """The next cycle at which the machine must act without a kernel event."""
        times = [self.plc.power_on_cycle] if self.cycle < self.plc.power_on_cycle else []
        times += [c for ax in self.axes if (c := ax.drive.next_change()) is not None]
        for due in (self.handshake.next_wakeup(), self.injection.next_wakeup()):
            if due is not None:
                times.append(due)
        times += [ax.deadline for ax in self.axes if ax.deadline is not None]
        for wake in (self.channel.next_wakeup(), self.ch_host.next_wakeup()):
            if wake is not None:
                times.append(wake)
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
        return len(self.channel.mdi.blocks)

    # --- training faults (nc_sim/machine/fault_injection.py) ------------------------------
    def inject(self, fault: Fault, trigger: Trigger = NOW) -> int:
        """Inject a training fault to take effect on `trigger`; returns its id."""
        return self.injection.inject(fault, trigger)

    def remove_fault(self, fid: int) -> None:
        """Remove injected fault `fid` (NcUsageError for an unknown id)."""
        self.injection.remove(fid)

    def faults(self) -> list[FaultState]:
        """The injected faults and whether each is in force."""
        return self.injection.states()

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
        signal: str | None = None,
        value: float | None = None,
        block: int | None = None,
    ) -> Event:
        """Record an error (its meaning, then the detail) or an event (its detail, which
        reads as a message of its own, else the meaning), numbered by the event log, with
        the M function, gear stage, signal and value it concerns as fields."""
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
            signal=signal,
            value=value,
            block=block,
        )
        self.events.append(ev)
        return ev

    # --- lookup -------------------------------------------------------------------------
    def axis(self, name: str) -> Axis:
        """Axis by name; the main spindle also answers to S, and to its rotary-axis name."""
        if (name == "S" and self.main_spindle) or (self.cax and name == self.cax.c_name):
            name = self.main_spindle or name
        ax = self.by_name.get(name)
        if ax is None:
            raise NcUsageError(f"no axis or spindle '{name}'")
        return ax

    @property
    def gear_change_enabled(self) -> bool:
        """P-CHAN-00052: M40-M45 change the main spindle's gear; else they are free M functions."""
        return bool(self.cfg.channel_raw("main_spindle_gear_change"))

    # --- reset, emergency stop ----------------------------------------------------------
    def _reset(self) -> None:
        """CNC reset: clear errors and the block queue, stop motion (spindles per P-AXIS-00455).
        After an emergency stop the PLC switches the drives on again (their power-up time);
        after an error reaction that took an axis' servo (lag monitoring), the PLC program
        gives its TorquePermission back once the reset has cleared the error."""
        estop, self.ctx.estop = self.ctx.estop, False
        self.channel.reset()
        self.modal_at_program_start()
        if self.cax is not None:
            self.cax.reset()
        self.handshake.clear()
        for ax in self.axes:
            self.moves.reset(ax)
            if ax.servo_taken and not estop:
                ax.units["TorquePermission"] = 1
                self.motion.enables_changed(ax)
            ax.servo_taken = False  # (after an E-stop the start-up below gives every enable)
        if estop:
            self._powered = False  # the PLC runs its start-up again: DriveOn, power-up, ...
            self._drive_status()  # DriveOn now; the power-up is then a wake-up of its own
        self.log(Code.EV_RESET)

    def _emergency_stop(self) -> None:
        """Step-shaped braking of every axis at a_emergency; the channel stays in error and
        the PLC removes each axis' enables (DriveOn, TorquePermission) once it has braked and
        settled (stop category 1)."""
        self.ctx.estop = True
        stop = self.log(Code.EMERGENCY_STOP)  # one error, the active one of every axis
        self.channel.abort(stop)  # the path axes brake on their own, leaving the path
        if self.cax is not None:
            self.cax.interrupt(estop=True)
        for ax in self.axes:
            self.motion.emergency_stop(ax, stop)

    # --- PLC ----------------------------------------------------------------------------
    def _plc_mode(self, mode: str, delay_s: float | None = None) -> None:
        if mode not in {p.value for p in PlcMode}:
            raise NcUsageError(f"unknown PLC mode '{mode}' (auto, manual, fault)")
        self.plc.set_mode(
            PlcMode(mode), self.cycle, None if delay_s is None else self._cycles(delay_s)
        )
        self.log(Code.EV_PLC_MODE, "", f"PLC {mode}")

    def _axis_failed(self, ax: Axis) -> None:
        """An axis' motion ended in a job error: the program or MDI block it moved for stops."""
        if self.cax is not None and ax is self.cax.ax:
            self.cax.axis_failed()
        on_path = self.k.ist[ax.slot, L.I_ROLE] == L.ROLE_PATH_AXIS
        failed = ax.block_id is not None or on_path
        ax.block_id = None
        if failed and self.channel.state in PROGRAM_ACTIVE:
            self.ch_host.channel_error(ax.error_event)

    # --- the cycle boundary --------------------------------------------------------------
    def on_cycle(self, cycle: int) -> None:
        """Handle kernel events and timers after the kernel reached `cycle`."""
        self.cycle = cycle
        self._drive_status()
        self.handshake.on_cycle(cycle)
        for ax in self.axes:
            ev = self.motion.take_events(ax)
            if ev:
                self.motion.on_events(ax, ev)
            self.motion.check_deadline(ax)
        if self.estop:  # the PLC takes the enables of every axis that has braked and settled
            for ax in self.axes:
                if ax.enables_ok() and self.motion.settled(ax):
                    self.motion.power_off(ax)
        ch_ev = int(self.k.ist[self.channel_slot, L.I_EVENTS])
        if ch_ev:
            self.k.ist[self.channel_slot, L.I_EVENTS] = 0
            self.channel.on_path_events()
        else:
            self.channel.pump()
        self.injection.tick()
        self.k.ist[self.channel_slot, L.I_STATE] = int(self.channel.state)

    def _drive_status(self) -> None:
        """Drive status at this cycle, and the PLC program's start-up [004 §4]: DriveOn once
        a drive is ready for power on, TorquePermission and ReleaseFeedhold once it is ready
        for the control loop (drives that report no status at the PLC's start)."""
        for ax in self.axes:
            before = ax.drive.ready()
            ax.drive.update(self.cycle, bool(ax.units["DriveOn"]))
            if ax.drive.ready() != before:
                self.motion.enables_changed(ax)
        if self._powered or self.estop or self.cycle < self.plc.power_on_cycle:
            return  # (no start-up during an E-stop: the reset resumes it)
        for ax in self.axes:
            units = ax.units
            if not units["DriveOn"] and READY_FOR_POWER_ON not in ax.drive.missing():
                units["DriveOn"] = 1
                self.motion.enables_changed(ax)
            if not ax.drive.missing() and not (
                units["TorquePermission"] and units["ReleaseFeedhold"]
            ):
                units["TorquePermission"] = units["ReleaseFeedhold"] = 1
                self.motion.enables_changed(ax)
        if all(ax.drive_follows() for ax in self.axes):
            self._powered = True
            self.log(Code.EV_POWERED)
