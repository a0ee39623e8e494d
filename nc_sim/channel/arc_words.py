"""The words of a G02/G03 block -> its centre [DIN 66025].

    G17 G02 X20 Y0 I10 J0     centre offsets I/J/K from the start, incremental, per axis
    G18 G03 X40 Z-20 R10      radius: R > 0 the arc up to 180°, R < 0 the longer one

A full circle (end = start) needs I/J/K. Start and end radius may differ by
`ARC_RADIUS_TOLERANCE_MM`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from nc_sim.channel import canon
from nc_sim.channel.modal import CENTRE_LETTER, PLANES
from nc_sim.channel.words import Error, Word
from nc_sim.errors import Code

ARC_RADIUS_TOLERANCE_MM = 0.002  # start and end radius of G02/G03 may differ by this much


def arc_feed(
    line: int,
    motion: int,
    plane: int,
    addr: Mapping[str, Word],
    start: Mapping[str, float],
    target: tuple[tuple[str, float], ...],
    col: int,
    error: Error,
    absolute: bool,
    exact_stop: bool,
) -> canon.ArcFeed:
    """G02/G03 (`motion`) in `plane` from `start` to `target` with the block's words `addr`;
    `col` is the block's motion column."""
    a, b, _ = PLANES[plane]
    for axis in (a, b):
        if axis not in start:
            raise error(f"G{plane} needs axis {axis}", col, Code.UNKNOWN_AXIS)
    end = dict(target)
    sa, sb, ea, eb = start[a], start[b], end[a], end[b]
    turn = 1 if motion == 3 else -1
    offsets = [addr[CENTRE_LETTER[x]] for x in (a, b) if CENTRE_LETTER[x] in addr]
    wrong = [addr[c] for c in "IJK" if c in addr and c not in (CENTRE_LETTER[a], CENTRE_LETTER[b])]
    if wrong:
        raise error(
            f"{wrong[0].letter} is not a centre offset in G{plane}",
            wrong[0].column,
            Code.BLOCK_SYNTAX,
        )
    r_word = addr.get("R")
    if r_word is not None and offsets:
        raise error("R and I/J/K in one block", r_word.column, Code.BLOCK_SYNTAX)
    if r_word is not None:
        ca, cb = _centre_from_radius(r_word, sa, sb, ea, eb, turn, error)
    elif offsets:
        ca = sa + (addr[CENTRE_LETTER[a]].value if CENTRE_LETTER[a] in addr else 0.0)
        cb = sb + (addr[CENTRE_LETTER[b]].value if CENTRE_LETTER[b] in addr else 0.0)
        r0, r1 = math.hypot(sa - ca, sb - cb), math.hypot(ea - ca, eb - cb)
        if r0 == 0.0 or abs(r0 - r1) > ARC_RADIUS_TOLERANCE_MM:
            raise error(
                f"start radius {r0:.4f} mm and end radius {r1:.4f} mm differ",
                offsets[0].column,
                Code.ARC_GEOMETRY,
            )
    else:
        raise error(f"G0{motion} needs a centre I/J/K or a radius R", col, Code.ARC_GEOMETRY)
    return canon.ArcFeed(
        line, target, plane, (ca, cb), turn, absolute=absolute, exact_stop=exact_stop
    )


def _centre_from_radius(
    r_word: Word, sa: float, sb: float, ea: float, eb: float, turn: int, error: Error
) -> tuple[float, float]:
    """R > 0: the arc up to 180°, R < 0: the longer one (DIN 66025)."""
    chord = math.hypot(ea - sa, eb - sb)
    radius = abs(r_word.value)
    if chord == 0.0:
        raise error("a full circle needs I/J/K, not R", r_word.column, Code.ARC_GEOMETRY)
    if radius < chord / 2 - ARC_RADIUS_TOLERANCE_MM:
        raise error(
            f"radius {radius:g} mm is less than half the chord {chord:.4f} mm",
            r_word.column,
            Code.ARC_GEOMETRY,
        )
    h = math.sqrt(max(0.0, radius**2 - (chord / 2) ** 2))
    # left of the chord for a counter-clockwise arc up to 180°, right for clockwise
    side = turn * (1 if r_word.value > 0 else -1)
    ua, ub = -(eb - sb) / chord, (ea - sa) / chord
    return (sa + ea) / 2 + side * h * ua, (sb + eb) / 2 + side * h * ub
