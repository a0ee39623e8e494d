"""What a machine shows at one cycle: axes, spindles, PLC, active job errors, event cursor.

`Machine.snapshot()` fills these records between cycles; they are plain frozen values in
engineering units (positions mm | °, speeds mm/min | °/min, spindles rpm), so a reader in
another process needs neither the kernel nor the machine. This module imports nothing that
computes: the gateway imports it without numba.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum, StrEnum
from typing import Literal

from nc_sim.events import Event
from nc_sim.plc import PlcMode
from nc_sim.units import AxisKind


class AxisState(IntEnum):
    """Operating state shown in the HLI and traces."""

    STANDSTILL = 0
    MOVING = 1  # positioning (G00/G01, incremental jog, M19 later)
    JOG = 2  # continuous jog
    HOMING = 3
    ENDLESS = 4  # spindle M3/M4
    STOPPING = 5
    POSITIONING = 6  # spindle M19
    OPEN_LOOP = 7  # spindle rotating above the control limit vb_regelgrenze
    GEAR_CHANGE = 8  # spindle at the change position, waiting for the PLC
    ERROR = 9
    CHANGEOVER = 10  # spindle <-> rotary axis C [003 Fig. 4-1]: braking, waiting for the PLC


# the shown state of an axis whose set-point is at rest while the axis itself still moves into
# its exact-stop window (nc_sim/machine/readout.py): not an NC state of its own
SETTLING = "SETTLING"


class LoopMode(StrEnum):
    """The position loop as the drive runs it."""

    OPEN = "open"  # servo off: the drive lacks its enables and does not follow
    CLOSED = "closed"  # position control
    CONTROL_LIMIT = "control_limit"  # spindle above vb_regelgrenze: open loop [000 §2.7]
    SPEED_CONTROL = "speed_control"  # spindle changed over to speed control [001 §2.3]


@dataclass(frozen=True)
class SpindleSnapshot:
    """The spindle part of an axis' snapshot."""

    gear: int  # active gear stage 1..6 (M40..M45)
    speed_prog_rpm: float  # programmed S, before override
    speed_reached: bool
    stopped: bool
    speed_monitoring_active: bool
    speed_monitoring_invalid: bool
    # a main spindle with rotary-axis capability [003]: "spindle", "rotary" or "none" (in
    # neither: changing over, or the PLC acknowledges none); None for other spindles
    mode: str | None = None
    changeover: str | None = None  # its phase: internal, external, interrupted; None


@dataclass(frozen=True)
class InterfaceSignals:
    """The axis status signals of 003 §4.2 worth showing (the MTC's names in comments)."""

    homed: bool  # HOMED
    moving_positive: bool  # MVPOS: the actual speed is positive
    moving_negative: bool  # MVNEG
    ready: bool  # READY / BBDIG: the drive follows (enables and its ready status)
    in_position: bool  # INPOS
    speed_reached: bool | None  # N_NCMD: N_act = N_comm (spindles)
    stopped: bool | None  # N_NMIN: N_act = 0 (spindles)
    gear_bits: tuple[bool, bool, bool] | None  # GEAR1..GEAR3: the gear stage in binary
    rotary_mode: bool | None  # rotary axis / main spindle operation; None without C


@dataclass(frozen=True)
class HomingSnapshot:
    """A G74 in progress [002 §2.7]: its phase, how far the axis moved since it began, and the
    distance left where the NC knows it (to ref_pos; a search does not know where the cam is)."""

    phase: str  # "search for the cam", "leaving the cam", "to the reference position"
    moved: float  # from where G74 began, signed, pos_unit (the reference's shift not counted)
    to_go: float | None  # to ref_pos in its last phase, pos_unit; None while searching
    speed: float  # the phase's commanded speed, vel_unit (before override)


@dataclass(frozen=True)
class AxisSnapshot:
    """One axis or spindle: state, actual values, its HLI objects and drive status."""

    name: str
    kind: AxisKind
    state: str  # AxisState name: STANDSTILL, MOVING, ... ERROR
    pos_unit: str  # "mm" (linear) or "deg" (rotary axes, spindles): positions and lag
    vel_unit: str  # "mm/min", "°/min" or "rpm" (spindles): vel_cmd, vel_act
    pos_cmd: float
    pos_act: float
    lag: float
    vel_cmd: float
    vel_act: float
    homed: bool
    in_position: bool
    target_pos: float | None  # target of the active or last positioning, None without
    distance_to_go: float | None  # target − commanded position, None without a target
    enabled: bool  # every drive enable present
    missing_enables: tuple[str, ...]
    # drive status [004 §4.2]; None where the drive type does not report the signal
    ready_for_power_on: bool | None
    ready_for_control_loop_on: bool | None
    control_units: dict[str, int]  # HLI control units as written
    override_pct: float  # override in force, %
    job_error: int  # code of the active job error, 0 none
    loop: LoopMode
    spindle: SpindleSnapshot | None  # None for axes
    display_name: str = ""  # the name that follows the mode: C as the rotary axis, else name
    signals: InterfaceSignals | None = None
    homing: HomingSnapshot | None = None  # G74 of an axis in progress


