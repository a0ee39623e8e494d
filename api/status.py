"""Status snapshots: a machine with its axes, HLI and PLC, and the service itself."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from api.assist import AssistProgress
from api.common import JobErrorModel
from api.control import ControlState

SimMode = Literal["run", "pause", "fast"]


SpindleModeName = Literal["spindle", "rotary", "none"]
ChangeoverPhase = Literal["internal", "external", "interrupted"]
HomingPhaseName = Literal["search for the cam", "leaving the cam", "to the reference position"]


class AxisSignals(BaseModel):
    """The axis status signals of 003 §4.2 worth showing."""

    homed: bool = Field(description="HOMED: the axis is homed")
    mvpos: bool = Field(description="MVPOS: moving in the positive direction")
    mvneg: bool = Field(description="MVNEG: moving in the negative direction")
    ready: bool = Field(description="READY: the drive follows (enables and ready status)")
    inpos: bool = Field(description="INPOS: in position")
    n_act_eq_n_comm: bool | None = Field(None, description="N_NCMD: N_act = N_comm (spindles)")
    n_act_zero: bool | None = Field(None, description="N_NMIN: N_act = 0 (spindles)")
    gear_bits: list[bool] | None = Field(
        None, description="GEAR1..GEAR3: the gear stage in binary, GEAR1 first (spindles)"
    )
    rotary_mode: bool | None = Field(
        None,
        description="rotary axis mode (true) or spindle mode (false) of a main spindle with "
        "rotary-axis capability; null for other axes",
    )


class HomingProgress(BaseModel):
    """A G74 of an axis in progress [002 §2.7]."""

    phase: HomingPhaseName = Field(
        description="to the cam at vb_refmax, off it at vb_reflow (the zero pulse at its edge "
        "sets ref_pos), then to ref_pos at vb_reflow"
    )
    moved: float = Field(
        description="from where G74 began, signed, mm or ° (the reference set on the way "
        "does not count as motion)"
    )
    to_go: float | None = Field(
        description="distance left to ref_pos in the last phase, mm or °; null while searching "
        "(the NC does not know where the cam is)"
    )
    speed: float = Field(description="the phase's speed before override, mm/min or °/min")


class AxisStatus(BaseModel):
    """One axis or spindle: state, actual values and its HLI objects."""

    name: str
    kind: Literal["linear", "rotary", "spindle"]
    state: str = Field(description="STANDSTILL, MOVING, JOG, HOMING, ENDLESS, ... ERROR")
    unit: str = Field(description="mm or deg")
    pos_cmd: float
    pos_act: float
    lag: float = Field(description="position lag, same unit as the position")
    vel_cmd: float = Field(
        description="unit/min (mm/min, °/min); rpm for spindles, °/min for a spindle while it "
        "is the rotary axis C"
    )
    vel_act: float
    homed: bool
    in_position: bool
    target_pos: float | None = Field(
        None, description="target position of the active or last positioning (HLI), None without"
    )
    distance_to_go: float | None = Field(
        None, description="target position − commanded position (HLI), None without a target"
    )
    enabled: bool = Field(description="all drive enables present")
    missing_enables: list[str]
    ready_for_power_on: bool | None = Field(
        None, description="drive status [004 §4.2]; None when the drive type does not report it"
    )
    ready_for_control_loop_on: bool | None = Field(
        None, description="drive status [004 §4.2]; None when the drive type does not report it"
    )
    control_units: dict[str, int] = Field(description="HLI control units as written")
    override_pct: float
    job_error: int = Field(description="active job error code, 0 none")
    gear: int | None = Field(None, description="active gear stage 1..6 (spindles)")
    speed_prog_rpm: float | None = Field(None, description="programmed S, rpm (spindles)")
    speed_reached: bool | None = None
    stopped: bool | None = None
    speed_monitoring_active: bool | None = None
    speed_monitoring_invalid: bool | None = None
    loop: Literal["open", "closed", "control_limit", "speed_control"] = Field(
        description="position loop: open while the drive lacks its enables (servo off)"
    )
    display_name: str = Field(
        description="the name that follows the mode: the rotary-axis name (C) while a main "
        "spindle with rotary-axis capability is the rotary axis, else `name` [003 §2.4]"
    )
    spindle_mode: SpindleModeName | None = Field(
        None,
        description="a main spindle with rotary-axis capability: spindle, rotary axis, or "
        "none (changing over, or the PLC acknowledges no mode); null for other axes",
    )
    changeover: ChangeoverPhase | None = Field(
        None,
        description="the phase of a changeover in progress [003 Fig. 4-1]: internal (braking, "
        "parameter record), external (waiting for ROTMOD_Q/SPMOD_Q), interrupted (by an "
        "immediate stop: reset or a jog/spindle key ends it); null without one",
    )
    signals: AxisSignals
    homing: HomingProgress | None = Field(None, description="G74 in progress; null without")


class PendingM(BaseModel):
    """An M function (or a mode request ROTMOD/SPMOD) waiting for the PLC's answer."""

    m: int | None = Field(description="the M function; null for a mode request")
    axis: str
    out_cycle: int
    signal: str | None = Field(
        None, description="the mode request ROTMOD or SPMOD (answered by <signal>_Q)"
    )
    timeout_cycle: int | None = Field(
        None,
        description="the NC gives up waiting at this cycle (P-CHAN plc.m_ack_timeout after the "
        "output): job error 90004",
    )


