"""Modal state of the channel: what a block inherits from the blocks before it."""

from __future__ import annotations

from dataclasses import dataclass, field

# plane -> (first axis, second axis, normal axis); G02/G03 turn as seen from +normal
PLANES: dict[int, tuple[str, str, str]] = {
    17: ("X", "Y", "Z"),
    18: ("Z", "X", "Y"),
    19: ("Y", "Z", "X"),
}
CENTRE_LETTER = {"X": "I", "Y": "J", "Z": "K"}  # incremental centre offsets per axis


@dataclass
class Modal:
    """Motion mode (0-3), plane (17-19), absolute (G90) or incremental (G91), feed in mm/min.

    At program start: G00, G17, G90, no feed (G01/G02/G03 need an F first); the position is
    where the program starts (the machine's, given to the interpreter).
    """

    motion: int = 0
    plane: int = 17
    absolute: bool = True
    feed_mm_min: float | None = None
    position: dict[str, float] = field(default_factory=dict)
    home_position: dict[str, float] = field(default_factory=dict)  # where G74 ends, per axis
