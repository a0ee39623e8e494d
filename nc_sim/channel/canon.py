"""Canonical calls: the interpreter's only way out (as LinuxCNC's canon).

The interpreter turns NC text into these calls and hands them to a `Sink`; path planning and
the spindle consume them. Positions are absolute machine coordinates in mm (degrees for rotary
axes), feeds in mm/min, times in s, speeds in rpm. Every call carries the 1-based source `line`.
`text()` gives a stable one-line form for golden files.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Literal, Protocol


def _num(value: float) -> str:
    """Stable number text: 4 decimals (0.1 µm), no trailing zeros, no negative zero."""
    text = f"{value:.4f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _axes(axes: tuple[tuple[str, float], ...]) -> str:
    return " ".join(f"{name}={_num(v)}" for name, v in axes)


@dataclass(frozen=True)
class Call:
    """Base of every canonical call."""

    line: int

    def text(self) -> str:
        """`NAME field=value ...` in field order (the golden-file form), without the line."""
        parts = [_NAMES[type(self)]]
        for f in fields(self):
            if f.name in ("line", "absolute"):
                continue
            value = getattr(self, f.name)
            if f.kw_only and value is False:  # flags show only when set
                continue
            if value is None:
                continue
            if f.name in ("end", "axes"):
                parts.append(_axes(value))
            elif isinstance(value, bool):
                parts.append(f"{f.name}={int(value)}")
            elif isinstance(value, float):
                parts.append(f"{f.name}={_num(value)}")
            elif isinstance(value, tuple):
                parts.append(f"{f.name}=" + ",".join(_num(v) for v in value))
            else:
                parts.append(f"{f.name}={value}")
        return " ".join(p for p in parts if p)


@dataclass(frozen=True)
class StraightTraverse(Call):
    """G00: rapid to `end` (every channel axis, absolute)."""

    end: tuple[tuple[str, float], ...]
    absolute: bool = field(default=True, kw_only=True)  # G90 in force (for the status)
    exact_stop: bool = field(default=False, kw_only=True)  # G60: the path stops at its end


@dataclass(frozen=True)
class StraightFeed(Call):
    """G01: straight line to `end` at the feed set by the last `SetFeedRate`; with effective
    distances RX/RY/RZ (mm) a rotary axis' move counts on the path as the arc the tool
    contact point travels at that distance [003 §1.2]."""

    end: tuple[tuple[str, float], ...]
    absolute: bool = field(default=True, kw_only=True)  # G90 in force (for the status)
    exact_stop: bool = field(default=False, kw_only=True)  # G60: the path stops at its end
    effective: tuple[float, float, float] | None = field(default=None, kw_only=True)


@dataclass(frozen=True)
class ArcFeed(Call):
    """G02/G03 in `plane` (17 XY, 18 ZX, 19 YZ): to `end` about `centre`.

    `centre` holds the plane's two coordinates in the plane's order (G17: X,Y; G18: Z,X;
    G19: Y,Z). `turn` is +1 counter-clockwise (G03), -1 clockwise (G02), seen from the positive
    end of the plane's normal axis. A change of the normal axis in `end` makes it a helix.
    """

    end: tuple[tuple[str, float], ...]
    plane: int
    centre: tuple[float, float]
    turn: int
    absolute: bool = field(default=True, kw_only=True)  # G90 in force (for the status)
    exact_stop: bool = field(default=False, kw_only=True)  # G60: the path stops at its end


@dataclass(frozen=True)
class ThreadFeed(Call):
    """G33 thread cutting [000 §2.8.7]: straight to `end` with the path synchronised to the
    zero passage of the endlessly rotating `spindle`. `pitch_mm` (K, I or J: modal) is the
    lead per revolution measured along `pitch_axis` (K: Z, I: X, J: Y); the cut starts
    `offset_deg` (S.OFFSET=, modal) after the zero passage, for multi-start threads."""

    end: tuple[tuple[str, float], ...]
    spindle: str
    pitch_mm: float
    pitch_axis: str
    offset_deg: float = 0.0
    absolute: bool = field(default=True, kw_only=True)  # G90 in force (for the status)


@dataclass(frozen=True)
class TapFeed(Call):
    """G63 tapping without compensating chuck [000 §2.8.6]: straight to `end` with the path
    coupled to `spindle`, which turns at `speed_rpm` (the last S; negative: left-hand thread
    or retract); the pitch is `feed_mm_min` (the last F) / |S| mm per revolution."""

    end: tuple[tuple[str, float], ...]
    spindle: str
    speed_rpm: float
    feed_mm_min: float
    absolute: bool = field(default=True, kw_only=True)  # G90 in force (for the status)


@dataclass(frozen=True)
class SetFeedRate(Call):
    """F: path feed in mm/min (modal)."""

    feed_mm_min: float


@dataclass(frozen=True)
class SelectPlane(Call):
    """G17/G18/G19."""

    plane: int


@dataclass(frozen=True)
class Dwell(Call):
    """G04: wait `time_s` seconds."""

    time_s: float


@dataclass(frozen=True)
class SpindleOn(Call):
    """M3 (clockwise) or M4 with the speed in force (None: the spindle's last S); `gear` the
    programmed stage 1-6 (M40-M45) checked against the speed, `override_off` G167."""

    spindle: str
    m: int
    speed_rpm: float | None
    gear: int | None = field(default=None, kw_only=True)
    override_off: bool = field(default=False, kw_only=True)


@dataclass(frozen=True)
class SpindleSpeed(Call):
    """S alone: a new speed for the direction in force [000 §2.3.1] (`gear`, `override_off`
    as for `SpindleOn`)."""

    spindle: str
    speed_rpm: float
    gear: int | None = field(default=None, kw_only=True)
    override_off: bool = field(default=False, kw_only=True)


@dataclass(frozen=True)
class SpindleSettings(Call):
    """G135/G136/G137 feedforward on/weighted/off [000 §2.8.1], G167 override off until the next
    programmed speed [000 §2.4.1] (when the block programs no speed), DEFAULT_DYNAMIC_DATA
    (the spindle's own dynamics again at its next start [000 §2.8.5])."""

    spindle: str
    feedforward: int | None = None
    ff_weight_pct: float | None = None
    override_off: bool = field(default=False, kw_only=True)
    default_dynamics: bool = field(default=False, kw_only=True)


@dataclass(frozen=True)
class SpindleOff(Call):
    """M5."""

    spindle: str


@dataclass(frozen=True)
class SpindleOrient(Call):
    """M19 S.POS=..: position to `pos_deg`; `direction` +1 with M3, -1 with M4, None: shortest."""

    spindle: str
    pos_deg: float | None
    speed_rpm: float | None
    direction: int | None


@dataclass(frozen=True)
class RotaryMode(Call):
    """#CAX (`rotary` True) / #CAX OFF: the main spindle `spindle` becomes the rotary path axis
    C, or a spindle again [000 §2.3.3, 003 §4.2]. Programming C, M3/M4/M5/M19, G33 or G63
    switch as well; the channel inserts this call where its mode has to change."""

    spindle: str
    rotary: bool


@dataclass(frozen=True)
class SelectGear(Call):
    """M40-M45 without a speed: gear stage 1-6 of the main spindle [000 §2.8.2]."""

    stage: int


@dataclass(frozen=True)
class SelectTool(Call):
    """T and D words: tool number and tool data (D: tool dynamics, 000 §2.8.5)."""

    tool: int | None
    d: int | None


@dataclass(frozen=True)
class Home(Call):
    """G74: home the named axes in order (1 first); "S" or a spindle name homes a spindle."""

    axes: tuple[tuple[str, float], ...]


@dataclass(frozen=True)
class SetSlope(Call):
    """#SLOPE[TYPE=..]: acceleration profile for path motion (002 §2.2.1, P-CHAN-00071)."""

    slope_type: int


@dataclass(frozen=True)
class Weighting(Call):
    """G130-G133 [002 §2.5.1]: the path axes' acceleration and ramp time weightings in percent
    (100: as the axis list has them) in force from this block on, for feed blocks."""

    acceleration: tuple[tuple[str, float], ...]
    ramp_time: tuple[tuple[str, float], ...]


PathLimit = float | Literal["default"] | None  # as programmed, the channel list's, or none


@dataclass(frozen=True)
class VectorLimit(Call):
    """#VECTOR LIMIT ON/OFF [002 §2.5.2]: the path's own velocity (mm/min), acceleration and
    deceleration limits (in the unit of P-CHAN-00351) in force from this block on, and the
    blocks they act on (feed, rapid traverse)."""

    velocity: PathLimit = None
    acceleration: PathLimit = None
    deceleration: PathLimit = None
    feed: bool = True
    rapid: bool = True


@dataclass(frozen=True)
class ManualMode(Call):
    """G200 exclusive manual mode, G201 manual mode with parallel path interpolation (002 §2.6)."""

    g: int


@dataclass(frozen=True)
class MFunction(Call):
    """An M function the interpreter does not act on itself: output to the PLC."""

    m: int


@dataclass(frozen=True)
class ProgramEnd(Call):
    """M30 or M02."""

    m: int


_NAMES: dict[type[Call], str] = {
    StraightTraverse: "STRAIGHT_TRAVERSE",
    StraightFeed: "STRAIGHT_FEED",
    ArcFeed: "ARC_FEED",
    ThreadFeed: "THREAD_FEED",
    TapFeed: "TAP_FEED",
    SetFeedRate: "SET_FEED_RATE",
    SelectPlane: "SELECT_PLANE",
    Dwell: "DWELL",
    SpindleOn: "SPINDLE_ON",
    SpindleSpeed: "SPINDLE_SPEED",
    SpindleOff: "SPINDLE_OFF",
    SpindleSettings: "SPINDLE_SETTINGS",
    SpindleOrient: "SPINDLE_ORIENT",
    RotaryMode: "ROTARY_MODE",
    SelectGear: "SELECT_GEAR",
    SelectTool: "SELECT_TOOL",
    Home: "HOME",
    SetSlope: "SET_SLOPE",
    Weighting: "WEIGHTING",
    VectorLimit: "VECTOR_LIMIT",
    ManualMode: "MANUAL_MODE",
    MFunction: "M_FUNCTION",
    ProgramEnd: "PROGRAM_END",
}


class Sink(Protocol):
    """Where the interpreter sends its calls."""

    def emit(self, call: Call) -> None:
        """Take one canonical call."""


class ListSink:
    """Collects the calls in order (tests, golden files)."""

    def __init__(self) -> None:
        self.calls: list[Call] = []

    def emit(self, call: Call) -> None:
        """Append `call`."""
        self.calls.append(call)

    def lines(self) -> list[str]:
        """`<line>: <text>` per call, the golden-file form."""
        return [f"{c.line}: {c.text()}" for c in self.calls]
