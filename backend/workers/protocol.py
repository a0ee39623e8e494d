"""What the gateway and a worker say to each other: requests with an id, one reply each, and
pushes the worker sends on its own (LinuxCNC's command / status / error channels).

Every message is a frozen dataclass of plain values and nc_sim records, so it pickles the
same through a local pipe and through Ray. Nothing here imports the kernel: the gateway
builds requests and reads replies without it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from backend.workers.flight import FlightWindow
from nc_sim import commands as nc
from nc_sim.commands import Outcome
from nc_sim.config import MachineConfig, ValueWrite
from nc_sim.events import Event
from nc_sim.faults import Fault, FaultState, Trigger
from nc_sim.params import Value
from nc_sim.scope import Record, ScopeSetup
from nc_sim.signals import Signal
from nc_sim.snapshot import AxisServiceSnapshot, MachineSnapshot

Mode = Literal["run", "pause", "fast"]
# parameter values a worker writes into a machine's lists
Values = list[ValueWrite]
ParamSnapshot = dict[tuple[str, str], dict[str, Value]]


def param_snapshot(cfg: MachineConfig) -> ParamSnapshot:
    """A machine's parameter lists as written now (cheap copies)."""
    params: ParamSnapshot = {("channel", ""): dict(cfg.channel), ("tool", ""): dict(cfg.tools)}
    for a in cfg.axes:
        params[("axis", a.name)] = dict(a.values)
    return params


# --- requests ---------------------------------------------------------------------------
@dataclass(frozen=True)
class AddMachine:
    """Build a machine powered on at cycle 0 and pace it in real time (also a rebuild)."""

    mid: str
    name: str
    cfg: MachineConfig
    epoch: int  # the gateway counts builds: telemetry readers restart when it changes
    mode: Mode = "run"
    state: bytes | None = None  # a snapshot to restore instead of powering on (TakeSnapshot)
    faults: list[tuple[Fault, Trigger]] = field(default_factory=list)  # injected when built
    exercise: object | None = None  # nc_sim.training Exercise whose checks the worker evaluates
    # the flight recorder's seconds before and after each job error (None: no windows)
    flight_s: tuple[float, float] | None = None


@dataclass(frozen=True)
class RemoveMachine:
    mid: str


@dataclass(frozen=True)
class Submit:
    """One command to a machine. `jog_hold_s` renews (a number) or drops (None with
    `jog_release`) the dead-man lease of a continuous jog; `then_apply` are values written
    in the same cycle when the command is accepted (pending values at reset)."""

    mid: str
    cmd: nc.Command
    jog_hold_s: float | None = None
    jog_release: bool = False
    then_apply: Values = field(default_factory=list)


@dataclass(frozen=True)
class Pace:
    mid: str
    mode: Mode
    until_cycle: int | None = None


@dataclass(frozen=True)
class Step:
    """Pause and advance `cycles`; answered when done or ended early (E-stop, new pacing)."""

    mid: str
    cycles: int


@dataclass(frozen=True)
class ApplyValues:
    """Write accepted parameter values into the running machine (at a cycle boundary)."""

    mid: str
    values: Values


@dataclass(frozen=True)
class ReadStatus:
    """A fresh status of the machine, consistent to one cycle."""

    mid: str


@dataclass(frozen=True)
class ReadServiceAxes:
    """The service-axis view of every axis and spindle (nc_sim/machine/service.py), from the
    machine and its newest records; answered with a ServiceAxesRead."""

    mid: str


@dataclass(frozen=True)
class Watch:
    """Push this machine's status at the status rate while `on` (someone watches it)."""

    mid: str
    on: bool


@dataclass(frozen=True)
class ScopeArm:
    """Arm the scope. With `drive` channels (one axis' drive signals) it captures those at
    the drive's rate over the span the NC setup's trigger and length give."""

    mid: str
    setup: ScopeSetup
    drive: list[Signal] = field(default_factory=list)


@dataclass(frozen=True)
class ScopeAct:
    mid: str
    action: Literal["force", "stop", "state"]


@dataclass(frozen=True)
class ScopeRoll:
    """The newest record length of a running scope, every stride-th cycle."""

    mid: str
    max_points: int


@dataclass(frozen=True)
class AssistStart:
    """Run assistant `name` live on the machine (nc_sim/assist/registry.py) with
    `args`; answered when it ends: its result as JSON values, or a Failure."""

    mid: str
    name: str
    args: dict[str, object]
    by: str  # who started it, shown to everyone watching the machine


@dataclass(frozen=True)
class AssistCancel:
    """End the machine's live assistant run now; its motion is stopped."""

    mid: str
    why: str


@dataclass(frozen=True)
class InjectFault:
    """A training fault into a machine's plant or PLC (answered with its FaultState)."""

    mid: str
    fault: Fault
    trigger: Trigger


@dataclass(frozen=True)
class RemoveFault:
    mid: str
    fid: int


@dataclass(frozen=True)
class TakeSnapshot:
    """The machine's whole state, to restore with AddMachine(state=...)."""

    mid: str


