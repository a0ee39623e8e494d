"""Seeded random NC programs with their expected motions, and mutations that break them.

`random_program(seed, ...)` writes a valid DIN 66025 program (G00/G01/G02/G03 with consistent
arcs by I/J/K or R, full circles, helices, G90/G91, F, planes, dwell, spindle words, #SLOPE,
block skip, subprograms called by `LL name` and `L<n> P<k>`, nested) and, while writing it,
works out on its own where every motion goes: `GeneratedProgram.motions` in execution order
and `end`, the point the last motion ends at. It never reads the interpreter's output, so the
two can be checked against each other; positions stay inside `bounds` (arcs as their whole
circle), so the motions can be run on a machine within its limits.

`mutate(program, seed)` breaks one thing and says where the first error must be: its line,
column and job error code.
"""

from __future__ import annotations

import math
import random
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from nc_sim.errors import Code

# plane -> (first axis, second axis, normal axis), as DIN 66025; centre offset letters
_PLANES = {17: ("X", "Y", "Z"), 18: ("Z", "X", "Y"), 19: ("Y", "Z", "X")}
_CENTRE = {"X": "I", "Y": "J", "Z": "K"}
_SLOPES = ("STEP", "TRAPEZ", "SIN2", "HSC")
_MIN_RADIUS_MM = 1.0
_R_ARC_TOLERANCE_MM = 0.01  # centre from R: rounding the end to 1 µm moves it a few µm


@dataclass(frozen=True)
class Motion:
    """One motion as the generator expects it: G code 0-3, the block's line, the end (every
    axis, absolute); arcs: plane, centre (the plane's two coordinates) and how exactly the
    interpreter must find that centre (0 for I/J/K, a few µm for R)."""

    line: int
    g: int
    end: tuple[tuple[str, float], ...]
    plane: int | None = None
    centre: tuple[float, float] | None = None
    centre_tolerance_mm: float = 0.0


@dataclass
class _Line:
    """One program line as words (columns follow from them); `role` tells mutations what it
    is: "header" (%...), "call" (LL/L), "end" (M30/M02), "block"."""

    words: list[str]
    role: str = "block"
    skipped: bool = False
    comment: str | None = None
    arc: tuple[int, int] | None = None  # word index of the first plane axis end, first centre
    arc_geom: tuple[float, float] | None = None  # that end minus the centre, radius
    feed_at: int | None = None  # word index of the F word

    def text(self) -> str:
        code = ("/" if self.skipped else "") + " ".join(self.words)
        return code + (f" ; {self.comment}" if self.comment else "")

    def column(self, index: int) -> int:
        """1-based column of word `index` (executed lines carry no `/`)."""
        return 1 + sum(len(w) + 1 for w in self.words[:index])


@dataclass(frozen=True)
class GeneratedProgram:
    """A valid program, the motions it must give in execution order and its end point."""

    seed: int
    text: str
    end: dict[str, float]
    motions: tuple[Motion, ...]
    lines: tuple[_Line, ...] = field(repr=False)
    first_feed: tuple[int, int] = field(repr=False)  # (line, word index) executed first


@dataclass(frozen=True)
class Mutation:
    """A broken program and where its first error must be reported."""

    kind: str
    text: str
    line: int
    column: int
    code: Code


def _num(value: float) -> tuple[str, float]:
    """Text with at most 3 decimals (1 µm) and the value the interpreter reads from it."""
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    text = "0" if text in ("-0", "") else text
    return text, float(text)


@dataclass(frozen=True)
class _Step:
    """A motion before the layout is known: `owner` None for the main program, else the
    subprogram's name; `local` the 0-based index of its line there."""

    owner: str | None
    local: int
    g: int
    end: tuple[tuple[str, float], ...]
    plane: int | None
    centre: tuple[float, float] | None
    by_radius: bool
    feed_word: int | None  # word index of an F in its line


@dataclass(frozen=True)
class _Rel:
    """A subprogram motion (G91): increments as read, the centre offset from its start."""

    local: int
    g: int
    delta: tuple[tuple[str, float], ...]
    plane: int | None
    centre_off: tuple[float, float] | None
    by_radius: bool
    feed_word: int | None


