"""Lexing one NC program line into words, with 1-based columns for errors.

N10 G01 X10 F500 (comment) ; comment      /N20 ... (block skip)
#SLOPE[TYPE=TRAPEZ]   S[M3 REV1000]   M19 S.POS=90   LL tapered thread   L123 P2
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from nc_sim.errors import Code

_NUM = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"
_WORD = re.compile(r"(?P<letter>[A-Z])\s*(?P<val>" + _NUM + ")", re.IGNORECASE | re.ASCII)
_SPEC = re.compile(r"(?P<name>S[0-9]*)\[", re.IGNORECASE | re.ASCII)
_POS = re.compile(
    r"(?P<name>S[0-9]*)\.\s*POS\s*=?\s*(?P<val>" + _NUM + ")", re.IGNORECASE | re.ASCII
)
_HASH = re.compile(r"#(?P<cmd>[A-Z_]+)\s*\[", re.IGNORECASE | re.ASCII)
_LOCAL_CALL = re.compile(r"LL\s+", re.IGNORECASE | re.ASCII)


class ProgramError(ValueError):
    """A program the interpreter refuses: 1-based `line` and `column`, the job error `code`."""

    def __init__(self, detail: str, line: int, column: int, code: Code = Code.BLOCK_SYNTAX):
        self.detail = detail
        self.line = line
        self.column = column
        self.code = code
        super().__init__(f"line {line}, column {column}: {detail} ({int(code)})")


@dataclass(frozen=True)
class Word:
    """An address letter with its value (`text` as written, for whole-number checks)."""

    letter: str
    value: float
    text: str
    column: int


@dataclass
class Line:
    """The parts of one line; `empty` when it holds nothing but comments."""

    words: list[Word] = field(default_factory=list)
    hashes: list[tuple[str, str, int]] = field(default_factory=list)  # (command, body, column)
    specific: list[tuple[str, str, int]] = field(
        default_factory=list
    )  # S[..]: name, body, name col
    positions: list[tuple[str, float, int]] = field(default_factory=list)  # S.POS: name, deg, col
    local_call: tuple[str, int] | None = None  # LL name
    skipped: bool = False

    @property
    def empty(self) -> bool:
        """Nothing to do on this line."""
        return not (self.words or self.hashes or self.specific or self.positions) and (
            self.local_call is None
        )


def _number(text: str, line: int, col: int) -> float:
    value = float(text)
    if not math.isfinite(value):
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
    while True:
        while pos < len(text) and text[pos].isspace():
            pos += 1
        if pos >= len(text) or text[pos] == ";":
            return out
        col = pos + 1
        ch = text[pos]
        if ch == "(":
            close = text.find(")", pos)
            if close < 0:
                raise ProgramError("comment '(' without ')'", line, col)
            pos = close + 1
        elif m := _HASH.match(text, pos):
            body, pos = _bracket_body(text, m.end() - 1, line, "#" + m.group("cmd"))
            out.hashes.append((m.group("cmd").upper(), body, col))
        elif m := _LOCAL_CALL.match(text, pos):
            end = len(text)
            for stop in (";", "("):  # the name runs to the comment: "LL tapered thread"
                if (k := text.find(stop, m.end())) >= 0:
                    end = min(end, k)
            name = " ".join(text[m.end() : end].split()).upper()
            if not name:
                raise ProgramError("LL needs a subprogram name", line, col)
            out.local_call = (name, col)
            pos = end
        elif m := _SPEC.match(text, pos):
            body, pos = _bracket_body(text, m.end() - 1, line, m.group("name"))
            out.specific.append((m.group("name").upper(), body, col))
        elif m := _POS.match(text, pos):
            deg = _number(m.group("val"), line, m.start("val") + 1)
            out.positions.append((m.group("name").upper(), deg, col))
            pos = m.end()
        elif m := _WORD.match(text, pos):
            value = _number(m.group("val"), line, m.start("val") + 1)
            out.words.append(Word(m.group("letter").upper(), value, m.group("val"), col))
            pos = m.end()
        else:
            after = text[pos + 1 : pos + 2]
            if not ch.isascii() or (after and not after.isascii()):
                odd = pos + (0 if not ch.isascii() else 1)  # e.g. full-width digits (CJK)
                raise ProgramError(f"'{text[odd]}' is not an NC character", line, odd + 1)
            if ch.isalpha():
                raise ProgramError(f"address '{ch}' without a value", line, col)
            raise ProgramError(f"unexpected '{ch}'", line, col)