Request = (
    AddMachine
    | RemoveMachine
    | Submit
    | Pace
    | Step
    | ApplyValues
    | ReadStatus
    | ReadServiceAxes
    | Watch
    | ScopeArm
    | ScopeAct
    | ScopeRoll
    | AssistStart
    | AssistCancel
    | InjectFault
    | RemoveFault
    | TakeSnapshot
)


# A request on its way: (request id, request, time.monotonic() when the gateway sent it; one
# clock for every process of a host, so a worker can tell how long a command took to act)
Envelope = tuple[int, Request, float]


# --- replies ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Pacing:
    """How a machine is paced and where its time stands."""

    mode: Mode
    cycle: int
    cycle_s: float
    rt_factor: float
    until_cycle: int | None
    t0_unix: float
    slips: int


@dataclass(frozen=True)
class MachineInfo:
    """A machine as built: its signals, where its samples are, and the training faults it
    was built with, each with the id the machine gave it (a restored one's own)."""

    mid: str
    epoch: int
    cycle_s: float
    axes: list[str]
    signals: list[Signal]
    slots: int  # kernel slots (axes) per sample row
    ring_path: str | None  # the shared sample ring, None when samples are pushed
    pacing: Pacing  # as built: the pacing it starts with, before its worker's next news
    faults: list[FaultState] = field(default_factory=list)
    drive_signals: list[Signal] = field(default_factory=list)  # at the drive's rate (scope)


@dataclass(frozen=True)
class Submitted:
    outcome: Outcome
    cycle: int  # the cycle the command took effect in
    state: dict[str, str]  # each axis' state after the command
    latency_s: float  # from the gateway sending it until the kernel took it


@dataclass(frozen=True)
class AssistRunning:
    """A live assistant run in progress: which, the phase, simulated seconds."""

    name: str
    axis: str
    phase: str
    elapsed_s: float
    planned_s: float
    by: str  # who started it (the gateway's actor name)


@dataclass(frozen=True)
class StatusRead:
    """A machine's snapshot and pacing, read in the same cycle, and its live assistant run."""

    snapshot: MachineSnapshot
    pacing: Pacing
    assist: AssistRunning | None = None
    faults: list[FaultState] = field(default_factory=list)  # for instructors only
    checks: list[object] = field(default_factory=list)  # nc_sim.training CheckResult of a seat


@dataclass(frozen=True)
class ServiceAxesRead:
    """The service-axis view of a machine's axes, read at `cycle`."""

    cycle: int
    axes: tuple[AxisServiceSnapshot, ...]


@dataclass(frozen=True)
class Snapshot:
    """A machine's saved state: pickled by nc_sim, restored only from our own snapshots."""

    cycle: int
    t_s: float
    data: bytes
    params: ParamSnapshot  # its lists as written then


@dataclass(frozen=True)
class ScopeState:
    state: str
    cycle: int
    length_cycles: int
    pre_cycles: int
    filled_cycles: int
    trigger_cycle: int | None


@dataclass(frozen=True)
class Roll:
    """A running scope's newest record length."""

    first_cycle: int
    stride: int
    signals: list[str]
    data: object  # np.ndarray channels × samples


@dataclass(frozen=True)
class Failure:
    """The request could not be carried out: `kind` says how the gateway answers."""

    kind: Literal["not_found", "invalid", "conflict", "internal"]
    message: str


# --- pushes -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Reply:
    """The answer to request `req` (a reply, or a Failure)."""

    req: int
    value: object


@dataclass(frozen=True)
class MachineNews:
    """What changed in one machine since the last push: new events always, the status when
    somebody watches, completed scope captures and job error windows."""

    mid: str
    epoch: int
    events: list[Event]
    first_seq: int  # sequence number of events[0]
    status: StatusRead | None  # while watched
    captures: list[tuple[Record, ParamSnapshot]]
    flights: list[FlightWindow] = field(default_factory=list)


@dataclass(frozen=True)
class LoopFigures:
    """A worker's real-time loop over its recent ticks."""

    period_s: float
    ticks: int
    overruns: int
    missed_deadlines: int
    work_p50_ms: float
    work_p99_ms: float
    work_max_ms: float
    wake_late_p99_ms: float
    cpu_pct: float
    host_failures: int
    recent_overruns: list[tuple[float, float, float]]  # unix time, wake late ms, work ms


@dataclass(frozen=True)
class WorkerNews:
    """Sent about once a second: the loop's figures and every machine's pacing."""

    pid: int
    node: str
    loop: LoopFigures
    pacing: dict[str, Pacing]


@dataclass(frozen=True)
class MachineSamples:
    """Kernel records of cycles `first`.. of one machine: how a worker without shared memory
    with the gateway (a Ray actor on another node) fills the gateway's copy of the ring."""

    mid: str
    epoch: int
    first: int  # cycle of rows[0]
    rows: object  # np.ndarray cycles × slots × columns (object: no numpy type in messages)


Push = Reply | MachineNews | WorkerNews | MachineSamples