@dataclass
class _Sub:
    name: str
    call: list[str]  # ["LL", name] or ["L<n>"] (then P is allowed)
    lines: list[_Line]
    body: list[_Rel | str]  # motions, and names of subprograms it calls
    plane: int | None  # the plane it leaves in force
    last_g: int | None  # the motion mode it leaves in force (None: the caller's)
    feeds: bool  # sets its own F before its first feed motion


class _Generator:
    """Writes blocks while tracking modal state and position: the generator's own model."""

    def __init__(
        self,
        seed: int,
        axes: tuple[str, ...],
        bounds: dict[str, tuple[float, float]],
        start: dict[str, float],
        spindles: tuple[str, ...],
    ) -> None:
        self.rng = random.Random(seed)
        self.axes = axes
        self.bounds = bounds
        self.spindles = spindles
        self.planes = [p for p, (a, b, _) in _PLANES.items() if a in axes and b in axes]
        self.pos = dict(start)
        self.absolute = True
        self.g = 0  # G00 at program start
        self.plane = 17
        self.feed: float | None = None
        self.main: list[_Line] = []
        self.steps: list[_Step] = []
        self.subs: dict[str, _Sub] = {}
        self.called: set[str] = set()

    # --- geometry ---------------------------------------------------------------------
    def inside(self, point: Mapping[str, float]) -> bool:
        return all(lo <= point[a] <= hi for a, (lo, hi) in self.bounds.items())

    def circle_inside(self, plane: int, centre: tuple[float, float], r: float) -> bool:
        a, b, _ = _PLANES[plane]
        return all(
            self.bounds[x][0] <= c - r and c + r <= self.bounds[x][1]
            for x, c in ((a, centre[0]), (b, centre[1]))
        )

    def arc(
        self, start: Mapping[str, float], plane: int, reach_mm: float, helix: bool
    ) -> tuple[dict[str, float], tuple[float, float], float, float, int] | None:
        """A random arc from `start` with its circle inside the bounds: end (as read back),
        centre, radius, sweep in degrees (360: full circle) and turn (+1 G03, -1 G02)."""
        a, b, n = _PLANES[plane]
        for _ in range(20):
            oa = _num(self.rng.uniform(-reach_mm, reach_mm))[1]
            ob = _num(self.rng.uniform(-reach_mm, reach_mm))[1]
            centre = (start[a] + oa, start[b] + ob)
            r = math.hypot(oa, ob)
            if r < _MIN_RADIUS_MM or not self.circle_inside(plane, centre, r):
                continue
            turn = self.rng.choice((1, -1))
            sweep = self.rng.choice((360.0, self.rng.uniform(20, 160), self.rng.uniform(200, 340)))
            phi = math.atan2(-ob, -oa) + turn * math.radians(sweep)
            end = dict(start)
            if sweep < 360.0:
                end[a] = _num(centre[0] + r * math.cos(phi))[1]
                end[b] = _num(centre[1] + r * math.sin(phi))[1]
            if helix and n in self.axes:
                end[n] = _num(self.rng.uniform(*self.bounds[n]))[1]
            return end, centre, r, sweep, turn
        return None

    def full(self, pos: Mapping[str, float]) -> tuple[tuple[str, float], ...]:
        return tuple((a, pos[a]) for a in self.axes)

    # --- subprograms: G91 bodies, the same from wherever they are called ---------------
    def make_sub(self, index: int) -> None:
        rng = self.rng
        numbered = rng.random() < 0.5
        name = str(100 + index) if numbered else f"STROKE {chr(65 + index)}"
        header = f"%L{name}" if numbered else f"%L {name.lower()}"
        lines = [_Line([header], role="header")]
        body: list[_Rel | str] = []
        plane: int | None = None
        if self.planes and rng.random() < 0.6:
            plane = rng.choice(self.planes)
        lines.append(_Line(["G91"] if plane is None else [f"G{plane}", "G91"]))
        feeds = False
        last_g: int | None = None
        for _ in range(rng.randint(1, 4)):
            g = rng.choice((0, 1, 1, 2, 3)) if plane is not None else rng.choice((0, 1, 1))
            words = [f"G0{g}"]
            line = _Line(words)
            if g in (0, 1):
                chosen = rng.sample(self.axes, rng.randint(1, len(self.axes)))
                delta = []
                for a in self.axes:
                    if a in chosen:
                        text, value = _num(rng.uniform(-5, 5))
                        words.append(f"{a}{text}")
                        delta.append((a, value))
                rel_centre, by_radius = None, False
            else:
                assert plane is not None
                local = _Generator(0, self.axes, {a: (-8.0, 8.0) for a in self.axes}, {}, ())
                local.rng = rng
                found = local.arc({a: 0.0 for a in self.axes}, plane, 4.0, helix=False)
                if found is None:
                    continue
                end, rel_centre, r, sweep, turn = found
                g = 3 if turn == 1 else 2
                words[-1] = f"G0{g}"
                a, b, _ = _PLANES[plane]
                delta = [(a, end[a]), (b, end[b])]
                words += [f"{a}{_num(end[a])[0]}", f"{b}{_num(end[b])[0]}"]
                by_radius = sweep < 360.0 and rng.random() < 0.4
                if by_radius:
                    words.append(f"R{_num(r if sweep <= 180 else -r)[0]}")
                else:
                    if sweep < 360.0:
                        line.arc = (len(words) - 2, len(words))
                        line.arc_geom = (end[a] - rel_centre[0], r)
                    words += [f"{_CENTRE[a]}{_num(rel_centre[0])[0]}"]
                    words += [f"{_CENTRE[b]}{_num(rel_centre[1])[0]}"]
            feed_word = None
            if g != 0 and not feeds:
                feeds = True
                words.append(f"F{rng.choice((300, 800, 1500))}")
                feed_word = len(words) - 1
            body.append(_Rel(len(lines), g, tuple(delta), plane, rel_centre, by_radius, feed_word))
            lines.append(line)
            last_g = g
        if self.subs and rng.random() < 0.3:  # nested: call an earlier subprogram
            inner = rng.choice(list(self.subs.values()))
            lines.append(_Line(list(inner.call), role="call"))
            body.append(inner.name)
            plane = inner.plane if inner.plane is not None else plane
            last_g = inner.last_g if inner.last_g is not None else last_g
            feeds = feeds or inner.feeds
        lines.append(_Line([rng.choice(("M17", "M29"))], role="end"))
        call = [f"L{name}"] if numbered else ["LL", name.lower()]
        self.subs[name] = _Sub(name, call, lines, body, plane, last_g, feeds)

    def run_sub(self, name: str, pos: dict[str, float], out: list[_Step]) -> bool:
        """Append the subprogram's motions from `pos` (moved along): False if it leaves the
        bounds."""
        for item in self.subs[name].body:
            if isinstance(item, str):
                if not self.run_sub(item, pos, out):
                    return False
                continue
            start = dict(pos)
            for a, d in item.delta:
                pos[a] = start[a] + d  # as the interpreter: position + increment
            if not self.inside(pos):
                return False
            centre = None
            if item.centre_off is not None and item.plane is not None:
                a, b, _ = _PLANES[item.plane]
                centre = (start[a] + item.centre_off[0], start[b] + item.centre_off[1])
                if not self.circle_inside(item.plane, centre, math.hypot(*item.centre_off)):
                    return False
            out.append(
                _Step(
                    name,
                    item.local,
                    item.g,
                    self.full(pos),
                    item.plane,
                    centre,
                    item.by_radius,
                    item.feed_word,
                )
            )
        return True

    # --- main program -----------------------------------------------------------------
    def add(self, line: _Line) -> int:
        """Append a line (sometimes numbered N.., sometimes commented); its main index."""
        if self.rng.random() < 0.3 and not line.skipped:
            line.words.insert(0, f"N{10 * (len(self.main) + 1)}")
            line.arc = None if line.arc is None else (line.arc[0] + 1, line.arc[1] + 1)
            line.feed_at = None if line.feed_at is None else line.feed_at + 1
        if self.rng.random() < 0.15 and line.role != "call":
            line.comment = self.rng.choice(("check", "Messung", "kv test", "back (and) forth"))
        self.main.append(line)
        return len(self.main) - 1

    def modal_words(self, g: int) -> list[str]:
        words = []
        if self.rng.random() < 0.15:
            self.absolute = not self.absolute
            words.append("G90" if self.absolute else "G91")
        if g != self.g or self.rng.random() < 0.3:
            words.append(f"G0{g}")
        self.g = g
        return words

    def axis_words(self, target: Mapping[str, float], force: tuple[str, ...]) -> list[str]:
        words = []
        for a in self.axes:
            if target[a] == self.pos[a] and a not in force and self.rng.random() < 0.7:
                continue
            value = target[a] if self.absolute else target[a] - self.pos[a]
            text, read = _num(value)
            words.append(f"{a}{text}")
            self.pos[a] = read if self.absolute else self.pos[a] + read
        return words

    def feed_word(self, line: _Line) -> None:
        if self.feed is None or self.rng.random() < 0.2:
            self.feed = float(self.rng.choice((100, 250, 600, 1000, 2500)))
            line.words.append(f"F{self.feed:g}")
            line.feed_at = len(line.words) - 1

    def record(
        self,
        line: _Line,
        g: int,
        centre: tuple[float, float] | None = None,
        by_radius: bool = False,
    ) -> None:
        index = self.add(line)
        plane = self.plane if g in (2, 3) else None
        self.steps.append(
            _Step(None, index, g, self.full(self.pos), plane, centre, by_radius, line.feed_at)
        )

    def linear(self) -> None:
        g = self.rng.choice((0, 1))
        target = {a: _num(self.rng.uniform(lo, hi))[1] for a, (lo, hi) in self.bounds.items()}
        line = _Line(self.modal_words(g))
        line.words += self.axis_words(target, force=(self.rng.choice(self.axes),))
        if g == 1:
            self.feed_word(line)
        self.record(line, g)

    def circle(self) -> None:
        plane = self.plane
        if plane not in self.planes or self.rng.random() < 0.2:
            plane = self.rng.choice(self.planes)
        found = self.arc(self.pos, plane, 30.0, helix=self.rng.random() < 0.25)
        if found is None:
            return
        end, centre, r, sweep, turn = found
        a, b, _ = _PLANES[plane]
        start = dict(self.pos)
        words = [f"G{plane}"] if plane != self.plane or self.rng.random() < 0.2 else []
        self.plane = plane
        words += self.modal_words(3 if turn == 1 else 2)
        full_circle = sweep == 360.0
        words += self.axis_words(end, force=() if full_circle else (a, b))
        line = _Line(words)
        by_radius = not full_circle and self.rng.random() < 0.4
        if by_radius:
            words.append(f"R{_num(r if sweep <= 180 else -r)[0]}")
        else:
            if not full_circle:
                line.arc = (next(i for i, w in enumerate(words) if w[0] == a), len(words))
                line.arc_geom = (end[a] - centre[0], r)
            words.append(f"{_CENTRE[a]}{_num(centre[0] - start[a])[0]}")
            words.append(f"{_CENTRE[b]}{_num(centre[1] - start[b])[0]}")
        self.feed_word(line)
        self.record(line, self.g, centre, by_radius)

    def call(self) -> None:
        if not self.subs:
            return
        sub = self.subs[self.rng.choice(sorted(self.subs))]
        numbered = sub.call[0] != "LL"
        reps = self.rng.randint(1, 3) if numbered else 1
        if (
            not sub.feeds
            and self.feed is None
            and any(isinstance(r, _Rel) and r.g for r in sub.body)
        ):
            return
        pos = dict(self.pos)
        steps: list[_Step] = []
        for _ in range(reps):
            if not self.run_sub(sub.name, pos, steps):
                return
        p_word = [f"P{reps}"] if numbered and (reps > 1 or self.rng.random() < 0.3) else []
        self.add(_Line(sub.call + p_word, role="call"))
        self.pos = pos
        self.steps += steps
        self.called.add(sub.name)
        self.mark_called(sub)
        self.absolute = False
        self.g = sub.last_g if sub.last_g is not None else self.g
        self.plane = sub.plane if sub.plane is not None else self.plane
        if sub.feeds:
            self.feed = 1.0  # set inside: any later feed block may leave F out

    def mark_called(self, sub: _Sub) -> None:
        for item in sub.body:
            if isinstance(item, str):
                self.called.add(item)
                self.mark_called(self.subs[item])

    def other(self) -> None:
        rng = self.rng
        choice = rng.randrange(7)
        if choice == 0 and "X" in self.axes:  # G04 takes its time as X
            self.add(_Line(["G04", f"X{_num(rng.uniform(0, 2))[0]}"]))
        elif choice == 1:
            self.add(_Line([rng.choice(("M3", "M4")), f"S{rng.randrange(100, 3000)}"]))
        elif choice == 2:
            self.add(_Line(["M19", f"S.POS={rng.randrange(0, 360)}", *rng.choice(([], ["M4"]))]))
        elif choice == 3:
            self.add(_Line([rng.choice(("M5", f"S{rng.randrange(100, 3000)}"))]))
        elif choice == 4:
            self.add(_Line([f"#SLOPE[TYPE={rng.choice(_SLOPES)}]"]))
        elif choice == 5:
            self.add(_Line([f"T{rng.randrange(1, 20)}", f"D{rng.randrange(1, 20)}"]))
        elif self.spindles:
            name = rng.choice(self.spindles)
            self.add(_Line([f"{name}[{rng.choice(('M3', 'M4'))} REV{rng.randrange(100, 2000)}]"]))

    def skipped(self) -> None:
        """A block skip line that would move far away if it ran (within the bounds)."""
        point = [f"{a}{_num(self.rng.uniform(lo, hi))[0]}" for a, (lo, hi) in self.bounds.items()]
        self.add(_Line(["G90", "G00", *point], skipped=True))


