"""The interpreter against golden files: program (`interp/*.ngc`) -> canonical calls
(`*.expected`, one `<line>: <call>` per line) or `ERROR <line>:<column> <job error>`. The
channel has the axes X, Y, Z and the spindle S2 besides the main spindle S, unless the
program's first line names its axes: `; axes: X Z C`; then C is the main spindle's name as the
rotary axis (P-CHAN-00010), and the spindle starts in spindle mode.

The expected numbers come from geometry worked by hand (the arc centres are noted in the
programs' comments), not from the interpreter's output.
"""

from __future__ import annotations

import math
import random
from pathlib import Path

import pytest

from nc_sim.channel import canon
from nc_sim.channel.interpreter import interpret, interpret_steps
from nc_sim.channel.words import ProgramError
from nc_sim.errors import Code

GOLDEN = Path(__file__).parent / "interp"
PROGRAMS = sorted(GOLDEN.glob("*.ngc"))


def _axes(text: str) -> tuple[str, ...]:
    first = text.split("\n", 1)[0]
    if first.startswith("; axes:"):
        return tuple(first.removeprefix("; axes:").split())
    return ("X", "Y", "Z")


def _run(text: str, skip_blocks: bool = True) -> canon.ListSink:
    sink = canon.ListSink()
    axes = _axes(text)
    c_axis = "C" if "C" in axes else None
    interpret(text, sink, axes, ("S2",), skip_blocks=skip_blocks, c_axis=c_axis)
    return sink


@pytest.mark.parametrize("path", PROGRAMS, ids=[p.stem for p in PROGRAMS])
def test_golden(path: Path) -> None:
    expected = path.with_suffix(".expected").read_text().splitlines()
    text = path.read_text()
    if expected[0].startswith("ERROR"):
        with pytest.raises(ProgramError) as err:
            _run(text)
        e = err.value
        assert f"ERROR {e.line}:{e.column} {int(e.code)}" == expected[0], e.detail
    else:
        assert _run(text).lines() == expected


def test_every_golden_arc_starts_and_ends_on_its_circle() -> None:
    """Independent of the expected files: each ARC_FEED's start and end lie on one circle."""
    planes = {17: ("X", "Y"), 18: ("Z", "X"), 19: ("Y", "Z")}
    arcs = 0
    for path in PROGRAMS:
        if path.stem.startswith("bad_"):
            continue
        position = {"X": 0.0, "Y": 0.0, "Z": 0.0}
        for call in _run(path.read_text()).calls:
            end = dict(getattr(call, "end", ()))
            if isinstance(call, canon.ArcFeed):
                a, b = planes[call.plane]
                r0 = math.hypot(position[a] - call.centre[0], position[b] - call.centre[1])
                r1 = math.hypot(end[a] - call.centre[0], end[b] - call.centre[1])
                assert r0 == pytest.approx(r1, abs=1e-9) and r0 > 0, (path.stem, call)
                arcs += 1
            position.update(end)
    assert arcs >= 8


def test_block_skip_off_runs_the_skipped_blocks() -> None:
    lines = _run((GOLDEN / "block_skip.ngc").read_text(), skip_blocks=False).lines()
    assert "2: STRAIGHT_TRAVERSE X=99 Y=0 Z=0" in lines
    assert "4: M_FUNCTION m=8" in lines


def test_calls_before_an_error_stay_in_the_sink() -> None:
    sink = canon.ListSink()
    with pytest.raises(ProgramError):
        interpret("G00 X5\nG01 X6\nM30", sink)
    assert sink.lines() == ["1: STRAIGHT_TRAVERSE X=5 Y=0 Z=0"]


def test_start_position_is_where_incremental_moves_begin() -> None:
    sink = canon.ListSink()
    interpret("G91 G00 X1\nM30", sink, axes=("X", "Z"), start={"X": 10.0, "Z": -3.0})
    assert sink.lines()[0] == "1: STRAIGHT_TRAVERSE X=11 Z=-3"


def test_after_g74_the_axes_stand_at_their_reference_positions() -> None:
    """G74 ends at kenngr.ref_pos [000 §2.7]: an incremental move and an arc centre after it
    count from there, not from where the axis was before homing."""
    sink = canon.ListSink()
    text = "G74 X1\nG91 G01 X5 F100\nG90 G17 G02 X25 Y0 I5 J0\nM30"
    interpret(text, sink, axes=("X", "Y"), start={"X": 80.0, "Y": 0.0}, home={"X": 10.0})
    assert sink.lines()[1:3] == ["2: SET_FEED_RATE feed_mm_min=100", "2: STRAIGHT_FEED X=15 Y=0"]
    assert sink.lines()[4] == "3: ARC_FEED X=25 Y=0 plane=17 centre=20,0 turn=-1"


