"""The words of a block whose path is coupled to the main spindle: G33 thread cutting
[000 §2.8.7] and G63 tapping without compensating chuck [000 §2.8.6].

    G33 Z48 K1.5            pitch K (mm/rev along Z; I along X, J along Y), modal
    G33 Z48 S.OFFSET=180    second start of a two-start thread: offset angle, modal
    G63 Z-50 F300 S200      tapping at the last F and S; Z100 S-200 retracts

Pitch and offset stay in force until the program ends. Under G33 the spindle turns endlessly
(M5 and M19 would stop it under the thread); under G63 it follows the path as an axis, so no
spindle M function at all.
"""

from __future__ import annotations

from collections.abc import Mapping

from nc_sim.channel import canon
from nc_sim.channel.modal import PITCH_AXIS, Modal, target
from nc_sim.channel.spindle_words import MAIN
from nc_sim.channel.words import Error, ProgramError, Word
from nc_sim.errors import Code

REFUSED_M = {33: (5, 19), 63: (3, 4, 5, 19)}  # spindle M functions a mode does not take


def set_thread_offset(
    offsets: list[tuple[str, float, int]], mode: int, modal: Modal, error: Error
) -> None:
    """S.OFFSET= (`offsets` as lexed: name, degrees, column): modal, reduced to 0 … 360°."""
    if len(offsets) > 1:
        raise error("two thread offsets in one block", offsets[1][2], Code.BLOCK_SYNTAX)
    name, deg, col = offsets[0]
    if name != MAIN:
        raise error(f"{name}.OFFSET: threads follow the main spindle S", col, Code.NOT_SUPPORTED)
    if mode != 33:
        raise error("S.OFFSET only with G33", col, Code.BLOCK_SYNTAX)
    modal.thread_offset_deg = deg % 360.0


def set_pitch(
    addr: Mapping[str, Word], axes: tuple[str, ...], modal: Modal, error: Error
) -> Word | None:
    """The block's pitch word I/J/K, checked and made modal (None: the modal pitch holds)."""
    words = sorted((addr[c] for c in "IJK" if c in addr), key=lambda w: w.column)
    if not words:
        return None
    if len(words) > 1:
        raise error("two thread pitches I/J/K in one block", words[1].column, Code.BLOCK_SYNTAX)
    w = words[0]
    axis = PITCH_AXIS[w.letter]
    if axis not in axes:
        raise error(
            f"pitch {w.letter} is along {axis}, not an axis of this channel",
            w.column,
            Code.UNKNOWN_AXIS,
        )
    if w.value <= 0:
        raise error(f"thread pitch {w.letter} must be above 0 mm", w.column + 1, Code.BLOCK_SYNTAX)
    modal.pitch = (w.letter, w.value)
    return w


def pitch_not_moved(letter: str, col: int, error: Error) -> ProgramError:
    """A pitch along an axis the block does not move: no lead, so no feed."""
    return error(
        f"pitch {letter} is along {PITCH_AXIS[letter]}, which this block does not move",
        col,
        Code.BLOCK_SYNTAX,
    )


def thread_feed(
    line: int,
    end: Mapping[str, float],
    modal: Modal,
    axes: tuple[str, ...],
    pitch_word: Word | None,
    col: int,
    error: Error,
) -> canon.ThreadFeed:
    """G33 from `modal.position` to `end`; `col` is the block's motion column."""
    if modal.pitch is None:
        raise error("G33 needs a thread pitch I/J/K", col, Code.FEED_MISSING)
    letter, pitch_mm = modal.pitch
    axis = PITCH_AXIS[letter]
    if end[axis] == modal.position[axis]:
        raise pitch_not_moved(letter, col if pitch_word is None else pitch_word.column, error)
    to = target(end, axes)
    return canon.ThreadFeed(
        line, to, MAIN, pitch_mm, axis, modal.thread_offset_deg, absolute=modal.absolute
    )


def tapping(modal: Modal, col: int, error: Error) -> tuple[float, float]:
    """G63's speed (signed) and feed: the last S and F programmed, neither 0."""
    if modal.feed_mm_min is None:
        raise error("G63 needs a feed F", col, Code.FEED_MISSING)
    if not modal.speed_rpm:
        raise error("G63 needs a spindle speed S other than 0", col, Code.FEED_MISSING)
    return modal.speed_rpm, modal.feed_mm_min


def tap_feed(
    line: int, end: Mapping[str, float], modal: Modal, axes: tuple[str, ...], col: int, error: Error
) -> canon.TapFeed:
    """G63 from `modal.position` to `end`; `col` is the block's motion column."""
    speed_rpm, feed_mm_min = tapping(modal, col, error)
    to = target(end, axes)
    return canon.TapFeed(line, to, MAIN, speed_rpm, feed_mm_min, absolute=modal.absolute)
