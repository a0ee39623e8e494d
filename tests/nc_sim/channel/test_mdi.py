"""MDI blocks through the interpreter: DIN and axis-specific syntax, modal words carried from
block to block, errors with columns (and nothing changed by a block with an error)."""

from __future__ import annotations

import pytest

from nc_sim.channel import canon
from nc_sim.channel.interpreter import interpret_blocks
from nc_sim.channel.mdi import MdiQueue
from nc_sim.channel.modal import Modal
from nc_sim.channel.words import ProgramError

AXES, SPINDLES = ["X", "Z"], ["S1"]


def _mdi(text: str, modal: Modal | None = None) -> list[str]:
    sink = canon.ListSink()
    modal = modal or Modal(position={"X": 0.0, "Z": 0.0})
    interpret_blocks(text, sink, modal, AXES, SPINDLES)
    return [c.text() for c in sink.calls]


def test_din_and_axis_specific_forms() -> None:
    assert _mdi("N10 G01 X10 Z-2.5 F500") == [
        "SET_FEED_RATE feed_mm_min=500",
        "STRAIGHT_FEED X=10 Z=-2.5",
    ]
    assert _mdi("G74 X1 Z2") == ["HOME X=1 Z=2"]
    assert _mdi("#SLOPE[TYPE=TRAPEZ]") == ["SET_SLOPE slope_type=1"]
    assert _mdi("M3 S1000") == ["SPINDLE_ON spindle=S m=3 speed_rpm=1000"]
    assert _mdi("M19 S.POS=90 M4") == ["SPINDLE_ORIENT spindle=S pos_deg=90 direction=-1"]
    assert _mdi("S1[M19 REV200 POS100]") == ["SPINDLE_ORIENT spindle=S1 pos_deg=100 speed_rpm=200"]
    assert _mdi("S[G74]") == ["HOME S=1"]
    assert _mdi("M8") == ["M_FUNCTION m=8"]
    assert _mdi("S1[G136=50]") == ["SPINDLE_SETTINGS spindle=S1 feedforward=136 ff_weight_pct=50"]


def test_modal_words_carry_over_from_block_to_block() -> None:
    """After `G01 X60 F500` a bare `X70` is a feed move at 500 mm/min (issue 16), and G91
    stays in force: positions add up from the end of the block before."""
    modal = Modal(position={"X": 50.0, "Z": 0.0})
    assert _mdi("G01 X60 F500", modal) == [
        "SET_FEED_RATE feed_mm_min=500",
        "STRAIGHT_FEED X=60 Z=0",
    ]
    assert _mdi("X70", modal) == ["STRAIGHT_FEED X=70 Z=0"]
    assert (modal.motion, modal.feed_mm_min) == (1, 500.0)
    _mdi("G91 Z-5", modal)
    assert _mdi("Z-5", modal) == ["STRAIGHT_FEED X=70 Z=-10"]


def test_a_block_with_an_error_changes_no_modal_word() -> None:
    modal = Modal(position={"X": 0.0, "Z": 0.0})
    with pytest.raises(ProgramError):
        _mdi("G01 G91 X5 F300 Q", modal)
    assert (modal.motion, modal.absolute, modal.feed_mm_min) == (0, True, None)
    assert modal.position == {"X": 0.0, "Z": 0.0}


@pytest.mark.parametrize(
    ("text", "column"),
    [
        ("G01 X10 Y5 F100", 9),
        ("G01 X1Q", 7),
        ("S[M3 FOO]", 6),
        ("#SLOPE[TYPE=FAST]", 8),
        ("G01 X1 X2", 8),
        ("G2.5 X1", 2),
        ("G74 X1.5", 6),
        ("G74 X0", 6),
        ("M3 S-1000", 5),
        ("S[M3 REV-1000]", 9),
        ("M19 S-5", 6),
    ],
)
def test_bad_blocks_name_the_column(text: str, column: int) -> None:
    with pytest.raises(ProgramError) as exc:
        _mdi(text)
    assert (exc.value.line, exc.value.column) == (1, column)


@pytest.mark.parametrize(
    ("text", "column", "why"),
    [
        ("M3 S１０００", 5, "'１' is not an NC character"),  # full-width digits
        ("M3 S1_000", 6, "unexpected '_'"),  # Python's digit grouping is no NC number
        ("G01 X" + "9" * 400, 6, "too large"),  # float() would give inf
        ("S[M3 REV" + "9" * 400 + "]", 9, "too large"),
        ("M19 S.POS=" + "9" * 400, 11, "too large"),
    ],
)
def test_numbers_are_ascii_and_finite(text: str, column: int, why: str) -> None:
    with pytest.raises(ProgramError, match=why) as exc:
        _mdi(text)
    assert exc.value.column == column


def test_diameter_programming_carries_over_until_a_reset() -> None:
    """G51 stays in force from one MDI block to the next (X words are diameters, the machine's
    X a radius); a reset brings back G52, radius programming."""
    queue = MdiQueue()
    queue.modal.position = {"X": 0.0, "Z": 0.0}
    assert _mdi("G51 G00 X40", queue.modal) == ["STRAIGHT_TRAVERSE X=20 Z=0"]
    assert _mdi("X30", queue.modal) == ["STRAIGHT_TRAVERSE X=15 Z=0"]
    queue.reset_modal()
    queue.modal.position = {"X": 15.0, "Z": 0.0}
    assert _mdi("G00 X30", queue.modal) == ["STRAIGHT_TRAVERSE X=30 Z=0"]


def test_g63_in_mdi_taps_at_the_speed_an_earlier_block_programmed() -> None:
    """The last S of the main spindle, also from its axis-specific form, is G63's speed
    [000 §2.8.6]: F 300 mm/min at 200 rpm, a 1.5 mm pitch."""
    modal = Modal(position={"X": 0.0, "Z": 0.0})
    assert _mdi("S[M19 POS0 REV200]", modal) == ["SPINDLE_ORIENT spindle=S pos_deg=0 speed_rpm=200"]
    assert _mdi("G63 Z-30 F300", modal)[-1] == (
        "TAP_FEED X=0 Z=-30 spindle=S speed_rpm=200 feed_mm_min=300"
    )
