"""Runtime state of one axis or spindle outside the kernel arrays."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

from nc_sim.axis.drive import STATUS_BY_DRIVE, DriveStatus
from nc_sim.axis.dynamics import Motion
from nc_sim.axis.faults import PlantFaults
from nc_sim.config import AxisConfig
from nc_sim.events import Event
from nc_sim.hli import axis_units
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.snapshot import AxisState
from nc_sim.units import AxisKind, Quantity, eng_unit


class Sequence(Protocol):
    """A sequence an axis runs, advanced by its kernel events: the phases of homing, a
    spindle task (M19, G74, M5 with homing), a gear change. `AxisMotion.on_events` offers it
    every event of its axis (after the faults); each phase is bounded by the axis' watchdog
    (`AxisMotion.watch`). It ends by taking itself off the axis (`ax.sequence = None`)."""

    def on_event(self, ev: int) -> bool:
        """React to kernel events `ev` (EV_* bits); True when they are consumed, so the end
        of its plan is not taken for the end of a plain motion."""
        ...

    def replan(self) -> bool:
        """Plan the current phase again (override, feedhold released); True when done here,
        False when the phase re-plans like a plain move to `ax.target`."""
        ...


@dataclass
class ToolLimits:
    """Tool-related spindle dynamics [000 §2.8.5]: °/s, °/s²; None = not limited."""

    vb_min: float = 0.0
    vb_max: float | None = None
    a_max: float | None = None


@dataclass
class Axis:
    """One axis or spindle of a machine: config, kernel slot and what it is doing."""

    cfg: AxisConfig
    slot: int
    gear: int = 1
    state: AxisState = AxisState.STANDSTILL
    motion: Motion | None = None
    target: float = math.nan
    feed: float | None = None  # unit/s for G01/jog
    speed_prog: float = 0.0  # spindle: programmed signed speed (°/s) before override
    slope: int = 1
    hold: bool = False  # braked by feedhold, resumes on release
    jog_on_path: bool = False  # G201: a jog of its own on top of the running path
    homed: bool = False
    error_event: Event | None = None  # the job error in force (what set it), None without
    block_id: int | None = None  # MDI block this motion belongs to
    sequence: Sequence | None = None  # the sequence in progress (homing, spindle task)
    # spindle only
    override_suppressed: bool = False  # G167 until the next S[REV..]
    ff_weight: float = 0.0  # G135/G136/G137 feedforward weight 0..1
    reversed: bool = False  # getriebe[i].reverse of the gear stage in force (P-AXIS-00159)
    tool: ToolLimits = field(default_factory=ToolLimits)  # in force
    tool_pending: ToolLimits | None = None  # adopted at the next start from standstill
    speed_ctrl: bool = False  # M3/M4 programmed above the changeover speed P-AXIS-00767
    ff_set: float = 1.0  # weighting for G135, set by G136
    reference_lost: bool = False  # lost above the control limit: M5 homes again [000 §2.7]
    deadline: int | None = None  # watchdog: cycle by which the current phase must have ended
    deadline_s: float = 0.0  # ... its bound in seconds
    deadline_what: str = ""  # ... and what it is (for the job error 90023)
    drive: DriveStatus = field(default_factory=lambda: DriveStatus((), 0, 0))
    units: dict[str, int] = field(default_factory=axis_units)  # its HLI control units
    servo_taken: bool = False  # the error reaction took TorquePermission (the reset gives it back)
    plant: PlantFaults = field(default_factory=PlantFaults)  # injected faults (training)

    # the enables the drive type needs [004 §4.1], read from the list by push_params (the
    # cycle boundary and every status ask them)
    required_enables: tuple[str, ...] = ("TorquePermission",)

    @property
    def name(self) -> str:
        return self.cfg.name

    @property
    def kind(self) -> AxisKind:
        return self.cfg.kind

    @property
    def job_error(self) -> int:
        """Code of the job error in force, 0 without (as the HLI shows it)."""
        return self.error_event.code if self.error_event is not None else 0

    @property
    def pos_unit(self) -> str:
        """Unit of the axis' positions in messages: mm (linear) or ° (rotary, spindle)."""
        return eng_unit(Quantity.POSITION, self.kind)

    def enables_ok(self) -> bool:
        return all(self.units[u] for u in self.required_enables)

    def missing_enables(self) -> list[str]:
        return [u for u in self.required_enables if not self.units[u]]

    def drive_follows(self) -> bool:
        """The drive obeys the NC: every enable set and every reported status present."""
        return self.enables_ok() and not self.drive.missing()


def target_and_distance(k: Kernel, ax: Axis) -> tuple[float | None, float | None]:
    """HLI target position and distance to go [000 §2.9]: the target of the position plan and
    what the command still has to travel to it; None for speed motions (M3/M4, homing
    searches) and continuous jog, which have no target."""
    target = float(k.st[ax.slot, L.S_TARGET])
    if math.isnan(target) or ax.state is AxisState.JOG:
        return None, None
    return target, target - float(k.st[ax.slot, L.S_P_CMD])


def drive_status(cfg: AxisConfig, cycle_s: float) -> DriveStatus:
    """The drive's status model for its type, with the simulated drive's start-up times."""
    signals = STATUS_BY_DRIVE.get(int(cfg.raw("kenngr.antr_typ")), ())
    boot = max(0, round(cfg.eng("sim.drive_boot_time") / cycle_s))
    power_up = max(0, round(cfg.eng("sim.drive_power_up_time") / cycle_s))
    return DriveStatus(signals, boot, power_up)
