"""Runtime state of one axis or spindle outside the kernel arrays, and its parameter push."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.machine.config import AxisConfig
from nc_sim.machine.drive import STATUS_BY_DRIVE, DriveStatus
from nc_sim.machine.dynamics import Motion
from nc_sim.params.definitions import OPMODE_SYMBOLS
from nc_sim.snapshot import AxisState
from nc_sim.units import AxisKind, Quantity, eng_unit, v_reso_digits_per_unit_s

# control units every drive type needs [004 §4.1]; others need only TorquePermission
ENABLES_BY_DRIVE = {
    2: ("DriveOn", "TorquePermission", "ReleaseFeedhold"),  # SERCOS
    3: ("DriveOn", "TorquePermission"),  # PROFIDRIVE
    8: ("DriveOn", "TorquePermission", "ReleaseFeedhold"),  # CANopen
}


class HomingPhase(IntEnum):
    NONE = 0
    TO_CAM = 1
    OFF_CAM = 2
    TO_REF = 3
    ZERO_MARK = 4  # spindle: rotate until the encoder's zero mark passes


class TaskPhase(IntEnum):
    DECEL = 1  # down to the switch-back speed before position control resumes
    SEEK_MARK = 2  # rotating until the zero mark passes (homing, automatic homing)
    POSITION = 3  # position plan to the target, then exact stop
    STOP = 4  # braking to standstill (gear change without positioning)
    WAIT_PLC = 5  # gear change: M40-M45 output, waiting for the PLC


@dataclass
class SpindleTask:
    """A spindle sequence in progress: M19, G74, a gear change, or M5 with homing."""

    kind: str  # "M19", "G74", "gear", "M5" (stop homing on the way after the control limit)
    pos_deg: float  # target angle 0..360
    direction: int | None  # +1 M3, -1 M4, None = shortest way
    speed: float  # positioning speed before override (°/s)
    phase: TaskPhase = TaskPhase.DECEL
    gear: int = 0  # gear change: the new stage
    resume: tuple[int, float] | None = None  # gear change: (M3|M4, rpm) to run afterwards


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
    homing: HomingPhase = HomingPhase.NONE
    homed: bool = False
    error_event: Event | None = None  # the job error in force (what set it), None without
    block_id: int | None = None  # MDI block this motion belongs to
    # spindle only
    override_suppressed: bool = False  # G167 until the next S[REV..]
    ff_weight: float = 0.0  # G135/G136/G137 feedforward weight 0..1
    tool: ToolLimits = field(default_factory=ToolLimits)  # in force
    tool_pending: ToolLimits | None = None  # adopted at the next start from standstill
    speed_ctrl: bool = False  # M3/M4 programmed above the changeover speed P-AXIS-00767
    ff_set: float = 1.0  # weighting for G135, set by G136
    task: SpindleTask | None = None
    reference_lost: bool = False  # lost above the control limit: M5 homes again [000 §2.7]
    deadline: int | None = None  # watchdog: cycle by which the current phase must have ended
    deadline_s: float = 0.0  # ... its bound in seconds
    deadline_what: str = ""  # ... and what it is (for the job error 90023)
    drive: DriveStatus = field(default_factory=lambda: DriveStatus((), 0, 0))
    units: dict[str, int] = field(
        default_factory=lambda: {
            "override": 1000,
            "override_valid": 1,
            "DriveOn": 0,
            "TorquePermission": 0,
            "ReleaseFeedhold": 0,
            "reduced_speed": 0,
            "spindle_stop_at_program_end": 0,
        }
    )

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


def open_position_loop(cfg: AxisConfig) -> bool:
    """A spindle in operation mode OPEN_POSITION_LOOP_MODE (P-AXIS-00320) [000 §2.2.4]."""
    mode = cfg.raw("antr.operation_mode")
    code = OPMODE_SYMBOLS[mode] if isinstance(mode, str) else int(mode)
    return cfg.is_spindle and code == OPMODE_SYMBOLS["OPEN_POSITION_LOOP_MODE"]


def speed_controlled(cfg: AxisConfig) -> bool:
    """A spindle that is never position-controlled [000 §2.2.4]: OPEN_POSITION_LOOP_MODE, or
    no encoder at all (it cannot be positioned: 70252)."""
    return open_position_loop(cfg) or (cfg.is_spindle and cfg.flag("sim.sensorless"))


def changeover_speeds(cfg: AxisConfig) -> tuple[float, float]:
    """(to speed control, back to position control) in °/s [001 §2.3]: P-AXIS-00767/00768,
    or their old names P-AXIS-00265/00266, which keep working; each default means "never",
    so whichever of a pair is set is in force (the lower / the higher speed if both are)."""
    on = min(
        cfg.eng("antr.sai_op_mode_change.v_velocity_control_on"),
        cfg.eng("antr.velocity_position_control_on"),
    )
    back = max(
        cfg.eng("antr.sai_op_mode_change.v_position_control_on"),
        cfg.eng("antr.velocity_position_control_off"),
    )
    return on, back


def push_params(k: Kernel, ax: Axis) -> None:
    """Write the axis' active gear record and loop parameters into the kernel row."""
    c, g, s = ax.cfg, ax.gear, ax.slot
    pr = k.pr
    ax.required_enables = ENABLES_BY_DRIVE.get(int(c.raw("kenngr.antr_typ")), ("TorquePermission",))
    spindle = ax.kind is AxisKind.SPINDLE
    pr[s, L.P_KV] = c.eng("getriebe.kv", g)
    pr[s, L.P_FF] = ax.ff_weight if spindle else c.eng("lr_param.ff_weight")
    pr[s, L.P_MG] = c.eng("getriebe.multi_gain_z", g) / c.eng("getriebe.multi_gain_n", g)
    # the plant's true gain follows the mechanical gear stage
    pr[s, L.P_DRV_GAIN] = c.eng("sim.getriebe[i].drive_gain", g) or c.eng("sim.drive_gain")
    pr[s, L.P_DA_MAX] = c.eng("lr_hw.da_max")
    pr[s, L.P_SIGN_CMD] = -1.0 if c.flag("lr_hw.vz_stellgr") else 1.0
    pr[s, L.P_SIGN_FB] = -1.0 if c.flag("lr_hw.vz_istw") else 1.0
    pr[s, L.P_MOTOR_SIGN] = -1.0 if c.flag("sim.motor_inverted") else 1.0
    pr[s, L.P_ENC_SIGN] = -1.0 if c.flag("sim.encoder_inverted") else 1.0
    t_drive = c.eng("sim.drive_t")
    pr[s, L.P_DRV_ALPHA] = 1.0 - math.exp(-k.cycle_s / t_drive) if t_drive > 0 else 1.0
    pr[s, L.P_DRV_A_MAX] = c.eng("sim.drive_a_max")
    # one increment = wegaufn/wegaufz in 0.1 µm or 0.0001°
    pr[s, L.P_ENC_INC] = c.eng("getriebe.wegaufn", g) / c.eng("getriebe.wegaufz", g)
    pr[s, L.P_LAG_MAX] = c.eng("getriebe.lag_max", g)
    if spindle:
        pr[s, L.P_SWE_NEG], pr[s, L.P_SWE_POS] = -math.inf, math.inf
    else:
        pr[s, L.P_SWE_NEG] = c.eng("kenngr.swe_neg")
        pr[s, L.P_SWE_POS] = c.eng("kenngr.swe_pos")
    pr[s, L.P_CAM_POS] = c.eng("sim.ref_cam_pos")
    pr[s, L.P_SPEED_BAND] = c.eng("kenngr.vb_prozent") if spindle else 0.1
    pr[s, L.P_V_ZERO] = c.eng("getriebe.vb_min_null", g)
    pr[s, L.P_INPOS_WIN] = c.eng("kenngr.exact_stop_window")
    pr[s, L.P_MODULO] = 360.0 if spindle else 0.0
    pr[s, L.P_V_CTRL_LIMIT] = (
        (c.eng("getriebe.vb_regelgrenze", g) or math.inf) if spindle else math.inf
    )
    pr[s, L.P_V_SPEED_CTRL] = changeover_speeds(c)[0] if spindle else math.inf
    pr[s, L.P_SENSORLESS] = float(spindle and c.flag("sim.sensorless"))
    # a speed-controlled spindle outputs its command speed with the v_reso scaling
    pr[s, L.P_V_RESO] = (
        v_reso_digits_per_unit_s(
            c.eng("antr.v_reso_num"),
            c.eng("antr.v_reso_denom"),
            int(c.raw("antr.v_time_base")),
            k.cycle_s,
        )
        if open_position_loop(c)
        else 0.0
    )
    curve = "getriebe.beschl_kennlinie."
    pr[s, L.P_CURVE_TYPE] = c.raw(curve + "typ", g) if spindle else 0
    for col, name in (
        (L.P_N_LIMIT, "n_grenz"),
        (L.P_A_KONST, "a_konst"),
        (L.P_B1, "b1"),
        (L.P_B2, "b2"),
        (L.P_B3, "b3"),
        (L.P_A_MIN, "a_min"),
        (L.P_CURVE_A_MAX, "a_max"),
        (L.P_N1, "n1"),
        (L.P_N2, "n2"),
    ):
        pr[s, col] = c.eng(curve + name, g)
    a_cap = c.eng("getriebe.dynamik.a_max", g)
    if ax.tool.a_max is not None:
        a_cap = min(a_cap, ax.tool.a_max)
    pr[s, L.P_A_CAP] = a_cap
    k.ist[s, L.I_GEAR] = g


def power_on(k: Kernel, ax: Axis) -> None:
    """Place the load at its power-on position with the NC position following it."""
    s = ax.slot
    x = ax.cfg.eng("sim.start_pos")
    k.st[s, L.S_X_MOTOR] = x  # the encoder sits on the load: physical = measured
    inc = k.pr[s, L.P_ENC_INC]
    counts = round(k.st[s, L.S_X_MOTOR] / inc) * inc if inc > 0 else k.st[s, L.S_X_MOTOR]
    p = k.pr[s, L.P_ENC_SIGN] * k.pr[s, L.P_SIGN_FB] * counts
    k.st[s, L.S_P_ACT] = k.st[s, L.S_P_CMD] = p
    x, cam, mod = k.st[s, L.S_X_MOTOR], k.pr[s, L.P_CAM_POS], k.pr[s, L.P_MODULO]
    k.ist[s, L.I_CAM] = math.floor((x - cam) / mod) if mod > 0 else int(x >= cam)
    k.st[s, L.S_OVERRIDE] = 1.0
