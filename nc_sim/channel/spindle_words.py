"""The spindle part of one block -> canonical spindle calls [000 §2.3-§2.8].

    M3 S1000     M19 S.POS=90 M4     M41 S650     G135     S1[M3 REV1000 G136=50]
    S[G74]       S[DEFAULT_DYNAMIC_DATA]          S[M19 POS100 REV200]   G167 S800

Per spindle and block at most one of M3/M4, M5, M19 (M3/M4 next to M19 give its direction),
one feedforward G (G135 on, G136 weighting, G137 off) and G167 (override off for this speed
and until the next programmed speed). "S" is the main spindle; M40-M45 select its gear stage
1-6 and go with its speed, as a programmed stage is checked against the speed [000 §2.8.2].
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field

from nc_sim.channel import canon
from nc_sim.channel.words import ProgramError, Word
from nc_sim.errors import Code

MAIN = "S"
FEEDFORWARD_G = (135, 136, 137)
SPINDLE_G = (*FEEDFORWARD_G, 167)  # G words of the main spindle in DIN form
_NUM = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"


@dataclass
class _Spindle:
    """What a block asks of one spindle, with the column of its first word."""

    name: str
    column: int
    m: int | None = None  # 3, 4, 5, 19
    m_columns: dict[int, int] = field(default_factory=dict)  # each M function's column
    speed_rpm: float | None = None
    pos_deg: float | None = None
    pos_column: int = 0
    direction: int | None = None  # M19 with M3 (+1) or M4 (-1)
    feedforward: int | None = None
    ff_weight_pct: float | None = None
    override_off: bool = False
    default_dynamics: bool = False
    home: bool = False


class SpindleWords:
    """Collects one block's spindle words, then gives its calls in the fixed order."""

    def __init__(
        self, line: int, spindles: set[str], error: Callable[[str, int, Code], ProgramError]
    ) -> None:
        self.line = line
        self.spindles = spindles
        self.error = error
        self.by_name: dict[str, _Spindle] = {}

    def spindle(self, name: str, col: int) -> _Spindle:
        """The entry of spindle `name` (checked), made at its first word."""
        if name != MAIN and name not in self.spindles:
            raise self.error(f"unknown spindle '{name}'", col, Code.UNKNOWN_AXIS)
        if name not in self.by_name:
            self.by_name[name] = _Spindle(name, col)
        return self.by_name[name]

    def m_function(self, sp: _Spindle, m: int, col: int) -> None:
        """M3/M4 next to M19 give the positioning direction [000 §2.3.2]."""
        sp.m_columns.setdefault(m, col)
        if sp.m is None:
            sp.m = m
        elif {sp.m, m} in ({19, 3}, {19, 4}) and sp.direction is None:
            sp.direction = 1 if 3 in (sp.m, m) else -1
            sp.m = 19
        else:
            raise self.error(
                f"two spindle M functions for {sp.name} in one block", col, Code.BLOCK_SYNTAX
            )

    def speed(self, sp: _Spindle, rpm: float, col: int) -> None:
        """S word or REV: the programmed speed (never negative: M3/M4 give the direction)."""
        if rpm < 0:  # a negative S reverses only under G63 tapping [000 §2.8.6], not here
            raise self.error(
                "S must not be negative: M3/M4 give the direction (G63 excepted)",
                col,
                Code.BLOCK_SYNTAX,
            )
        if sp.speed_rpm is not None:
            raise self.error(f"two speeds for {sp.name} in one block", col, Code.BLOCK_SYNTAX)
        sp.speed_rpm = rpm

    def position(self, sp: _Spindle, deg: float, col: int) -> None:
        """S.POS= or POS: the M19 target."""
        if sp.pos_deg is not None:
            raise self.error(f"two positions for {sp.name} in one block", col, Code.BLOCK_SYNTAX)
        sp.pos_deg, sp.pos_column = deg, col

    def g_word(self, sp: _Spindle, g: int, weight_pct: float | None, col: int) -> None:
        """G135/G136/G137 feedforward, G167 override off."""
        if g == 167:
            sp.override_off = True
            return
        if sp.feedforward is not None:
            raise self.error(
                f"two feedforward G codes for {sp.name} in one block", col, Code.BLOCK_SYNTAX
            )
        sp.feedforward, sp.ff_weight_pct = g, weight_pct

    def specific(self, name: str, body: str, col: int) -> None:
        """`S1[M3 REV1000 G136=50]`: `col` is the column of the name."""
        sp = self.spindle(name, col)
        start = col + len(name) + 1  # column of the body's first character
        for m in re.finditer(r"\S+", body):
            tok = m.group(0).upper()
            c = start + m.start()
            if mm := re.fullmatch(r"M0*(3|4|5|19)", tok):
                self.m_function(sp, int(mm.group(1)), c)
            elif mm := re.fullmatch(r"REV=?(" + _NUM + ")", tok):
                self.speed(sp, self._finite(mm.group(1), c + mm.start(1)), c + mm.start(1))
            elif mm := re.fullmatch(r"POS=?(" + _NUM + ")", tok):
                self.position(sp, self._finite(mm.group(1), c + mm.start(1)), c)
            elif mm := re.fullmatch(r"G0*(74|135|137|167)", tok):
                g = int(mm.group(1))
                if g == 74:
                    sp.home = True
                else:
                    self.g_word(sp, g, None, c)
            elif mm := re.fullmatch(r"G0*136(?:=?(" + _NUM + "))?", tok):
                weight = self._finite(mm.group(1), c + mm.start(1)) if mm.group(1) else None
                if weight is not None and not 0.0 <= weight <= 100.0:
                    raise self.error(
                        f"G136 weighting {weight:g} % outside 0 … 100 %",
                        c + mm.start(1),
                        Code.BLOCK_SYNTAX,
                    )
                self.g_word(sp, 136, weight, c)
            elif tok == "DEFAULT_DYNAMIC_DATA":
                sp.default_dynamics = True
            else:
                raise self.error(
                    f"'{m.group(0)}' is not allowed in {name}[...]", c, Code.BLOCK_SYNTAX
                )

    def _finite(self, text: str, col: int) -> float:
        """A number of a bracket body; 400 digits would be inf, which nothing takes."""
        value = float(text)
        if not math.isfinite(value):
            raise self.error(f"{text[:12]}… is too large", col, Code.BLOCK_SYNTAX)
        return value

    def calls(self, gear: Word | None) -> list[canon.Call]:
        """The block's spindle calls; `gear` is its M40-M45 word (None: none)."""
        out: list[canon.Call] = []
        stage = None if gear is None else int(gear.value) - 39
        main = self.by_name.get(MAIN)
        carries_gear = main is not None and main.speed_rpm is not None and main.m in (None, 3, 4)
        if stage is not None and not carries_gear:
            out.append(canon.SelectGear(self.line, stage))
        for sp in self.by_name.values():
            out.extend(self._calls_of(sp, stage if sp.name == MAIN else None))
        return out

    def _calls_of(self, sp: _Spindle, stage: int | None) -> list[canon.Call]:
        line = self.line
        out: list[canon.Call] = []
        if sp.pos_deg is not None and sp.m != 19:
            raise self.error(f"{sp.name}.POS needs M19", sp.pos_column, Code.BLOCK_SYNTAX)
        if sp.home and (sp.m is not None or sp.speed_rpm is not None):
            raise self.error(
                f"{sp.name}[G74] homes the spindle: no M function or speed with it",
                sp.column,
                Code.BLOCK_SYNTAX,
            )
        speed_call = sp.speed_rpm is not None and sp.m in (None, 3, 4)
        override_alone = sp.override_off and not speed_call  # else it goes with the speed
        if sp.feedforward is not None or sp.default_dynamics or override_alone:
            out.append(
                canon.SpindleSettings(
                    line,
                    sp.name,
                    sp.feedforward,
                    sp.ff_weight_pct,
                    override_off=override_alone,
                    default_dynamics=sp.default_dynamics,
                )
            )
        if sp.home:
            out.append(canon.Home(line, ((sp.name, 1.0),)))
        if sp.m in (3, 4):
            out.append(
                canon.SpindleOn(
                    line, sp.name, sp.m, sp.speed_rpm, gear=stage, override_off=sp.override_off
                )
            )
        elif sp.m == 5:
            out.append(canon.SpindleOff(line, sp.name))
        elif sp.m == 19:
            out.append(canon.SpindleOrient(line, sp.name, sp.pos_deg, sp.speed_rpm, sp.direction))
        elif sp.speed_rpm is not None:
            out.append(
                canon.SpindleSpeed(
                    line, sp.name, sp.speed_rpm, gear=stage, override_off=sp.override_off
                )
            )
        return out