class PlcStatus(BaseModel):
    mode: Literal["auto", "manual", "fault"]
    ack_delay_s: float
    drives_powered: bool = Field(
        description="power-on done: every drive switched on and reporting ready"
    )
    pending: list[PendingM]
    signals: dict[str, bool] = Field(
        default_factory=dict,
        description="the spindle/rotary-axis handshake [003 §4.1]: ROTMOD, SPMOD (the NC's "
        "requests), ROTMOD_Q, SPMOD_Q (the PLC's acknowledgements); empty without a C axis",
    )


class SimulationStatus(BaseModel):
    """How the machine's simulated time is paced."""

    mode: SimMode
    cycle: int
    epoch: int = Field(
        description="the machine's build: grows by one with every power-on (restart), restore "
        "from a snapshot and rebuild after its worker died; values that waited for a restart "
        "are in force from a new epoch on",
    )
    t_s: float = Field(description="simulated time, s")
    cycle_s: float
    rt_factor: float = Field(description="simulated seconds per wall second, last ~1 s")
    until_cycle: int | None = Field(None, description="fast mode pauses at this cycle")
    t0_unix: float = Field(description="wall time (Unix s) of cycle 0 while running")
    slips: int = Field(description="times the machine fell over 1 s behind and was re-anchored")
    worker: str | None = Field(None, description="the worker whose loop paces this machine")
    loop_overruns: int = Field(0, description="overruns of that worker's loop so far")
    loop_work_p99_ms: float = Field(0.0, description="that loop's work per tick, 99th pct, ms")


ChannelStateName = Literal["idle", "ready", "running", "held", "block_end", "error"]


class ModalStatus(BaseModel):
    """The channel's modal state: what the next block inherits."""

    motion: Literal["G00", "G01", "G02", "G03", "G33", "G63"] = Field(
        description="motion group: G00-G03, G33 thread cutting, G63 tapping"
    )
    plane: Literal["G17", "G18", "G19"]
    distance: Literal["G90", "G91"]
    feed_mm_min: float | None = Field(description="F in force, mm/min; null before the first F")
    slope: int = Field(description="acceleration profile (#SLOPE, P-CHAN-00071): 0 step ... 3 HSC")
    manual_mode: Literal["G200", "G201"] = Field(
        "G200",
        description="G201: the path's axes may be jogged while it runs (manual mode with "
        "parallel path interpolation); G200: not [002 §2.6]",
    )