def test_g04_takes_its_time_as_x_on_a_machine_without_x() -> None:
    """X after G04 is the dwell time in seconds, an address of its own [002 §2.6 G04]; without
    G04 it is an unknown axis there."""
    sink = canon.ListSink()
    interpret("G04 X1.5\nM30", sink, axes=("Z",))
    assert sink.lines()[0] == "1: DWELL time_s=1.5"
    with pytest.raises(ProgramError) as err:
        interpret("G01 X5 F100\nM30", canon.ListSink(), axes=("Z",))
    assert (err.value.line, err.value.column) == (1, 5)


@pytest.mark.parametrize(
    ("text", "where", "code"),
    [
        ("M17\nM30", "1:1", Code.BLOCK_SYNTAX),  # return outside a subprogram
        ("G90 G91 X1\nM30", "1:5", Code.BLOCK_SYNTAX),  # G90 and G91 in one block
        ("M3 S.POS=90\nM30", "1:4", Code.BLOCK_SYNTAX),  # S.POS with M3, not M19
        ("%L1\nG00 X1\n%\nL1\nM30", "1:1", Code.PROGRAM_STRUCTURE),  # no M17/M29
        ("%L1\nL1\nM17\n%\nL1\nM30", "2:1", Code.PROGRAM_STRUCTURE),  # calls itself forever
        ("G04 F2\nM30", "1:1", Code.BLOCK_SYNTAX),  # G04 takes X seconds
        ("G02 X10 F100\nM30", "1:1", Code.ARC_GEOMETRY),  # no centre, no radius
        ("G01 X1 Y2 X3 F100\nM30", "1:11", Code.BLOCK_SYNTAX),  # X twice
        ("G01 G00 X1\nM30", "1:5", Code.BLOCK_SYNTAX),  # two motion G codes
        ("#SLOPE[TYPE=FAST]\nM30", "1:8", Code.BLOCK_SYNTAX),
        ("M19 S.POS=90 S9[M3]\nM30", "1:14", Code.UNKNOWN_AXIS),
        ("G00 X\nM30", "1:5", Code.BLOCK_SYNTAX),  # address without a value
        ("S2[M3 REV-5]\nM30", "1:10", Code.BLOCK_SYNTAX),  # column inside S2[...]
        ("#SLOPE G01\nM30", "1:7", Code.BLOCK_SYNTAX),  # #SLOPE needs its [TYPE=..]
        ("#CAX[C]\nM30", "1:6", Code.NOT_SUPPORTED),  # only the main spindle becomes C
        ("G33 G04 X1\nM30", "1:5", Code.BLOCK_SYNTAX),  # G04 takes no motion G code
        ("G63 G74 Z1\nM30", "1:5", Code.BLOCK_SYNTAX),  # nor does G74
    ],
)
def test_bad_blocks(text: str, where: str, code: Code) -> None:
    with pytest.raises(ProgramError) as err:
        _run(text)
    assert (f"{err.value.line}:{err.value.column}", err.value.code) == (where, code)


def test_random_text_gives_calls_or_a_program_error() -> None:
    """Seeded garbage from NC characters: the interpreter never fails any other way."""
    rng = random.Random(16)
    alphabet = "GMXYZIJKRFSTDNLP0123456789.-+ ()[];/#%=\n" + "GXYZ01 " * 4
    for _ in range(3000):
        text = "".join(rng.choice(alphabet) for _ in range(rng.randint(1, 40)))
        try:
            _run(text)
        except ProgramError as err:
            assert err.line >= 1 and err.column >= 1, (text, err)


def test_g60_is_taken_with_g33_and_g63() -> None:
    """A thread cut or a tap starts and ends at rest: exact stop G60 is allowed with them."""
    sink = canon.ListSink()
    interpret("G33 G60 Z-10 K1\nG63 G60 Z0 F300 S200\nM30", sink, axes=("X", "Z"))
    assert sink.lines()[:3] == [
        "1: THREAD_FEED X=0 Z=-10 spindle=S pitch_mm=1 pitch_axis=Z offset_deg=0",
        "2: SET_FEED_RATE feed_mm_min=300",
        "2: TAP_FEED X=0 Z=0 spindle=S speed_rpm=200 feed_mm_min=300",
    ]


