"""DIN 66025 program text -> canonical calls (nc_sim/channel/canon.py), pure.

`interpret(text, sink, ...)` runs the main program from its first line, subprograms (`LL name`,
`L<n> P<repetitions>`) in place, until M30/M02. Modal words (G00-G03, G33, G63, G17-G19,
G51/G52, G90/G91, F, S, the G33 pitch and offset) carry over from block to block. A bad
program raises `ProgramError` with line, column and job error code; calls emitted before it
stay in the sink (the program stops there).

Within a block the calls come in a fixed order: F, #SLOPE/#CAX, T/D, M40-M45, spindle,
G17-G19, G200/G201, G130-G133, G04, G74, motion, other M functions, subprogram call, end
(M17/M29/M30/M02). When a spindle function acts relative to the motion is the
synchronisation type's business (000 §2.5),
decided where the calls are consumed; they carry the block's line for that.

A main spindle with a rotary-axis name (`c_axis`, P-CHAN-00010) is either a spindle or the
rotary axis C [003 §4.2]: C in G00-G03 (or #CAX) makes it the axis, M3/M4/M5/M19, G33 and G63
(or #CAX OFF) the spindle again. ROTARY_MODE comes where the mode changes, before the call that
needs it. After a change C's position is known only from the machine, so until C is programmed
absolute it is NaN here and G91 C is refused.
"""

from __future__ import annotations

import math
from collections.abc import Generator, Iterable, Iterator, Mapping
from dataclasses import replace

from nc_sim.channel import canon
from nc_sim.channel.arc_words import arc_feed
from nc_sim.channel.c_words import cax_command, check_known, motion_mode, spindle_function
from nc_sim.channel.modal import Modal, target
from nc_sim.channel.program import Program, split_program
from nc_sim.channel.spindle_words import MAIN, SPINDLE_G, SpindleWords
from nc_sim.channel.thread_words import (
    REFUSED_M,
    pitch_not_moved,
    set_pitch,
    set_thread_offset,
    tap_feed,
    tapping,
    thread_feed,
)
from nc_sim.channel.vector_words import vector_limit
from nc_sim.channel.weight_words import weighting
from nc_sim.channel.words import Line, ProgramError, Word, lex_line
from nc_sim.errors import Code

MAX_NESTING = 8  # subprogram levels
# blocks one run of a program may take, repetitions included: what memory and the time to
# interpret it can hold (about 40 µs and 1 KB a block); a program of the longest text runs
# about 50 000 blocks
MAX_PROGRAM_BLOCKS = 100_000
_END_PROGRAM = (30, 2)
_END_SUB = (17, 29)
SLOPE_TYPES = {"STEP": 0, "TRAPEZ": 1, "SIN2": 2, "HSC": 3}  # #SLOPE[TYPE=..] (P-CHAN-00071)
_MOTION_G = (0, 1, 2, 3, 33, 63)  # the modal block types; G04 is not one
_SUPPORTED_G = (4, 17, 18, 19, 51, 52, 60, 74, 90, 91, 130, 132, 200, 201, *_MOTION_G, *SPINDLE_G)
_EXCLUSIVE_G = (
    (_MOTION_G, "motion G codes"),
    ((17, 18, 19), "planes"),
    ((51, 52), "of G51/G52"),
    ((90, 91), "of G90/G91"),
    ((200, 201), "of G200/G201"),
)


def interpret(
    text: str,
    sink: canon.Sink,
    axes: Iterable[str] = ("X", "Y", "Z"),
    spindles: Iterable[str] = (),
    start: Mapping[str, float] | None = None,
    skip_blocks: bool = True,
    home: Mapping[str, float] | None = None,
    c_axis: str | None = None,
    rotary: bool = False,
) -> None:
    """Interpret a whole program into `sink`; `start` is where the axes are (default 0),
    `home` where G74 leaves them (their reference positions; default: where they were);
    `c_axis` the main spindle's name as the rotary axis, `rotary` whether it is that now."""
    for _ in interpret_steps(text, sink, axes, spindles, start, skip_blocks, home, c_axis, rotary):
        pass