@dataclass(frozen=True)
class PendingMSnapshot:
    """An M function (or a mode request ROTMOD/SPMOD, `signal`) output to the PLC and not yet
    acknowledged."""

    m: int | None
    axis: str
    out_cycle: int
    signal: str | None = None
    timeout_cycle: int | None = None  # the NC gives up (90004) at this cycle


@dataclass(frozen=True)
class PlcSnapshot:
    mode: PlcMode
    ack_delay_s: float  # auto mode acknowledges this long after the output
    drives_powered: bool  # power-on done: every drive switched on and reporting ready
    pending: tuple[PendingMSnapshot, ...]
    # the spindle/rotary-axis handshake [003 §4.1]: ROTMOD, SPMOD (the NC's requests) and
    # ROTMOD_Q, SPMOD_Q (the PLC's acknowledgements); empty without a C axis
    signals: tuple[tuple[str, bool], ...] = ()


class ChannelState(IntEnum):
    """Program execution state of the channel (recorded as `CH.state`)."""

    IDLE = 0  # no program loaded: MDI
    READY = 1  # a program is loaded and waits for cycle start
    RUNNING = 2
    HELD = 3  # feedhold
    BLOCK_END = 4  # single block: stopped at the end of a block
    ERROR = 5  # a job error stopped the program


@dataclass(frozen=True)
class ModalSnapshot:
    motion: int  # 0..3 (G00..G03)
    plane: int  # 17..19
    absolute: bool  # G90
    feed_mm_min: float | None
    slope: int  # P-CHAN-00071 / #SLOPE
    parallel_manual: bool = False  # G201 in force [002 §2.6.2]


@dataclass(frozen=True)
class ChannelSnapshot:
    """The channel: program, position in it, modal state, what the path waits for."""

    state: ChannelState
    program: str | None
    block_line: int | None
    blocks_done: int
    single_block: bool
    mdi: bool  # MDI blocks run (state RUNNING while they do)
    modal: ModalSnapshot
    path_feed_mm_min: float
    distance_to_go_mm: float | None
    waiting_for: str | None
    error: Event | None
    axes: tuple[str, ...] = ()  # its path axes as NC text names them (X, Z, C)
    rotary_axis: str | None = None  # the main spindle's rotary-axis name (C), None without
    rotary: bool = False  # ... and whether the main spindle is that axis now


@dataclass(frozen=True)
class MachineSnapshot:
    """A machine at the end of one cycle, consistent in itself."""

    cycle: int
    t_s: float  # simulated time, s
    channel_units: dict[str, int]  # override (‰), feedhold, reduced_acceleration
    emergency_stop: bool
    queued_blocks: int  # MDI blocks waiting or running
    channel: ChannelSnapshot
    axes: tuple[AxisSnapshot, ...]
    plc: PlcSnapshot
    job_errors: tuple[Event, ...]  # the event behind each active job error, once each
    event_cursor: int  # sequence number the next event will get


# --- the service-axis view (nc_sim/machine/service.py) ------------------------------------
LimitKind = Literal["parameter", "programmed", "reduced_speed", "reduced_acceleration", "tool"]


@dataclass(frozen=True)
class LimitInForce:
    """A dynamic limit in force (velocity in the axis' display unit, acceleration unit/s²,
    jerk unit/s³) and where it comes from."""

    value: float
    unit: str
    source: str  # list name (`getriebe[0].dynamik.vb_max`), `F`, `S`, `jog feed`, ...
    param_id: str | None
    kind: LimitKind
    override_pct: float | None = None  # the override that scales it, None when none does


@dataclass(frozen=True)
class GainReading:
    """k = v / lag from the newest records, or why it is not shown."""

    k_per_s: float | None
    why_not: str | None


@dataclass(frozen=True)
class AxisServiceSnapshot:
    """One axis or spindle in the service-axis view."""

    name: str
    gear: int  # the active gear record (1..)
    kv_per_s: float  # getriebe[gear-1].kv of the active record, 1/s
    ff_weight: float  # feedforward weight 0..1 in force
    multi_gain: float  # multi_gain_z / multi_gain_n: digits for 1 m/min or 1000 °/min
    lag_max: float  # getriebe.lag_max (mm | °)
    v_cmd: float  # commanded speed, unit/s (mm/s | °/s)
    lag_expected: float | None  # (1 − ff)·v / kv (mm | °), None without a closed loop
    lag_expected_why_not: str | None
    gain: GainReading
    da_digits: float  # manipulated variable at the D/A
    da_max_digits: float  # lr_hw.da_max
    velocity: LimitInForce
    acceleration: LimitInForce
    jerk: LimitInForce | None  # None: step-shaped, jerk not limited
    jerk_why_none: str | None
