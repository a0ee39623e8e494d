"""The interpreter against seeded random programs (tests/nc_sim/channel/randprog.py).

The generator works out every motion itself while it writes the program (the position after
each block, each arc's centre from the start and the I/J/K it wrote, or the centre it chose
before writing R), so the interpreter's calls are checked against an independent model:
- nothing but ProgramError comes out, no NaN or inf in any call;
- every arc starts and ends on its circle within the interpreter's 2 µm;
- the motions are the generator's, one by one (line, G code, end, centre), and the last one
  ends at the generator's end point;
- a mutated program raises ProgramError at the line, column and code the mutation predicts.
"""

from __future__ import annotations

import math
from dataclasses import fields

import pytest

from nc_sim.channel import canon
from nc_sim.channel.arc_words import ARC_RADIUS_TOLERANCE_MM
from nc_sim.channel.interpreter import interpret
from nc_sim.channel.words import ProgramError
from tests.nc_sim.channel.randprog import GeneratedProgram, mutate, random_program

SEEDS = range(200)
CHANNELS = [(("X", "Z"), ()), (("X", "Y", "Z"), ("S2",)), (("Y", "Z"), ())]
PLANES = {17: ("X", "Y"), 18: ("Z", "X"), 19: ("Y", "Z")}


def _interpret(
    prog: GeneratedProgram, axes: tuple[str, ...], spindles: tuple[str, ...]
) -> list[canon.Call]:
    sink = canon.ListSink()
    interpret(prog.text, sink, axes, spindles, start={a: 0.0 for a in axes})
    return sink.calls


def _numbers(call: canon.Call) -> list[float]:
    out: list[float] = []
    for f in fields(call):
        value = getattr(call, f.name)
        if isinstance(value, float):
            out.append(value)
        elif isinstance(value, tuple):
            for v in value:
                out.extend([v[1]] if isinstance(v, tuple) else [v])
    return out


@pytest.mark.parametrize(("axes", "spindles"), CHANNELS, ids=["XZ", "XYZ", "YZ"])
def test_random_programs_give_the_generators_motions(
    axes: tuple[str, ...], spindles: tuple[str, ...]
) -> None:
    arcs = full_circles = helices = by_radius = 0
    for seed in SEEDS:
        prog = random_program(seed, axes=axes, spindles=spindles)
        calls = _interpret(prog, axes, spindles)
        for call in calls:
            assert all(math.isfinite(v) for v in _numbers(call)), (seed, call)
        motions = [
            c
            for c in calls
            if isinstance(c, canon.StraightTraverse | canon.StraightFeed | canon.ArcFeed)
        ]
        assert len(motions) == len(prog.motions), (seed, prog.text)
        position = {a: 0.0 for a in axes}
        for call, want in zip(motions, prog.motions, strict=True):
            where = (seed, call, want)
            g = {canon.StraightTraverse: 0, canon.StraightFeed: 1}.get(type(call))
            if isinstance(call, canon.ArcFeed):
                g = 3 if call.turn == 1 else 2
            assert (call.line, g) == (want.line, want.g), where
            end = dict(call.end)
            assert [a for a, _ in call.end] == list(axes)
            for a, v in want.end:
                assert end[a] == pytest.approx(v, abs=1e-9), where
            if isinstance(call, canon.ArcFeed):
                assert want.centre is not None and call.plane == want.plane, where
                assert call.centre[0] == pytest.approx(want.centre[0], abs=want.centre_tolerance_mm)
                assert call.centre[1] == pytest.approx(want.centre[1], abs=want.centre_tolerance_mm)
                a, b = PLANES[call.plane]
                r0 = math.hypot(position[a] - call.centre[0], position[b] - call.centre[1])
                r1 = math.hypot(end[a] - call.centre[0], end[b] - call.centre[1])
                assert abs(r0 - r1) <= ARC_RADIUS_TOLERANCE_MM, where
                arcs += 1
                full_circles += (position[a], position[b]) == (end[a], end[b])
                helices += any(position[x] != end[x] for x in axes if x not in (a, b))
                by_radius += want.centre_tolerance_mm > 1e-6
            position = end
        assert position == pytest.approx(prog.end, abs=1e-9), seed
    if len(axes) > 2 or axes == ("X", "Z") or axes == ("Y", "Z"):
        assert min(arcs, full_circles, by_radius) >= 20, (arcs, full_circles, by_radius)
    if axes == ("X", "Y", "Z"):
        assert helices >= 10


def test_random_programs_cover_the_features() -> None:
    """The generator writes what it claims: subprograms (both calls, nested, P), G90/G91,
    block skip, dwell, spindle words, #SLOPE, planes."""
    texts = "\n".join(random_program(s, axes=("X", "Y", "Z"), spindles=("S2",)).text for s in SEEDS)
    for token in (
        "%L",
        "LL ",
        " P2",
        "M17",
        "M29",
        "G91",
        "G90",
        "\n/",
        "G04 X",
        "M19 S.POS=",
        "#SLOPE[TYPE=",
        "S2[M",
        "G17",
        "G18",
        "G19",
        " R-",
        "T",
        "M3 S",
        "M02",
        "M30",
    ):
        assert token in texts, token


def test_random_programs_stay_inside_the_bounds() -> None:
    bounds = {"X": (0.0, 120.0), "Z": (-150.0, -20.0)}
    start = {"X": 50.0, "Z": -100.0}
    for seed in SEEDS:
        prog = random_program(seed, axes=("X", "Z"), bounds=bounds, start=start)
        sink = canon.ListSink()
        interpret(prog.text, sink, ("X", "Z"), start=start)
        position = dict(start)
        for call in sink.calls:
            if isinstance(call, canon.ArcFeed):  # the whole circle: the arc is on it
                r = math.hypot(position["Z"] - call.centre[0], position["X"] - call.centre[1])
                assert bounds["Z"][0] - 1e-6 <= call.centre[0] - r, (seed, call)
                assert call.centre[0] + r <= bounds["Z"][1] + 1e-6, (seed, call)
                assert bounds["X"][0] - 1e-6 <= call.centre[1] - r, (seed, call)
                assert call.centre[1] + r <= bounds["X"][1] + 1e-6, (seed, call)
            for a, v in getattr(call, "end", ()):
                assert bounds[a][0] - 1e-9 <= v <= bounds[a][1] + 1e-9, (seed, call)
                position[a] = v
        assert position == pytest.approx(prog.end, abs=1e-9)


@pytest.mark.parametrize(("axes", "spindles"), CHANNELS, ids=["XZ", "XYZ", "YZ"])
def test_a_mutated_program_fails_where_the_mutation_says(
    axes: tuple[str, ...], spindles: tuple[str, ...]
) -> None:
    kinds: set[str] = set()
    for seed in SEEDS:
        prog = random_program(seed, axes=axes, spindles=spindles)
        bad = mutate(prog, seed)
        kinds.add(bad.kind)
        with pytest.raises(ProgramError) as err:
            interpret(bad.text, canon.ListSink(), axes, spindles, start={a: 0.0 for a in axes})
        e = err.value
        lines = bad.text.splitlines()
        assert 1 <= e.line <= len(lines) and 1 <= e.column <= max(1, len(lines[e.line - 1]))
        assert (e.line, e.column, e.code) == (bad.line, bad.column, bad.code), (
            seed,
            bad.kind,
            e.detail,
            bad.text,
        )
    assert kinds == {"unknown_address", "no_end", "undefined_sub", "missing_feed", "arc_radius"}


def test_the_same_seed_gives_the_same_program() -> None:
    assert random_program(7).text == random_program(7).text
    assert random_program(7).text != random_program(8).text