def interpret_steps(
    text: str,
    sink: canon.Sink,
    axes: Iterable[str] = ("X", "Y", "Z"),
    spindles: Iterable[str] = (),
    start: Mapping[str, float] | None = None,
    skip_blocks: bool = True,
    home: Mapping[str, float] | None = None,
    c_axis: str | None = None,
    rotary: bool = False,
) -> Iterator[None]:
    """`interpret` a block at a time: each step interprets one block (a host may interleave
    other work between the steps of a long program)."""
    names = tuple(a.upper() for a in axes)
    modal = Modal(
        rotary=rotary,
        position={a: float((start or {}).get(a, 0.0)) for a in names},
        home_position={a.upper(): float(p) for a, p in (home or {}).items()},
    )
    if c_axis is not None and not rotary:
        modal.position[c_axis] = math.nan
    run = _Run(
        split_program(text), sink, names, {s.upper() for s in spindles}, modal, skip_blocks, c_axis
    )
    if not (yield from run.lines(run.prog.main, depth=0)):
        last = max(run.prog.main, default=0) + 1
        raise ProgramError("program ends without M30 or M02", last, 1, Code.PROGRAM_STRUCTURE)


def interpret_blocks(
    text: str,
    sink: canon.Sink,
    modal: Modal,
    axes: Iterable[str],
    spindles: Iterable[str],
    c_axis: str | None = None,
) -> None:
    """MDI: one or more blocks, no program end needed, starting from `modal` (what the
    blocks before left in force) and leaving it for the next. `modal` is changed only when
    every block interpreted without error."""
    names = tuple(a.upper() for a in axes)
    work = replace(modal, position=dict(modal.position))
    run = _Run(split_program(text), sink, names, {s.upper() for s in spindles}, work, True, c_axis)
    for _ in run.lines(run.prog.main, depth=0):
        pass
    modal.__dict__.update(work.__dict__)


class _Run:
    """One interpretation: the program, the sink and the modal state."""

    def __init__(
        self,
        prog: Program,
        sink: canon.Sink,
        axes: tuple[str, ...],
        spindles: set[str],
        modal: Modal,
        skip_blocks: bool,
        c_axis: str | None = None,
    ) -> None:
        self.prog = prog
        self.c_axis = c_axis
        self.sink = sink
        self.axes = axes
        self.spindles = spindles
        self.modal = modal
        self.skip_blocks = skip_blocks
        self.ended = False
        self.blocks = 0  # blocks interpreted so far, each repetition's again
        self.outer_call: tuple[int, int] | None = None  # (line, column) of the main's call

    def count_block(self, line: int) -> None:
        """One more block; beyond MAX_PROGRAM_BLOCKS the program is refused where the main
        program calls the subprogram that makes it so long (or at the block itself)."""
        self.blocks += 1
        if self.blocks > MAX_PROGRAM_BLOCKS:
            at_line, col = self.outer_call or (line, 1)
            raise ProgramError(
                f"the program runs more than {MAX_PROGRAM_BLOCKS} blocks "
                "(subprogram repetitions included)",
                at_line,
                col,
                Code.PROGRAM_STRUCTURE,
            )

    def lines(self, indexes: list[int], depth: int) -> Generator[None, None, bool]:
        """Run these lines, a step per block; True when a block ended them (M30/M02, or
        M17/M29 in a subprogram)."""
        for index in indexes:
            lexed = lex_line(self.prog.lines[index], index + 1, self.skip_blocks)
            if lexed.skipped or lexed.empty:
                continue
            self.count_block(index + 1)
            block = _Block(self, lexed, index + 1, depth)
            end = block.run()
            yield
            if block.sub_call is not None:  # after the block's M functions, before its end
                yield from self.call(*block.sub_call, depth)
            if end in _END_PROGRAM and not self.ended:
                self.sink.emit(canon.ProgramEnd(index + 1, end))
                self.ended = True
            if self.ended:
                return True
            if end is not None:
                if end in _END_SUB and depth == 0:
                    raise ProgramError(f"M{end} outside a subprogram", index + 1, 1)
                return True
        return False

    def call(
        self, name: str, repetitions: int, line: int, col: int, depth: int
    ) -> Generator[None, None, None]:
        """Run subprogram `name` `repetitions` times, a step per block."""
        if name not in self.prog.subprograms:
            raise ProgramError(
                f"subprogram {name} is not defined", line, col, Code.PROGRAM_STRUCTURE
            )
        if depth >= MAX_NESTING:
            raise ProgramError(
                f"subprograms nested deeper than {MAX_NESTING}", line, col, Code.PROGRAM_STRUCTURE
            )
        if depth == 0:
            self.outer_call = (line, col)
        for _ in range(repetitions):
            if not (yield from self.lines(self.prog.subprograms[name], depth + 1)):
                at = self.prog.defined_at[name] + 1
                raise ProgramError(
                    f"subprogram {name} ends without M17 or M29", at, 1, Code.PROGRAM_STRUCTURE
                )
            if self.ended:
                return


