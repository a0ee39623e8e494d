"""Lexing one NC program line into words, with 1-based columns for errors.

N10 G01 X10 F500 (comment) ; comment      /N20 ... (block skip)
#SLOPE[TYPE=TRAPEZ]   #CAX   #CAX OFF   S[M3 REV1000]   M19 S.POS=90   G33 Z48 K1.5 S.OFFSET=180
G01 X-70 C-270 RX50   G130 X70 Z50   G131 = 50
#VECTOR LIMIT ON [ACC=1000 VEL=1500 FEED]   #VECTOR LIMIT OFF
LL tapered thread   L123 P2
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

from nc_sim.errors import Code

_NUM = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"
# One pass per token: leading whitespace (any Unicode space, as str.isspace), then the first
# of these that matches, in this order (the order decides: S1[ before S1.POS before S1).
_TOKEN = re.compile(
    r"\s*(?:"
    r"(?P<end>;|\Z)"
    r"|(?P<comment>\()"
    r"|(?a:(?P<hash>#(?P<cmd>[A-Z_]+(?:[ \t]+LIMIT[ \t]+(?:ON|OFF)(?:[ \t]+ALL)?\b|[ \t]+OFF\b)?)"
    r"\s*(?P<open>\[)?))"
    r"|(?a:(?P<call>LL\s+(?P<name>[^;(]*)))"
    r"|(?a:(?P<spec>(?P<sname>S[0-9]*)\[))"
    r"|(?a:(?P<pos>(?P<pname>S[0-9]*)\.\s*(?P<pkey>POS|OFFSET)\s*=?\s*(?P<pval>" + _NUM + r")))"
    r"|(?a:(?P<gset>G\s*(?P<gnum>[0-9]+)\s*=\s*(?P<gval>" + _NUM + r")))"
    r"|(?a:(?P<eff>R(?P<eaxis>[XYZ])\s*(?P<eval>" + _NUM + r")))"
    r"|(?a:(?P<word>(?P<letter>[A-Z])\s*(?P<val>" + _NUM + r")))"
    r"|(?P<bad>[\s\S])"
    r")",
    re.IGNORECASE,
)


class ProgramError(ValueError):
    """A program the interpreter refuses: 1-based `line` and `column`, the job error `code`."""

    def __init__(self, detail: str, line: int, column: int, code: Code = Code.BLOCK_SYNTAX):
        self.detail = detail
        self.line = line
        self.column = column
        self.code = code
        super().__init__(f"line {line}, column {column}: {detail} ({int(code)})")

    def __reduce__(self) -> tuple[type[ProgramError], tuple[str, int, int, Code]]:
        """Pickled with its fields (a machine's snapshot may hold one)."""
        return (ProgramError, (self.detail, self.line, self.column, self.code))


# how a word module reports a bad word: detail, column, job error code (BLOCK_SYNTAX default)
Error = Callable[..., ProgramError]


class Word(NamedTuple):
    """An address letter with its value (`text` as written, for whole-number checks)."""

    letter: str
    value: float
    text: str
    column: int


@dataclass(slots=True)
class Line:
    """The parts of one line; `empty` when it holds nothing but comments."""

    words: list[Word] = field(default_factory=list)
    # (command, body or None without [...], column of #, column of the body)
    hashes: list[tuple[str, str | None, int, int]] = field(default_factory=list)
    specific: list[tuple[str, str, int]] = field(
        default_factory=list
    )  # S[..]: name, body, name col
    positions: list[tuple[str, float, int]] = field(default_factory=list)  # S.POS: name, deg, col
    offsets: list[tuple[str, float, int]] = field(default_factory=list)  # S.OFFSET: name, deg, col
    g_values: list[tuple[int, float, int]] = field(default_factory=list)  # G131 = 50: G, value, col
    # RX/RY/RZ: a rotary move's effective distances in mm, with their columns [003 §1.2]
    effective: dict[str, tuple[float, int]] = field(default_factory=dict)
    local_call: tuple[str, int] | None = None  # LL name
    skipped: bool = False

    @property
    def empty(self) -> bool:
        """Nothing to do on this line."""
        return not (
            self.words
            or self.hashes
            or self.specific
            or self.positions
            or self.offsets
            or self.g_values
            or self.effective
        ) and (self.local_call is None)


def _number(text: str, line: int, col: int) -> float:
    value = float(text)
    if not math.isfinite(value):  # the pattern allows no inf/nan: only an overflow
        raise ProgramError(f"{text[:12]}… is too large", line, col)
    return value


def _bracket_body(text: str, open_at: int, line: int, what: str) -> tuple[str, int]:
    """The text inside `[...]` whose `[` is at index `open_at`, and the index after `]`."""
    close = text.find("]", open_at)
    if close < 0:
        raise ProgramError(f"{what}[ without ]", line, open_at + 1)
    return text[open_at + 1 : close], close + 1


def lex_line(text: str, line: int, skip_blocks: bool) -> Line:
    """Split one line into its words; `skip_blocks` makes `/` lines skipped (block skip)."""
    out = Line()
    pos = len(text) - len(text.lstrip())
    if text.startswith("/", pos):
        if skip_blocks:
            out.skipped = True
            return out
        pos += 1
    match = _TOKEN.match
    words = out.words
    while True:
        m = match(text, pos)
        assert m is not None  # `bad` takes any character the others do not
        kind = m.lastgroup or "bad"  # each alternative is a named group
        pos = m.end()
        if kind == "word":  # the common case first, with as few calls as can be
            letter, val = m.group("letter", "val")
            value = float(val)
            if not math.isfinite(value):
                _number(val, line, m.start("val") + 1)
            words.append(Word(letter.upper(), value, val, m.start(kind) + 1))
            continue
        if kind == "end":
            return out
        col = m.start(kind) + 1
        if kind == "comment":
            close = text.find(")", pos)
            if close < 0:
                raise ProgramError("comment '(' without ')'", line, col)
            pos = close + 1
        elif kind == "hash":  # `#CAX OFF`: OFF is part of the command
            cmd = " ".join(m.group("cmd").split()).upper()
            body: str | None = None
            if m.group("open"):
                body, pos = _bracket_body(text, pos - 1, line, "#" + cmd)
            out.hashes.append((cmd, body, col, m.start("open") + 2))
        elif kind == "call":  # the name runs to the comment: "LL tapered thread"
            name = " ".join(m.group("name").split()).upper()
            if not name:
                raise ProgramError("LL needs a subprogram name", line, col)
            out.local_call = (name, col)
        elif kind == "spec":
            body, pos = _bracket_body(text, pos - 1, line, m.group("sname"))
            out.specific.append((m.group("sname").upper(), body, col))
        elif kind == "eff":  # RX50: effective distance along X
            name = "R" + m.group("eaxis").upper()
            if name in out.effective:
                raise ProgramError(f"{name} twice in one block", line, col)
            out.effective[name] = (_number(m.group("eval"), line, m.start("eval") + 1), col)
        elif kind == "gset":  # G131 = 50, G133 = 80: a G function with its value
            value = _number(m.group("gval"), line, m.start("gval") + 1)
            out.g_values.append((int(m.group("gnum")), value, col))
        elif kind == "pos":  # S.POS (M19) or S.OFFSET (G33)
            deg = _number(m.group("pval"), line, m.start("pval") + 1)
            dotted = out.positions if m.group("pkey").upper() == "POS" else out.offsets
            dotted.append((m.group("pname").upper(), deg, col))
        else:
            ch = m.group("bad")
            at = col - 1  # where ch is
            after = text[at + 1 : at + 2]
            if not ch.isascii() or (after and not after.isascii()):
                odd = at + (0 if not ch.isascii() else 1)  # e.g. full-width digits (CJK)
                raise ProgramError(f"'{text[odd]}' is not an NC character", line, odd + 1)
            if ch.isalpha():
                raise ProgramError(f"address '{ch}' without a value", line, col)
            raise ProgramError(f"unexpected '{ch}'", line, col)