def random_program(
    seed: int,
    axes: tuple[str, ...] = ("X", "Z"),
    bounds: Mapping[str, tuple[float, float]] | None = None,
    start: Mapping[str, float] | None = None,
    spindles: tuple[str, ...] = (),
    blocks: int = 25,
    block_skip: bool = True,
) -> GeneratedProgram:
    """A valid program from `seed` for a channel with `axes` (and named `spindles`): about
    `blocks` blocks in the main program, every point and every arc's circle inside `bounds`
    (default ±100 mm per axis), starting from `start` (default 0, inside the bounds).
    `block_skip` adds `/` lines that must be skipped (interpret with skip_blocks=True)."""
    box = {a: (bounds or {}).get(a, (-100.0, 100.0)) for a in axes}
    origin = {a: float((start or {}).get(a, 0.0)) for a in axes}
    gen = _Generator(seed, axes, box, origin, spindles)
    rng = gen.rng
    for i in range(rng.randint(0, 3)):
        gen.make_sub(i)
    for _ in range(blocks):
        kind = rng.random()
        if kind < 0.35 or (kind < 0.6 and not gen.planes):
            gen.linear()
        elif kind < 0.6:
            gen.circle()
        elif kind < 0.75:
            gen.call()
        elif kind < 0.83 and block_skip:
            gen.skipped()
        else:
            gen.other()
    if not gen.steps:
        gen.linear()
    gen.add(_Line([rng.choice(("M30", "M02"))], role="end"))
    return _layout(gen, seed, subs_first=rng.random() < 0.5, header=rng.random() < 0.5)


