"""Commands to a machine: one model per command, one union the route accepts."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field

from api.common import unit

AxisName = Annotated[str, Field(min_length=1, max_length=16, description="axis or spindle name")]
SpindleName = Annotated[
    str, Field(min_length=1, max_length=16, description="spindle name; S is the main spindle")
]
Feed = Annotated[float, Field(gt=0, le=1e6, description="feed, mm/min (°/min for rotary)")]
JogFeed = Annotated[
    float,
    Field(
        gt=0,
        allow_inf_nan=False,
        description="jog feed, mm/min (°/min for rotary); the NC refuses one above the axis' "
        "manual-mode maximum handbetrieb.hb.vb_max (P-AXIS-00213)",
    ),
]


class MdiCommand(BaseModel):
    """One NC block for the MDI channel, e.g. `M3 S1000` or `G01 X10 F500`."""

    type: Literal["mdi"] = "mdi"
    block: str = Field(min_length=1, max_length=256)


class SpindleCommand(BaseModel):
    """M3/M4 with a speed, or M5."""

    type: Literal["spindle"] = "spindle"
    spindle: SpindleName = "S"
    m: Literal[3, 4, 5]
    speed_rpm: float | None = Field(
        None, ge=0, allow_inf_nan=False, description="S word, rpm (the NC checks its maximum)"
    )


class SpindlePositionCommand(BaseModel):
    """M19 S.POS: orient the spindle, M3 (+1) / M4 (-1) direction or the shortest way."""

    type: Literal["spindle_position"] = "spindle_position"
    spindle: SpindleName = "S"
    position_deg: float = Field(ge=-1e9, le=1e9, description="M19 target angle, ° (modulo 360)")
    direction: Literal[-1, 1] | None = None
    speed_rpm: float | None = Field(
        None, gt=0, allow_inf_nan=False, description="rpm (the NC checks its maximum)"
    )


class GearCommand(BaseModel):
    """M40-M45: gear stage change of the main spindle."""

    type: Literal["gear"] = "gear"
    spindle: SpindleName = "S"
    m: int = Field(ge=40, le=45, description="M function: M40-M45 select gear stage 1-6")


class HomeCommand(BaseModel):
    """G74 homing of an axis or a spindle."""

    type: Literal["home"] = "home"
    axis: AxisName


class JogCommand(BaseModel):
    """Jog: continuous `start`/`stop`, or an incremental `step` of `distance` (mm | °)."""

    type: Literal["jog"] = "jog"
    axis: AxisName
    action: Literal["start", "stop", "step"]
    direction: Literal[-1, 1] = 1
    distance: float | None = Field(
        None, ge=-1e6, le=1e6, description="step, mm | °", json_schema_extra=unit("mm")
    )
    feed_mm_min: JogFeed | None = None
    hold_s: float | None = Field(
        None,
        gt=0,
        le=5,
        description="dead-man for `start`: the jog stops unless started again within this "
        "many simulated seconds (a UI renews it while the button is held)",
    )


class MoveCommand(BaseModel):
    """Single-axis G0 (rapid) or G1 (feed) move to an absolute position."""

    type: Literal["move"] = "move"
    axis: AxisName
    target: float = Field(ge=-1e9, le=1e9, description="mm | °")
    rapid: bool = True
    feed_mm_min: Feed | None = None


class OverrideCommand(BaseModel):
    """Override of the channel (path axes) or of one axis or spindle, in percent."""

    type: Literal["override"] = "override"
    axis: AxisName | None = Field(None, description="null: the channel's path override")
    percent: float = Field(ge=0, le=200)


HliUnit = Literal[
    "DriveOn",
    "TorquePermission",
    "ReleaseFeedhold",
    "reduced_speed",
    "reduced_speed_zone",
    "reduced_speed_2_zone",
    "spindle_stop_at_program_end",
    "spindle_reset",
    "override_valid",
    "feedhold",
    "reduced_acceleration",
]


class HliCommand(BaseModel):
    """Write an HLI control unit of an axis (`axis` set) or of the channel."""

    type: Literal["hli"] = "hli"
    unit: HliUnit
    value: int = Field(ge=0, le=1)
    axis: AxisName | None = None


class PlcModeCommand(BaseModel):
    """PLC behaviour for M functions: auto acknowledge, manual, or fault (never answers)."""

    type: Literal["plc_mode"] = "plc_mode"
    mode: Literal["auto", "manual", "fault"]
    delay_s: float | None = Field(None, ge=0, le=60, description="auto acknowledge delay, s")


class PlcAckCommand(BaseModel):
    """Manual acknowledgement of one pending M function, or of all (m = null)."""

    type: Literal["plc_ack"] = "plc_ack"
    m: int | None = Field(None, ge=0, le=999)


class PlcSignalCommand(BaseModel):
    """The PLC sets or withdraws a mode acknowledgement by hand [003 §4.1]: setting ROTMOD_Q
    (SPMOD_Q) answers the NC's pending ROTMOD (SPMOD) request; withdrawing the one of the mode
    in force is a process error (90031)."""

    type: Literal["plc_signal"] = "plc_signal"
    signal: Literal["ROTMOD_Q", "SPMOD_Q"]
    on: bool


class ResetCommand(BaseModel):
    """CNC reset: clears job errors and the block queue, stops motion."""

    type: Literal["reset"] = "reset"


class EmergencyStopCommand(BaseModel):
    """Emergency stop: every axis brakes at a_emergency, the channel stays in error. Sent to
    its own route (`POST /api/machines/{mid}/emergency-stop`): anyone who may command may
    stop the machine, holding control or not."""

    type: Literal["emergency_stop"] = "emergency_stop"


ProgramName = Annotated[
    str,
    Field(
        pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}$",
        description="program name: letters, digits, _ . - (1-64, not starting with . or -)",
    ),
]
PROGRAM_MAX_CHARS = 2_000_000  # about 50 000 blocks


class ProgramLoadCommand(BaseModel):
    """Load an NC program into the channel (it runs on `cycle_start`): the stored program
    `name`, or `text` when given (then `name` is only its label). A program that does not
    interpret is refused with the line and column of its first error."""

    type: Literal["program_load"] = "program_load"
    name: ProgramName
    text: str | None = Field(None, max_length=PROGRAM_MAX_CHARS)


class CycleStartCommand(BaseModel):
    """Cycle start: run the loaded program from its start, or continue after feedhold or a
    single-block stop."""

    type: Literal["cycle_start"] = "cycle_start"


class FeedholdCommand(BaseModel):
    """Feedhold on: the path brakes on its contour and waits; off: it continues (as the
    channel's HLI feedhold unit)."""

    type: Literal["feedhold"] = "feedhold"
    on: bool


class SingleBlockCommand(BaseModel):
    """Single block on: the program stops at the end of every block until `cycle_start`."""

    type: Literal["single_block"] = "single_block"
    on: bool


class ProgramStopCommand(BaseModel):
    """Stop the program: the path brakes on its contour, the program is rewound to its start
    (it stays loaded); spindles keep turning as after M0 (a reset stops them)."""

    type: Literal["program_stop"] = "program_stop"


Command = Annotated[
    MdiCommand
    | ProgramLoadCommand
    | CycleStartCommand
    | FeedholdCommand
    | SingleBlockCommand
    | ProgramStopCommand
    | SpindleCommand
    | SpindlePositionCommand
    | GearCommand
    | HomeCommand
    | JogCommand
    | MoveCommand
    | OverrideCommand
    | HliCommand
    | PlcModeCommand
    | PlcAckCommand
    | PlcSignalCommand
    | ResetCommand,
    Field(discriminator="type"),
]


class CommandResult(BaseModel):
    """The acknowledgement of an accepted command."""

    accepted: bool = True
    serial: int = Field(
        description="the machine's number of this command (counting from 1 per service run), "
        "as its outcome records it"
    )
    cycle: int = Field(description="cycle at which the command took effect")
    block_id: int | None = Field(None, description="MDI block number")
    acknowledged: int | None = Field(
        None,
        description="M functions acknowledged (plc_ack); mode requests answered (plc_signal)",
    )
    state: dict[str, str] = Field(
        default_factory=dict, description="state of every axis after the command"
    )
    latency_ms: float = Field(
        0.0,
        description="from the gateway handing the command to the machine's worker until it "
        "took effect in the kernel there, ms",
    )