def test_cax_with_an_empty_body_names_the_main_spindle() -> None:
    sink = canon.ListSink()
    interpret("#CAX[]\n#CAX OFF[ S ]\nM30", sink, ("X", "Z", "C"), c_axis="C")
    assert sink.lines()[:2] == [
        "1: ROTARY_MODE spindle=S rotary=1",
        "2: ROTARY_MODE spindle=S rotary=0",
    ]


def test_random_thread_and_tapping_words_give_calls_or_a_program_error() -> None:
    """Seeded blocks of G33/G63/G51/#CAX/C words in any order: calls or ProgramError, never
    another exception; the coupled calls carry a positive pitch and a non-zero speed; the
    spindle is one thing at a time [003 §4.2]: ROTARY_MODE only where the mode changes, C
    moves only in rotary mode, spindle functions and G33/G63 only in spindle mode; no NaN."""
    rng = random.Random(17)
    tokens = [
        "G33", "G63", "G51", "G52", "G00", "G01", "G04", "G91", "K1.5", "I2", "J0", "K-1",
        "S.OFFSET=400", "S.OFFSET=90", "#CAX", "#CAX OFF", "S200", "S-200", "S0", "Z-5", "X10",
        "F100", "M3", "M5", "M19", "R3", "C90", "C-45", "G90", "\n", "\n",
    ]  # fmt: skip
    for _ in range(2000):
        text = " ".join(rng.choice(tokens) for _ in range(rng.randint(1, 12))) + "\nM30"
        sink = canon.ListSink()
        try:
            interpret(text, sink, ("X", "Z", "C"), c_axis="C")
        except ProgramError as err:
            assert err.line >= 1 and err.column >= 1, (text, err)
        rotary = False
        for call in sink.calls:
            if isinstance(call, canon.RotaryMode):
                assert call.rotary != rotary, (text, sink.lines())
                rotary = call.rotary
            ends = dict(getattr(call, "end", ()))
            assert not any(math.isnan(v) for v in ends.values()), (text, call)
            if "C" in ends:
                assert rotary and isinstance(
                    call, canon.StraightTraverse | canon.StraightFeed | canon.ArcFeed
                ), (text, call)
            if isinstance(
                call,
                canon.SpindleOn
                | canon.SpindleOff
                | canon.SpindleOrient
                | canon.ThreadFeed
                | canon.TapFeed,
            ):
                assert not rotary, (text, sink.lines())
            if isinstance(call, canon.ThreadFeed):
                assert call.pitch_mm > 0 and 0 <= call.offset_deg < 360, (text, call)
            if isinstance(call, canon.TapFeed):
                assert call.speed_rpm != 0 and call.feed_mm_min > 0, (text, call)


def test_a_program_runs_at_most_100000_blocks_and_is_refused_where_main_calls() -> None:
    """Repetitions count as the blocks they run: a subprogram of two blocks (the move and
    M17) run 50 000 times is exactly 100 000 blocks with the main's G90 and M30 over; nested
    P5000 × P5000 (50 million moves) is refused as soon as the count passes the bound, where
    the main program makes the call. 49 998 runs (99 996 + 3 blocks) still interpret whole."""
    sub = "%L1\nG91 G01 X0.001 F100\nM17\n%L2\nL1 P5000\nM17\n%MAIN\nG90\n"
    sink = canon.ListSink()
    interpret(sub + "L1 P49998\nM30\n", sink, ("X",))
    moves = [c for c in sink.calls if isinstance(c, canon.StraightFeed)]
    assert len(moves) == 49_998
    assert moves[-1].end[0][1] == pytest.approx(49.998)  # 49 998 µm-steps from 0
    for main, col in (("L1 P50000\nM30\n", 1), ("G01 L2 P5000\nM30\n", 5)):
        with pytest.raises(ProgramError) as e:
            interpret(sub + main, canon.ListSink(), ("X",))
        assert (e.value.line, e.value.column, e.value.code) == (9, col, Code.PROGRAM_STRUCTURE)
        assert "more than 100000 blocks" in e.value.detail


def test_a_program_interprets_a_block_per_step() -> None:
    """A host interleaves its own work between steps: one step per block run, repetitions
    included, and the calls so far are in the sink at every step."""
    text = "%L1\nG91 G01 X1 F100\nM17\n%MAIN\nG90\nL1 P3\nM30\n"
    sink = canon.ListSink()
    moves = [
        sum(isinstance(c, canon.StraightFeed) for c in sink.calls)
        for _ in interpret_steps(text, sink, ("X",))
    ]
    # G90, L1 P3, three runs of the move and M17, M30: a move appears with its own step
    assert moves == [0, 0, 1, 1, 2, 2, 3, 3, 3]
    assert isinstance(sink.calls[-1], canon.ProgramEnd)