def _layout(gen: _Generator, seed: int, subs_first: bool, header: bool) -> GeneratedProgram:
    """Place main program and the called subprograms; give every motion its line."""
    subs = [gen.subs[n] for n in sorted(gen.subs) if n in gen.called]
    main = ([_Line(["%main"], role="header")] if header or subs_first else []) + gen.main
    offset = len(main) - len(gen.main)
    blocks: list[list[_Line]] = [s.lines for s in subs]
    order = [*blocks, main] if subs_first else [main, *blocks]
    lines = [line for part in order for line in part]
    start: dict[str | None, int] = {}
    at = 0
    for part, owner in zip(
        order,
        [*(s.name for s in subs), None] if subs_first else [None, *(s.name for s in subs)],
        strict=True,
    ):
        start[owner] = at + (offset if owner is None else 0)
        at += len(part)
    motions = tuple(
        Motion(
            start[s.owner] + s.local + 1,
            s.g,
            s.end,
            s.plane,
            s.centre,
            (_R_ARC_TOLERANCE_MM if s.by_radius else 1e-9) if s.centre is not None else 0.0,
        )
        for s in gen.steps
    )
    first = next(s for s in gen.steps if s.g != 0) if any(s.g for s in gen.steps) else None
    first_feed = (
        (0, 0)
        if first is None or first.feed_word is None
        else (
            start[first.owner] + first.local + 1,
            first.feed_word,
        )
    )
    return GeneratedProgram(
        seed,
        "\n".join(line.text() for line in lines) + "\n",
        dict(gen.pos),
        motions,
        tuple(lines),
        first_feed,
    )