def _whole(word: Word, line: int) -> int:
    if word.value != int(word.value) or "." in word.text:
        raise ProgramError(
            f"{word.letter} takes a whole number, not {word.text}", line, word.column + 1
        )
    return int(word.value)


class _Block:
    """One block: collects its words, then emits its calls in the fixed order."""

    def __init__(self, run: _Run, lexed: Line, line: int, depth: int) -> None:
        self.run_ = run
        self.lexed = lexed
        self.line = line
        self.depth = depth
        self.g: dict[int, Word] = {}
        self.m: list[tuple[int, Word]] = []
        self.addr: dict[str, Word] = {}  # one each of the other addresses
        self.sub_call: tuple[str, int, int, int] | None = None  # (name, runs, line, column)
        self.motion_g: int | None = None  # the block's G00-G03/G33/G63
        self.mode = 0  # the motion mode in force for this block (its own G or the modal one)

    def error(self, detail: str, col: int, code: Code = Code.BLOCK_SYNTAX) -> ProgramError:
        return ProgramError(detail, self.line, col, code)

    def run(self) -> int | None:
        """Emit the block's calls; returns the M code that ends the (sub)program, if any."""
        axes = self.run_.axes
        for w in self.lexed.words:
            if w.letter == "G":
                g = _whole(w, self.line)
                if g not in _SUPPORTED_G:
                    raise self.error(f"G{g} is not supported", w.column, Code.NOT_SUPPORTED)
                if g in self.g:
                    raise self.error(f"G{g} twice in one block", w.column)
                self.g[g] = w
            elif w.letter == "M":
                self.m.append((_whole(w, self.line), w))
            elif w.letter in self.addr:
                raise self.error(f"{w.letter} twice in one block", w.column)
            elif w.letter in "NFSTDIJKRLP" or w.letter in axes or w.letter == "X":
                self.addr[w.letter] = w  # X: also G04's dwell time on machines without X
            else:
                raise self.error(f"unknown address '{w.letter}'", w.column)
        if "X" in self.addr and "X" not in axes and 4 not in self.g:
            raise self.error("unknown address 'X'", self.addr["X"].column)
        for group, what in _EXCLUSIVE_G:
            found = [g for g in self.g if g in group]
            if len(found) > 1:
                raise self.error(f"two {what} in one block", self.g[found[1]].column)
            if group is _MOTION_G and found:
                self.motion_g = found[0]
        self.mode = self.run_.modal.motion if self.motion_g is None else self.motion_g
        self._preparatory()
        self._spindle()
        self._motion_and_g()
        return self._m_and_calls()

    def _emit(self, call: canon.Call) -> None:
        self.run_.sink.emit(call)

    def _preparatory(self) -> None:
        if (n := self.addr.get("N")) is not None:
            _whole(n, self.line)
        if (f := self.addr.get("F")) is not None:
            if f.value <= 0:
                raise self.error("F must be positive", f.column + 1)
            self.run_.modal.feed_mm_min = f.value
            self._emit(canon.SetFeedRate(self.line, f.value))
        for cmd, body, col, body_col in self.lexed.hashes:
            key = "".join((body or "").split()).upper()
            if cmd == "SLOPE":
                if not key.startswith("TYPE=") or key[5:] not in SLOPE_TYPES:
                    at = col + len("#SLOPE") if body is None else body_col
                    raise self.error(f"#SLOPE needs [TYPE= one of {', '.join(SLOPE_TYPES)}]", at)
                self._emit(canon.SetSlope(self.line, SLOPE_TYPES[key[5:]]))
            elif cmd.startswith("VECTOR LIMIT"):
                modal = self.run_.modal
                modal.vector_limit = vector_limit(
                    cmd, body, col, body_col, modal.vector_limit, self.line, self.error
                )
                self._emit(modal.vector_limit)
            elif cmd in ("CAX", "CAX OFF"):
                c = self.run_.c_axis
                self._rotary(cax_command(cmd, body, key, col, body_col, c, self.error))
            else:
                raise self.error(f"#{cmd} is not supported", col, Code.NOT_SUPPORTED)
        tool, d = self.addr.get("T"), self.addr.get("D")
        if tool is not None or d is not None:
            self._emit(
                canon.SelectTool(
                    self.line,
                    None if tool is None else _whole(tool, self.line),
                    None if d is None else _whole(d, self.line),
                )
            )

    def _rotary(self, rotary: bool) -> None:
        """The main spindle becomes the rotary axis C or a spindle again, if it is not yet;
        C's position is the machine's business from here."""
        modal = self.run_.modal
        if modal.rotary == rotary:
            return
        self._emit(canon.RotaryMode(self.line, MAIN, rotary))
        modal.rotary = rotary
        assert self.run_.c_axis is not None
        modal.position[self.run_.c_axis] = math.nan

    def _spindle(self) -> None:
        lexed = self.lexed
        if not (self.m or "S" in self.addr or lexed.positions or lexed.specific) and not any(
            g in SPINDLE_G for g in self.g
        ):
            return  # no spindle word in this block
        modal = self.run_.modal
        tapping = self.mode == 63  # the S word is the tapping speed, not a spindle call
        words = SpindleWords(self.line, self.run_.spindles, self.error)
        gear: Word | None = None
        for m, w in self.m:
            if m in (3, 4, 5, 19):
                words.m_function(words.spindle(MAIN, w.column), m, w.column)
            elif 40 <= m <= 45:
                if gear is not None:
                    raise self.error("two gear stages M40-M45 in one block", w.column)
                gear = w
        if (s := self.addr.get("S")) is not None and 74 not in self.g:
            if tapping:  # negative: left-hand thread or out of the bore [000 §2.8.6]
                modal.speed_rpm = s.value
            else:
                words.speed(words.spindle(MAIN, s.column), s.value, s.column + 1)
        for g, w in self.g.items():
            if g in SPINDLE_G:
                words.g_word(words.spindle(MAIN, w.column), g, None, w.column)
        for name, deg, col in self.lexed.positions:
            words.position(words.spindle(name, col), deg, col)
        for name, body, col in self.lexed.specific:
            if tapping and name == MAIN:
                raise self.error("under G63 the main spindle takes only its S word", col)
            words.specific(name, body, col)
        if (main := words.by_name.get(MAIN)) is not None:
            refused = REFUSED_M.get(self.mode, ())
            for m, col in main.m_columns.items():  # the spindle is coupled to the path
                if m in refused:
                    raise self.error(
                        f"M{m} cannot be programmed under G{self.mode} (G00/G01 end it)", col
                    )
            if main.speed_rpm is not None:
                modal.speed_rpm = main.speed_rpm
            c = self.run_.c_axis
            if main.m is not None and c is not None:
                spindle_function(c, main.m, self.addr, self.error)
                self._rotary(False)
        for call in words.calls(gear):
            self._emit(call)

    def _motion_and_g(self) -> None:
        modal = self.run_.modal
        gs = self.g
        if gs:  # most blocks of a contour have no G word (the checks are the hot path)
            for g in (17, 18, 19):
                if g in gs:
                    modal.plane = g
                    self._emit(canon.SelectPlane(self.line, g))
            if 90 in gs or 91 in gs:
                modal.absolute = 90 in gs
            if 51 in gs or 52 in gs:
                modal.diameter = 51 in gs
            for g in (200, 201):
                if g in gs:
                    modal.parallel_manual = g == 201
                    self._emit(canon.ManualMode(self.line, g))
        if self.lexed.g_values or 130 in gs or 132 in gs:
            self._emit(
                weighting(
                    self.line,
                    gs,
                    self.lexed.g_values,
                    self.addr,
                    self.run_.axes,
                    modal,
                    self.motion_g,
                    self.error,
                )
            )
            return
        if self.lexed.offsets:
            set_thread_offset(self.lexed.offsets, self.mode, modal, self.error)
        axis_words = [self.addr[a] for a in self.run_.axes if a in self.addr]
        if gs:
            if 4 in gs:
                self._dwell(axis_words)
                return
            if 74 in gs:
                self._home(axis_words)
                return
            if self.motion_g is not None:
                modal.motion = self.motion_g
        mode = self.mode
        axes = self.run_.axes
        pitch = set_pitch(self.addr, axes, modal, self.error) if mode == 33 else None
        arc_words = [self.addr[a] for a in ("R" if mode == 33 else "IJKR") if a in self.addr]
        if arc_words and mode not in (2, 3):
            raise self.error("I/J/K/R only with G02/G03", arc_words[0].column)
        col = self.g[self.motion_g].column if self.motion_g is not None else 0
        if not axis_words and not arc_words:
            if self.lexed.effective:  # effective distances of a move that is not there
                name, (_v, at) = next(iter(self.lexed.effective.items()))
                raise self.error(f"{name} needs a move in its block", at)
            if pitch is not None:  # under G33 I/J/K are the pitch
                raise pitch_not_moved(pitch.letter, pitch.column, self.error)
            if mode == 63 and 63 in gs:  # G63 selected: its feed and speed are checked now
                tapping(modal, col, self.error)
            return
        col = col or (axis_words + arc_words)[0].column
        if self.lexed.effective and mode not in (0, 1):
            name, (_v, at) = next(iter(self.lexed.effective.items()))
            raise self.error(f"{name} only in G00/G01 blocks", at)
        c = self.run_.c_axis
        if c is not None and (rotary := motion_mode(c, mode, self.addr, self.error)) is not None:
            self._rotary(rotary)
            check_known(c, self.addr, modal, self.error)
        end = dict(modal.position)
        for w in axis_words:
            value = w.value / 2 if w.letter == "X" and modal.diameter else w.value
            end[w.letter] = value if modal.absolute else modal.position[w.letter] + value
        to = target(end, axes)
        if mode == 0:
            self._emit(canon.StraightTraverse(self.line, to, **self._motion_flags()))
        elif mode in (33, 63):  # they start and end at rest: G60 holds without a flag
            self._emit(
                thread_feed(self.line, end, modal, axes, pitch, col, self.error)
                if mode == 33
                else tap_feed(self.line, end, modal, axes, col, self.error)
            )
        elif modal.feed_mm_min is None:
            raise self.error("G01/G02/G03 need a feed F first", col, Code.FEED_MISSING)
        elif mode == 1:
            self._emit(
                canon.StraightFeed(
                    self.line,
                    to,
                    absolute=modal.absolute,
                    exact_stop=60 in self.g,
                    effective=self._effective(),
                )
            )
        else:
            self._emit(
                arc_feed(
                    self.line,
                    mode,
                    modal.plane,
                    self.addr,
                    modal.position,
                    to,
                    col,
                    self.error,
                    **self._motion_flags(),
                )
            )
        modal.position = end

    def _effective(self) -> tuple[float, float, float] | None:
        """RX/RY/RZ of this block (mm, 0 for one not given), None without any [003 §1.2]."""
        eff = self.lexed.effective
        if not eff:
            return None
        return (eff.get("RX", (0.0, 0))[0], eff.get("RY", (0.0, 0))[0], eff.get("RZ", (0.0, 0))[0])

    def _motion_flags(self) -> dict[str, bool]:
        """G90/G91 in force (for the status) and G60 exact stop (this block only)."""
        return {"absolute": self.run_.modal.absolute, "exact_stop": 60 in self.g}

    def _dwell(self, axis_words: list[Word]) -> None:
        x = self.addr.get("X")
        if (
            x is None
            or any(w.letter != "X" for w in axis_words)
            or self.g.keys() & {*_MOTION_G, 74}
        ):
            raise self.error("G04 takes only its dwell time X<s>", self.g[4].column)
        if x.value < 0:
            raise self.error("G04 dwell time must not be negative", x.column + 1)
        self._emit(canon.Dwell(self.line, x.value))

    def _home(self, axis_words: list[Word]) -> None:
        if self.motion_g is not None:
            raise self.error(f"G74 cannot be combined with G{self.motion_g:02d}", self.g[74].column)
        order = [(w.letter, w) for w in axis_words]
        if (s := self.addr.get("S")) is not None:
            order.append(("S", s))
        for name, w in order:
            if w.value != int(w.value) or w.value < 1:
                raise self.error(f"G74 takes a homing order 1, 2, ... for {name}", w.column + 1)
        if not order:
            raise self.error("G74 needs the axes to home with their order", self.g[74].column)
        self._emit(canon.Home(self.line, tuple((n, w.value) for n, w in order)))
        modal = self.run_.modal
        for name, _w in order:  # the axes end at their reference positions
            if name in modal.position and name in modal.home_position:
                modal.position[name] = modal.home_position[name]

    def _m_and_calls(self) -> int | None:
        ending: int | None = None
        for m, w in self.m:
            if m in (3, 4, 5, 19) or 40 <= m <= 45:
                continue  # the spindle's (SpindleWords)
            if m in _END_PROGRAM or m in _END_SUB:
                if ending is not None:
                    raise self.error("two program ends in one block", w.column)
                ending = m
            else:
                self._emit(canon.MFunction(self.line, m))
        self._subprogram_call()  # the run calls it, then ends the program if the block does
        return ending

    def _subprogram_call(self) -> None:
        l_word, p_word = self.addr.get("L"), self.addr.get("P")
        local = self.lexed.local_call
        if l_word is not None and local is not None:
            raise self.error("two subprogram calls in one block", l_word.column)
        repetitions = 1
        if p_word is not None:
            if l_word is None:
                raise self.error("P (repetitions) only with L<n>", p_word.column)
            repetitions = _whole(p_word, self.line)
            if repetitions < 1:
                raise self.error("P takes the number of runs, 1 or more", p_word.column + 1)
        if l_word is not None:
            name = str(_whole(l_word, self.line))
            self.sub_call = (name, repetitions, self.line, l_word.column)
        elif local is not None:
            self.sub_call = (local[0], 1, self.line, local[1])
