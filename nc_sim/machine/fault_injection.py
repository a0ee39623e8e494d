"""Training faults injected into a machine (nc_sim/faults.py): when each takes effect (its
`Trigger`) and what it changes. A fault changes the plant behind an axis (its kernel columns,
nc_sim/axis/plant.py), its drive's status or the PLC program - never a parameter, and nothing
of it goes to the event log: the student finds it by its symptoms.

A trigger takes effect at a cycle boundary: `after_s` after the injection, or after the axis'
next motion began (`on_motion`); the machine wakes up for it (`next_wakeup`), so it acts in
that exact cycle. A motion begins at a boundary (a command, a block, a sequence's next
phase), so the boundary that starts it also starts the count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from nc_sim.axis.faults import PlantFaults
from nc_sim.axis.plant import change_plant
from nc_sim.axis.state import Axis
from nc_sim.errors import NcUsageError
from nc_sim.faults import (
    CATALOGUE,
    NOW,
    Backlash,
    CouplingSoft,
    DriveAccelLimit,
    DriveGainWrong,
    DriveNotReady,
    EnableDrop,
    EncoderInverted,
    EncoderNoise,
    EncoderResolutionWrong,
    Fault,
    FaultState,
    Friction,
    FrictionRising,
    GearRatioWrong,
    MotorInverted,
    NotchMistuned,
    PlcNoAck,
    PlcSlowAck,
    Trigger,
)
from nc_sim.kernel import layout as L
from nc_sim.machine.core import MachineCore
from nc_sim.snapshot import AxisState

GEAR_STAGES = 6  # M40-M45: gear stages 1..6, gear records getriebe[0..5]
_WORD = 0xFFFFFFFF


@dataclass
class Injected:
    """One injected fault and where its trigger stands."""

    id: int
    fault: Fault
    trigger: Trigger
    injected_cycle: int
    due: int | None  # the cycle it takes effect; None while it waits for its axis to move
    active_since: int | None = None
    # EnableDrop only: the PLC drops the enable once in every motion of the axis
    in_motion: bool = False  # the axis' current motion has been seen
    dropped: bool = False  # it has taken TorquePermission (given back on removal)

    def state(self) -> FaultState:
        return FaultState(self.id, self.fault, self.trigger, self.injected_cycle, self.active_since)


def noise_state(seed: int) -> int:
    """The encoder noise generator's start state for a seed (never 0, its fixed point):
    the seed spread over 32 bits, so neighbouring seeds give unrelated noise."""
    return (seed * 0x9E3779B1 + 0x7F4A7C15) & _WORD or 1


class FaultInjection:
    """The faults injected into one machine; `Machine.inject`, `remove_fault`, `faults`."""

    def __init__(self, m: MachineCore) -> None:
        self.m = m
        self._faults: list[Injected] = []
        self._next_id = 1

    # --- the instructor's surface ---------------------------------------------------------
    def inject(self, fault: Fault, trigger: Trigger = NOW) -> int:
        """Inject `fault` to take effect on `trigger`; returns its id (1, 2, ...). A value
        the fault cannot have (unknown axis, gear out of range, non-positive factor) raises
        NcUsageError naming it."""
        self._check(fault, trigger)
        cycle = self.m.cycle
        waits = isinstance(fault, EnableDrop) or (trigger.on_motion and _axis_name(fault))
        due = None if waits else cycle + self._cycles(trigger.after_s)
        self._faults.append(Injected(self._next_id, fault, trigger, cycle, due))
        self._next_id += 1
        self.tick()
        return self._next_id - 1

    def remove(self, fid: int) -> None:
        """Remove fault `fid`: what it changed is as the parameters say again."""
        entry = next((e for e in self._faults if e.id == fid), None)
        if entry is None:
            ids = ", ".join(str(e.id) for e in self._faults) or "none"
            raise NcUsageError(f"no injected fault with id {fid} (injected: {ids})")
        self._faults.remove(entry)
        if isinstance(entry.fault, EnableDrop):
            ax = self.m.axis(entry.fault.axis)
            if entry.dropped and not ax.units["TorquePermission"] and not self.m.estop:
                ax.units["TorquePermission"] = 1  # the PLC program gives it back
                self.m.motion.enables_changed(ax)
        elif entry.active_since is not None:
            self._apply()

    def states(self) -> list[FaultState]:
        """The injected faults, oldest first."""
        return [e.state() for e in self._faults]

    # --- time -------------------------------------------------------------------------------
    def tick(self) -> None:
        """At a cycle boundary (after the machine's reaction, after a command): count from
        the motions that began, and let the faults due now take effect."""
        now = self.m.cycle
        changed = False
        for e in self._faults:
            if isinstance(e.fault, EnableDrop):
                self._enable_drop(e, self.m.axis(e.fault.axis), now)
                continue
            if e.active_since is not None:
                continue
            if e.due is None:
                if not _moving(self.m.axis(_axis_name(e.fault))):
                    continue
                e.due = now + self._cycles(e.trigger.after_s)
            if now >= e.due:
                e.active_since = now
                changed = True
                if isinstance(e.fault, EncoderNoise):  # the same seed, the same noise
                    slot = self.m.axis(e.fault.axis).slot
                    self.m.k.ist[slot, L.I_NOISE_STATE] = noise_state(e.fault.seed)
        if changed:
            self._apply()

    def next_wakeup(self) -> int | None:
        """The next cycle a trigger is due (a fault waiting for a motion needs none: the
        motion starts at a boundary of its own)."""
        dues = [e.due for e in self._faults if e.due is not None and e.due > self.m.cycle]
        return min(dues) if dues else None

    def _cycles(self, seconds: float) -> int:
        return max(0, round(seconds / self.m.k.cycle_s))

    # --- effects ----------------------------------------------------------------------------
    def _apply(self) -> None:
        """Put the faults in force into the plants, drives and PLC program."""
        m = self.m
        active = [e.fault for e in self._faults if e.active_since is not None]
        for ax in m.axes:
            plant = _plant([f for f in active if _axis_name(f) and m.axis(_axis_name(f)) is ax])
            if plant != ax.plant:
                change_plant(m.k, ax, plant)
            failed = any(isinstance(f, DriveNotReady) and m.axis(f.axis) is ax for f in active)
            if failed != ax.drive.failed:
                ax.drive.failed = failed
                m.motion.enables_changed(ax)  # the NC's reaction to a drive not ready
        no_ack = any(isinstance(f, PlcNoAck) for f in active)
        slow = [self._cycles(f.delay_s) for f in active if isinstance(f, PlcSlowAck)]
        m.plc.set_program_fault(no_ack, max(slow) if slow else None, m.cycle)

    def _enable_drop(self, e: Injected, ax: Axis, now: int) -> None:
        """The PLC drops TorquePermission in every motion of the axis: `after_s` into it
        (on_motion), else at its start once `after_s` after the injection have passed."""
        if not _moving(ax):
            e.in_motion, e.due = False, None
            return
        if not e.in_motion:
            e.in_motion = True
            if e.trigger.on_motion:
                e.due = now + self._cycles(e.trigger.after_s)
            else:
                e.due = max(now, e.injected_cycle + self._cycles(e.trigger.after_s))
        if e.due is None or now < e.due:
            return
        e.due = None
        if e.active_since is None:
            e.active_since = now
        if ax.units["TorquePermission"]:
            ax.units["TorquePermission"] = 0
            e.dropped = True
            self.m.motion.enables_changed(ax)

    # --- checks -----------------------------------------------------------------------------
    def _check(self, fault: Fault, trigger: Trigger) -> None:
        if not isinstance(fault, CATALOGUE):
            raise NcUsageError(f"{fault!r} is not a fault of the catalogue")
        if not (math.isfinite(trigger.after_s) and trigger.after_s >= 0.0):
            raise NcUsageError(f"trigger after_s = {trigger.after_s} s: must be >= 0")
        name = _axis_name(fault)
        ax = None
        if name:
            try:
                ax = self.m.axis(name)
            except NcUsageError as e:
                raise NcUsageError(f"{fault.kind}: {e}") from None
        for field_name, unit in (
            ("factor", ""),
            ("rms", " mm|°"),
            ("v_loss", " mm|°/s"),
            ("width", " mm|°"),
            ("a_max", " mm|°/s²"),
            ("delay_s", " s"),
        ):
            value = getattr(fault, field_name, None)
            if value is not None and not (math.isfinite(value) and value > 0.0):
                raise NcUsageError(f"{fault.kind}: {field_name} = {value}{unit}: must be > 0")
        if isinstance(fault, GearRatioWrong) and not 1 <= fault.gear <= GEAR_STAGES:
            raise NcUsageError(
                f"{fault.kind}: gear = {fault.gear}: gear stages are 1..{GEAR_STAGES} (M40-M45)"
            )
        if isinstance(fault, DriveNotReady) and ax is not None and not ax.drive.signals:
            raise NcUsageError(
                f"{fault.kind}: the drive of {ax.name} (kenngr.antr_typ "
                f"{ax.cfg.raw('kenngr.antr_typ')}) reports no ready signals to drop"
            )


def _axis_name(fault: Fault) -> str:
    """The axis a fault concerns, "" for the PLC's."""
    return "" if isinstance(fault, PlcNoAck | PlcSlowAck) else fault.axis


def _moving(ax: Axis) -> bool:
    """The axis moves (a motion, a sequence, a path block): not at rest or in error."""
    return ax.state not in (AxisState.STANDSTILL, AxisState.ERROR)


def _plant(faults: list[Fault]) -> PlantFaults:
    """The plant of an axis with these (active) faults of it; several of one kind compound."""
    p = PlantFaults()
    for f in faults:
        match f:
            case MotorInverted():
                p.motor_inverted = not p.motor_inverted
            case EncoderInverted():
                p.encoder_inverted = not p.encoder_inverted
            case DriveGainWrong():
                p.speed_factor *= f.factor
            case EncoderResolutionWrong():
                p.encoder_factor *= f.factor
            case EncoderNoise():
                p.noise_rms = math.hypot(p.noise_rms, f.rms)
            case GearRatioWrong():
                p.gear_factors[f.gear] = p.gear_factors.get(f.gear, 1.0) * f.factor
            case Friction():
                p.friction += f.v_loss
            case Backlash():
                p.backlash += f.width
            case CouplingSoft():
                p.stiffness_factor *= f.factor
            case FrictionRising():
                p.friction_factor *= f.factor
            case NotchMistuned():
                p.filter_factor *= f.factor
            case DriveAccelLimit():
                p.a_max = min(p.a_max, f.a_max) if p.a_max > 0.0 else f.a_max
            case _:
                pass
    return p