def _with(lines: tuple[_Line, ...], index: int, line: _Line | None, insert: bool = False) -> str:
    out = list(lines)
    if insert and line is not None:
        out.insert(index, line)
    elif line is not None:
        out[index] = line
    return "\n".join(x.text() for x in out) + "\n"


def mutate(program: GeneratedProgram, seed: int) -> Mutation:
    """`program` with one thing broken, and where the interpreter must report it: an unknown
    address, the program end removed, a call of a subprogram nobody defines, the first F
    removed, an arc end moved off its circle."""
    rng = random.Random(seed)
    lines = program.lines
    executed = [
        i for i, x in enumerate(lines) if x.role in ("block", "end") and not x.skipped and x.words
    ]
    ends = [i for i, x in enumerate(lines) if x.role == "end" and x.words[-1] in ("M30", "M02")]
    main_end = ends[0]
    header = next(
        (i for i, x in enumerate(lines) if x.words == ["%main"]), -1
    )  # the main program starts after it, or at line 1
    arcs = [i for i in executed if lines[i].arc is not None]
    kinds = ["unknown_address", "no_end", "undefined_sub"]
    if program.first_feed[0]:
        kinds.append("missing_feed")
    if arcs:
        kinds.append("arc_radius")
    kind = rng.choice(kinds)
    if kind == "unknown_address":
        i = rng.choice(executed)
        letter = rng.choice([c for c in "EHOQ" if c not in program.end])
        line = replace(lines[i], words=[*lines[i].words, f"{letter}7"])
        return Mutation(
            kind, _with(lines, i, line), i + 1, line.column(len(line.words) - 1), Code.BLOCK_SYNTAX
        )
    if kind == "no_end":
        line = replace(lines[main_end], words=["(no", "end)"])
        return Mutation(kind, _with(lines, main_end, line), main_end + 1, 1, Code.PROGRAM_STRUCTURE)
    if kind == "undefined_sub":
        at = rng.randint(header + 1, main_end)
        call = _Line(rng.choice((["L999"], ["LL", "nowhere"])), role="call")
        return Mutation(
            kind, _with(lines, at, call, insert=True), at + 1, 1, Code.PROGRAM_STRUCTURE
        )
    if kind == "missing_feed":
        no, f_index = program.first_feed
        words = [w for k, w in enumerate(lines[no - 1].words) if k != f_index]
        line = replace(lines[no - 1], words=words)
        motion = [k for k, w in enumerate(words) if w in ("G01", "G02", "G03")]
        first = motion or [k for k, w in enumerate(words) if w[0] not in "NGF"]
        return Mutation(
            kind, _with(lines, no - 1, line), no, line.column(first[0]), Code.FEED_MISSING
        )
    i = rng.choice(arcs)
    end_word, centre_word = lines[i].arc or (0, 0)
    u, r = lines[i].arc_geom or (0.0, 0.0)
    # moving the end by d along its first axis changes the radius unless d = -2u: one of
    # these moves it well beyond the 2 µm the interpreter allows
    delta = next(
        d
        for d in (0.5, -0.5, 2.0, -2.0, 5.0)
        if abs(math.sqrt(r * r + 2 * d * u + d * d) - r) > 0.01
    )

    words = list(lines[i].words)
    words[end_word] = words[end_word][0] + _num(float(words[end_word][1:]) + delta)[0]
    line = replace(lines[i], words=words)
    return Mutation(kind, _with(lines, i, line), i + 1, line.column(centre_word), Code.ARC_GEOMETRY)
