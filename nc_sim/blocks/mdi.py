"""Single NC blocks in DIN syntax and axis-specific syntax.

    G01 X10 F500            G00 Z-5          G74 X1 Z2 S1     #SLOPE[TYPE=TRAPEZ]
    M3 S1000                M19 S.POS=90 M4  M40 S650         M8
    S[M3 REV1000]           S1[M19 REV200 POS100]             S[G74]   S[M5]

A bad block raises `BlockError` with the 1-based column of the offending character.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field

SLOPE_TYPES = {"STEP": 0, "TRAPEZ": 1, "SIN2": 2, "HSC": 3}
_NUM = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"  # ASCII digits only: `S１０００` is refused


class BlockError(ValueError):
    """A block that cannot be parsed; `column` is 1-based."""

    def __init__(self, message: str, column: int) -> None:
        self.column = column
        self.detail = message
        super().__init__(f"column {column}: {message}")


@dataclass
class SpindleCmd:
    """What one block asks of one spindle."""

    spindle: str  # "S" for the main spindle or a configured name
    m: int | None = None  # 3, 4, 5, 19
    speed_rpm: float | None = None
    pos_deg: float | None = None
    direction: int | None = None  # M19 with M3 (+1) or M4 (-1)
    g: list[int] = field(default_factory=list)  # 74, 135, 136, 137, 167
    ff_weight: float | None = None  # G136 weighting
    default_dynamics: bool = False


@dataclass
class Block:
    """A parsed block."""

    text: str
    number: int | None = None
    motion: int | None = None  # 0 or 1
    absolute: bool | None = None  # G90 / G91
    homing: dict[str, int] = field(default_factory=dict)  # G74: axis -> order
    axes: dict[str, float] = field(default_factory=dict)
    feed: float | None = None  # mm/min
    m_functions: list[int] = field(default_factory=list)
    gear: int | None = None  # 40..45
    spindles: list[SpindleCmd] = field(default_factory=list)
    slope_type: int | None = None
    tool: int | None = None  # D word: tool dynamic data [000 §2.8.5]
    g_other: list[int] = field(default_factory=list)


_TOKEN = re.compile(
    r"\s*(?:"
    r"(?P<comment>\(.*?\)|;.*$)"
    r"|(?P<slope>#SLOPE\s*\[(?P<slope_body>[^\]]*)\])"
    r"|(?P<spec>(?P<spec_name>[A-Z][A-Z0-9]*)\[(?P<spec_body>[^\]]*)\])"
    r"|(?P<pos>(?P<pos_name>S\d*)\.POS\s*=?\s*(?P<pos_val>" + _NUM + "))"
    r"|(?P<word>(?P<letter>[A-Z][A-Z]*\d*?)(?P<val>" + _NUM + "))"
    r")",
    re.IGNORECASE | re.ASCII,
)


def _spindle_ref(name: str, spindles: Iterable[str], col: int) -> str:
    name = name.upper()
    if name == "S" or name in spindles:
        return name
    raise BlockError(f"unknown spindle '{name}'", col)


def parse_spindle_specific(body: str, spindle: str, col: int) -> SpindleCmd:
    """The body of `S[M3 REV1000]` (axis-specific spindle syntax); `col` is its 1-based column."""
    cmd = SpindleCmd(spindle)
    for m in re.finditer(r"\S+", body):
        tok = m.group(0).upper()
        c = col + m.start()
        if mm := re.fullmatch(r"M0*(3|4|5|19)", tok):
            _spindle_m(cmd, int(mm.group(1)), c)
        elif mm := re.fullmatch(r"REV=?(" + _NUM + ")", tok):
            rev = _number(mm.group(1), c + mm.start(1))
            if rev < 0:  # as the S word: M3/M4 give the direction
                raise BlockError("REV must not be negative: M3/M4 give the direction", c + 3)
            cmd.speed_rpm = rev
        elif mm := re.fullmatch(r"POS=?(" + _NUM + ")", tok):
            cmd.pos_deg = _number(mm.group(1), c + mm.start(1))
        elif mm := re.fullmatch(r"G0*(74|135|137|167)", tok):
            cmd.g.append(int(mm.group(1)))
        elif mm := re.fullmatch(r"G136(?:=?(" + _NUM + "))?", tok):
            cmd.g.append(136)
            cmd.ff_weight = _number(mm.group(1), c + mm.start(1)) if mm.group(1) else None
        elif tok == "DEFAULT_DYNAMIC_DATA":
            cmd.default_dynamics = True
        else:
            raise BlockError(f"'{m.group(0)}' is not allowed in {spindle}[...]", c)
    return cmd


def parse_block(text: str, axes: Iterable[str], spindles: Iterable[str] = ()) -> Block:
    """Parse one block; `axes` are the channel's axis names, `spindles` the spindle names."""
    axes = {a.upper() for a in axes}
    spindles = {s.upper() for s in spindles}
    block = Block(text)
    main = SpindleCmd("S")
    columns: dict[str, int] = {}  # column of each axis word and S (G74 order digits)
    pos = 0
    line = text.rstrip("\n")
    while pos < len(line):
        if not line[pos:].strip():
            break
        m = _TOKEN.match(line, pos)
        col = pos + 1 + (len(line[pos:]) - len(line[pos:].lstrip()))
        if m is None or m.end() == pos:
            word = line[col - 1 :].split(maxsplit=1)[0]
            odd = next((k for k, ch in enumerate(word) if not ch.isascii()), None)
            if odd is not None:  # e.g. full-width digits typed on a CJK keyboard
                raise BlockError(f"'{word[odd]}' is not an NC character", col + odd)
            raise BlockError(f"unexpected '{line[col - 1]}'", col)
        pos = m.end()
        if m.group("comment"):
            continue
        if m.group("slope"):
            body = m.group("slope_body").replace(" ", "").upper()
            sm = re.fullmatch(r"TYPE=(\w+)", body)
            if not sm or sm.group(1) not in SLOPE_TYPES:
                raise BlockError(
                    f"#SLOPE needs TYPE= one of {', '.join(SLOPE_TYPES)}", m.start("slope_body") + 1
                )
            block.slope_type = SLOPE_TYPES[sm.group(1)]
            continue
        if m.group("spec"):
            name = _spindle_ref(m.group("spec_name"), spindles, col)
            block.spindles.append(
                parse_spindle_specific(m.group("spec_body"), name, m.start("spec_body") + 1)
            )
            continue
        if m.group("pos"):
            name = _spindle_ref(m.group("pos_name"), spindles, col)
            target = main if name == "S" else _named(block, name)
            target.pos_deg = _number(m.group("pos_val"), m.start("pos_val") + 1)
            continue
        letter = m.group("letter").upper()
        val_text = m.group("val")
        value = _number(val_text, col + len(letter))
        columns.setdefault(letter, col)
        _word(block, main, letter, value, val_text, col, axes, spindles)
    if 74 in block.g_other and block.motion is not None:
        raise BlockError("G74 cannot be combined with G00/G01", 1)
    if 74 in block.g_other:
        _homing_order(block, main, columns)
    if main.m is not None or main.speed_rpm is not None or main.pos_deg is not None or main.g:
        block.spindles.insert(0, main)
    return block