class ChannelStatus(BaseModel):
    """The NC channel: its program, where it is in it, and what the path waits for."""

    state: ChannelStateName = Field(
        description="idle: no program loaded (MDI); ready: loaded, waiting for cycle start; "
        "running; held: feedhold; block_end: single block stop; error: a job error stopped it"
    )
    program: str | None = Field(description="name of the loaded program")
    block_line: int | None = Field(description="line (from 1) of the block the path is in")
    blocks_done: int = Field(description="blocks of the program finished since cycle start")
    single_block: bool
    mdi: bool = Field(
        description="MDI blocks run: the state is running while they do, block_line is null, "
        "and the modal state is what the next MDI block starts from"
    )
    modal: ModalStatus
    path_feed_mm_min: float = Field(description="commanded path velocity now, mm/min")
    distance_to_go_mm: float | None = Field(description="path length left in the current block, mm")
    waiting_for: str | None = Field(
        description="what the path waits for, in the operator's words (speed reached of S, "
        "the PLC's acknowledgement of M8, dwell), null when it moves or is done"
    )
    error: JobErrorModel | None = Field(
        description="the program error or job error that stopped the program, with line"
    )


class MachineStatus(BaseModel):
    """A full snapshot of one machine."""

    id: str
    name: str
    simulation: SimulationStatus
    channel_units: dict[str, int] = Field(description="override (‰), feedhold, ...")
    emergency_stop: bool
    queued_blocks: int
    channel: ChannelStatus
    axes: list[AxisStatus]
    plc: PlcStatus
    job_errors: list[JobErrorModel] = Field(description="active job errors, one per axis")
    recent_events: list[JobErrorModel] = Field(description="the newest 50 events and errors")
    control: ControlState = Field(description="who holds the machine, who asks for it")
    assist: AssistProgress | None = Field(
        None, description="a commissioning assistant running live on the machine"
    )


class MachineSummary(BaseModel):
    id: str
    name: str
    source: Literal["demo", "lists"]
    axes: list[str]
    mode: SimMode
    cycle: int
    seat: bool = Field(
        description="a class's seat: it has an exercise (GET /api/machines/{id}/exercise)"
    )


class OverrunRecord(BaseModel):
    """One overrun: whether the loop woke late (held up) or its work took long."""

    time_unix: float
    wake_late_ms: float
    work_ms: float


class LoopStatus(BaseModel):
    """A worker's real-time loop, which paces the worker's machines."""

    period_s: float = Field(
        description="loop period, s (it steps every due cycle per tick; the longest, 0.01 s, "
        "while every machine of the worker rests)"
    )
    ticks: int
    overruns: int = Field(description="ticks whose work ran past the next deadline")
    missed_deadlines: int = Field(description="deadlines skipped after overruns")
    work_p50_ms: float = Field(
        description="time the loop was busy per tick (stepping its machines and carrying out "
        "requests), median"
    )
    work_p99_ms: float
    work_max_ms: float = Field(description="the longest, a stall of the loop included")
    wake_late_p99_ms: float = Field(description="how late the loop woke, 99th percentile")
    recent_overruns: list[OverrunRecord] = Field(description="the last 20 overruns")
    host_failures: int = Field(
        description="machine ticks that raised; the machine was paused, the loop went on"
    )
    cpu_pct: float = Field(description="CPU time of the worker process, % of one core")


class WorkerStatus(BaseModel):
    """One worker: a process on this server or a Ray actor on a cluster node."""

    id: str
    pid: int | None
    node: str = Field(description="'local', or the Ray node the actor runs on")
    alive: bool
    machines: list[str]
    loop: LoopStatus | None = Field(description="figures of its last report (about 1 s old)")


class TelemetryStatus(BaseModel):
    """The telemetry hub that sends frames and events to websocket clients."""

    frames_sent: int
    clients_dropped: int = Field(
        description="clients we disconnected: not reading, flooding, bad messages, failures"
    )
    restarts: int = Field(description="times the hub failed and was restarted")


class ServiceStatus(BaseModel):
    version: str
    uptime_s: float
    transport: Literal["local", "ray"] = Field(description="how the gateway reaches workers")
    workers: list[WorkerStatus]
    workers_replaced: int = Field(description="workers that died and were replaced")
    machines_rebuilt: int = Field(description="machines rebuilt after their worker died")
    clients: int = Field(description="telemetry websockets connected")
    telemetry: TelemetryStatus
    machines: dict[str, SimulationStatus]
