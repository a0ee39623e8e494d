"""The command surface of a machine: one frozen dataclass per command, and its outcome.

These are the messages a process boundary carries (LinuxCNC's command channel with serial
numbers, ruckig's `Result`): `Machine.submit(cmd)` is the one way in and always answers with
an `Outcome`, never an exception. Every command carries the caller's `serial` (0 = none),
returned in its outcome so a caller can match answers to requests. Units are in the field
names where they are ambiguous; positions and distances are mm for linear axes, ° for rotary
axes and spindles.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from nc_sim.events import Event

# --- commands ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Mdi:
    """One NC block for the MDI channel, e.g. `M3 S1000` or `G01 X10 F500`."""

    block: str
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class SpindleRun:
    """M3/M4 with a speed (S word, rpm; None keeps the programmed one), or M5."""

    spindle: str  # S is the main spindle
    m: int  # 3, 4 or 5
    speed_rpm: float | None = None
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class SpindlePosition:
    """M19 S.POS: orient the spindle to an angle, M3 (+1) / M4 (-1) or the shortest way."""

    spindle: str
    position_deg: float  # modulo 360
    direction: int | None = None  # +1 M3, -1 M4, None the shortest way
    speed_rpm: float | None = None
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class GearChange:
    """M40-M45: gear stage 1-6 of the main spindle (free M functions without P-CHAN-00052)."""

    spindle: str
    m: int  # 40..45
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class Home:
    """G74 homing of an axis or a spindle."""

    axis: str
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class JogStart:
    """Continuous jog with G200 dynamics until `JogStop` (the host owns any dead-man)."""

    axis: str
    direction: int  # +1 | -1
    feed_mm_min: float | None = None  # °/min for rotary axes; None: the G200 maximum
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class JogStop:
    """Release of the jog key: brake with the manual-mode deceleration."""

    axis: str
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class JogStep:
    """Incremental jog by a signed distance (mm | °) with G200 dynamics."""

    axis: str
    distance: float  # mm | °, the sign gives the direction
    feed_mm_min: float | None = None
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class Move:
    """Single-axis G00 (rapid) or G01 (feed) move to an absolute position (mm | °)."""

    axis: str
    target: float  # mm | °; a spindle moves there as a modulo axis, the shortest way
    rapid: bool = True
    feed_mm_min: float | None = None
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class HliWrite:
    """Write an HLI control unit of an axis (`axis` set) or of the channel (None)."""

    unit: str  # e.g. DriveOn, override (‰), feedhold
    value: int
    axis: str | None = None
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class PlcMode:
    """PLC behaviour for M functions: auto acknowledge, manual, or fault (never answers)."""

    mode: str  # auto | manual | fault
    delay_s: float | None = None  # auto acknowledge delay; None keeps plc.m_ack_delay
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class PlcAck:
    """Manual acknowledgement of one pending M function, or of all (m = None)."""

    m: int | None = None
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class PlcSignal:
    """The PLC sets or resets a mode acknowledgement by hand: ROTMOD_Q or SPMOD_Q [003 §4.1].
    Setting one answers the NC's pending request; withdrawing the one of the mode in force is
    a process error."""

    signal: str
    on: bool
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class Reset:
    """CNC reset: clears job errors and the block queue, stops motion."""

    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class EmergencyStop:
    """Emergency stop: every axis brakes at a_emergency, the channel stays in error."""

    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class ProgramLoad:
    """Load an NC program into the channel; it runs on `CycleStart`. `name` labels it."""

    name: str
    text: str
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class CycleStart:
    """Run the loaded program from its start, or continue after feedhold or single block."""

    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class Feedhold:
    """Feedhold on (the path brakes on its contour and waits) or off (it continues)."""

    on: bool
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class SingleBlock:
    """Single block on: the program stops at the end of each block until `CycleStart`."""

    on: bool
    serial: int = field(default=0, kw_only=True)


@dataclass(frozen=True)
class ProgramStop:
    """Stop the program on its path and rewind it (it stays loaded)."""

    serial: int = field(default=0, kw_only=True)


Command = (
    Mdi
    | ProgramLoad
    | CycleStart
    | Feedhold
    | SingleBlock
    | ProgramStop
    | SpindleRun
    | SpindlePosition
    | GearChange
    | Home
    | JogStart
    | JogStop
    | JogStep
    | Move
    | HliWrite
    | PlcMode
    | PlcAck
    | PlcSignal
    | Reset
    | EmergencyStop
)

# --- outcomes ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Accepted:
    """The NC took the command. An MDI block is accepted once it parsed and either started
    without a job error or waits in the queue behind a running block: a queued block has not
    started yet, so a job error it raises later goes only to the event log."""

    serial: int  # the command's serial
    cycle: int  # cycle the command took effect in
    block_id: int | None = None  # MDI: the block's number
    acknowledged: int | None = None  # PLC acknowledgement: M functions acknowledged


@dataclass(frozen=True)
class Refused:
    """The NC refused the command with a job error (also in the event log): a precondition
    failed, or an MDI block failed while starting."""

    serial: int  # the command's serial
    error: Event  # the job error the command raised

    @property
    def cycle(self) -> int:
        """Cycle the refusal happened in."""
        return self.error.cycle

    @property
    def code(self) -> int:
        """Job error code, e.g. 90001."""
        return self.error.code

    @property
    def detail(self) -> str:
        """The job error's message: its meaning and what it concerned (names a limit)."""
        return self.error.message


@dataclass(frozen=True)
class Invalid:
    """The command is malformed and changed nothing: an NC block that does not parse (logged
    as job error 90010), or a name or value no machine command has (unknown axis, not a
    spindle, unknown HLI unit, M41 as a spindle direction). Misuse is an outcome, not an
    exception: a process boundary carries answers, not tracebacks."""

    serial: int  # the command's serial
    message: str  # what is wrong
    column: int | None = None  # NC block or program: 1-based column of the error
    code: int | None = None  # the job error logged for it: 90010 for a block, else None
    line: int | None = None  # NC program: 1-based line of the error


Outcome = Accepted | Refused | Invalid
