"""Which words make the main spindle the rotary axis C and which make it a spindle again
[003 §4.2 "Activating the changeover process", 000 §2.3.3]:

    G00 X10 C90   G01 C-45 F500   #CAX      -> rotary axis C
    M3 S1000      M19 S.POS=0     G33 ...   G63 ...   #CAX OFF   -> spindle

The interpreter emits ROTARY_MODE where the mode changes (nc_sim/channel/interpreter.py).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from nc_sim.channel.modal import Modal
from nc_sim.channel.spindle_words import MAIN
from nc_sim.channel.words import Error, Word
from nc_sim.errors import Code


def cax_command(
    cmd: str, body: str | None, key: str, col: int, body_col: int, c: str | None, error: Error
) -> bool:
    """#CAX / #CAX OFF (`#CAX[S]` names the main spindle): True for rotary axis mode."""
    if key not in ("", MAIN):  # the main spindle is the one that becomes C
        at = body_col + len(body or "") - len((body or "").lstrip())
        raise error(f"#{cmd}[{body}]: only the main spindle S", at, Code.NOT_SUPPORTED)
    if c is None:
        raise error(
            f"#{cmd}: the main spindle has no rotary-axis name (P-CHAN-00010)",
            col,
            Code.NOT_SUPPORTED,
        )
    return cmd == "CAX"


def spindle_function(c: str, m: int, addr: Mapping[str, Word], error: Error) -> None:
    """M3/M4/M5/M19 make the drive a spindle: not in a block that positions C."""
    if c in addr:  # one drive cannot turn and position at once [003 §4.2]
        raise error(f"{c} and M{m} in one block: the spindle is one or the other", addr[c].column)


def motion_mode(c: str, motion: int, addr: Mapping[str, Word], error: Error) -> bool | None:
    """The mode a motion block needs: spindle for G33/G63 (no C there), rotary for C in
    G00-G03, None when it leaves the mode alone."""
    if motion in (33, 63):
        if c in addr:
            raise error(
                f"{c} cannot be programmed under G{motion} (the spindle turns)", addr[c].column
            )
        return False
    return True if c in addr else None


def check_known(c: str, addr: Mapping[str, Word], modal: Modal, error: Error) -> None:
    """After a changeover C is where the machine left it: G91 C needs a G90 C first."""
    if c in addr and not modal.absolute and math.isnan(modal.position[c]):
        raise error(
            f"{c}'s position is known only after the changeover: program it absolute (G90) first",
            addr[c].column,
        )
