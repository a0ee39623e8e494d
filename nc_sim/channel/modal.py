"""Modal state of the channel: what a block inherits from the blocks before it."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from nc_sim.channel import canon

# plane -> (first axis, second axis, normal axis); G02/G03 turn as seen from +normal
PLANES: dict[int, tuple[str, str, str]] = {
    17: ("X", "Y", "Z"),
    18: ("Z", "X", "Y"),
    19: ("Y", "Z", "X"),
}
CENTRE_LETTER = {"X": "I", "Y": "J", "Z": "K"}  # incremental centre offsets per axis
PITCH_AXIS = {"I": "X", "J": "Y", "K": "Z"}  # G33: the axis each pitch letter is measured on


@dataclass
class Modal:
    """Motion mode (0-3, 33 thread cutting, 63 tapping), plane (17-19), absolute (G90) or
    incremental (G91), diameter programming (G51) or radius (G52), feed in mm/min, the main
    spindle's last programmed speed (G63 taps at it), the G33 pitch and offset angle.

    At program start: G00, G17, G90, G52, no feed (G01/G02/G03 need an F first), no speed, no
    pitch, offset 0°; the position is where the program starts (the machine's, given to the
    interpreter). Pitch and offset stay until the program ends [000 §2.8.7]; so do the
    G130-G133 weightings (100 % at the start).
    """

    motion: int = 0
    plane: int = 17
    absolute: bool = True
    diameter: bool = False  # G51: X words are diameters (the machine's X is the radius)
    feed_mm_min: float | None = None
    speed_rpm: float | None = None  # last S of the main spindle; negative only from G63
    pitch: tuple[str, float] | None = None  # G33: letter I/J/K and mm per revolution
    thread_offset_deg: float = 0.0  # G33 S.OFFSET=, 0 <= offset < 360
    rotary: bool = False  # the main spindle is the rotary axis C (003), not a spindle
    position: dict[str, float] = field(default_factory=dict)  # NaN: not known (C as spindle)
    home_position: dict[str, float] = field(default_factory=dict)  # where G74 ends, per axis
    # G130/G131 and G132/G133: percent per axis, an axis not named is at 100 [002 §2.5.1]
    acceleration_weight: dict[str, float] = field(default_factory=dict)
    ramp_time_weight: dict[str, float] = field(default_factory=dict)
    vector_limit: canon.VectorLimit | None = None  # #VECTOR LIMIT in force [002 §2.5.2]
    parallel_manual: bool = False  # G201 in force, G200 the default [002 §2.6]


def target(end: Mapping[str, float], axes: tuple[str, ...]) -> tuple[tuple[str, float], ...]:
    """A motion call's end point: the axes whose positions are known (C is not while the
    main spindle is a spindle, so a block without C leaves it alone)."""
    return tuple([(a, end[a]) for a in axes if not math.isnan(end[a])])