def _homing_order(block: Block, main: SpindleCmd, columns: dict[str, int]) -> None:
    """G74 X1 Z2 S1: the digits are the homing order, S the main spindle [000 §2.7]."""
    orders = dict(block.axes)
    if main.speed_rpm is not None:
        if main.m is not None or main.pos_deg is not None:
            raise BlockError("G74 S.. homes the spindle: no spindle M function with it", 1)
        orders["S"] = main.speed_rpm
        main.speed_rpm = None
    for name, order in orders.items():
        if order != int(order) or order < 1:
            raise BlockError(f"G74 takes a homing order 1, 2, ... for {name}", columns[name] + 1)
        block.homing[name] = int(order)
    block.axes.clear()


def _number(text: str, col: int) -> float:
    """The value of a number in a block; 400 digits would be inf, which no address takes."""
    value = float(text)
    if not math.isfinite(value):
        raise BlockError(f"{text[:12]}… is too large", col)
    return value


def _named(block: Block, name: str) -> SpindleCmd:
    for s in block.spindles:
        if s.spindle == name:
            return s
    cmd = SpindleCmd(name)
    block.spindles.append(cmd)
    return cmd


def _spindle_m(cmd: SpindleCmd, m: int, col: int) -> None:
    """M3/M4 next to M19 give the positioning direction [000 §2.3.2]."""
    if cmd.m is None:
        cmd.m = m
    elif cmd.m == 19 and m in (3, 4) and cmd.direction is None:
        cmd.direction = 1 if m == 3 else -1
    elif cmd.m in (3, 4) and m == 19 and cmd.direction is None:
        cmd.direction = 1 if cmd.m == 3 else -1
        cmd.m = 19
    else:
        raise BlockError("two spindle M functions for one spindle in one block", col)


def _int_word(letter: str, value: float, text: str, col: int) -> int:
    if value != int(value) or "." in text:
        raise BlockError(f"{letter} takes a whole number, not {text}", col + len(letter))
    return int(value)


def _word(
    block: Block,
    main: SpindleCmd,
    letter: str,
    value: float,
    text: str,
    col: int,
    axes: set[str],
    spindles: set[str],
) -> None:
    if letter == "N":
        block.number = _int_word(letter, value, text, col)
    elif letter == "G":
        g = _int_word(letter, value, text, col)
        if g in (0, 1):
            if block.motion is not None:
                raise BlockError("two motion G codes in one block", col)
            block.motion = g
        elif g in (90, 91):
            block.absolute = g == 90
        elif g == 74:
            block.g_other.append(74)
        elif g in (135, 136, 137, 167):
            main.g.append(g)
        elif g in (200, 201):
            block.g_other.append(g)
        else:
            raise BlockError(f"G{g} is not supported in MDI", col)
    elif letter == "M":
        mval = _int_word(letter, value, text, col)
        if mval in (3, 4, 5, 19):
            _spindle_m(main, mval, col)
        elif 40 <= mval <= 45:
            block.gear = mval
        else:
            block.m_functions.append(mval)
    elif letter == "F":
        if value <= 0:
            raise BlockError("F must be positive", col + 1)
        block.feed = value
    elif letter == "S":
        if value < 0:  # a negative S reverses only under G63 tapping [000 §2.8.6], not here
            raise BlockError("S must not be negative: M3/M4 give the direction", col + 1)
        main.speed_rpm = value
    elif letter == "D":
        block.tool = _int_word(letter, value, text, col)
    elif letter in axes:
        if letter in block.axes:
            raise BlockError(f"axis {letter} twice in one block", col)
        block.axes[letter] = value
    elif letter in spindles:
        raise BlockError(f"spindle {letter} is programmed as {letter}[...]", col)
    else:
        raise BlockError(f"unknown address '{letter}'", col)
