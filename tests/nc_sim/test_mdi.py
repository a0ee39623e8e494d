"""MDI blocks: DIN and axis-specific syntax, errors with columns."""

from __future__ import annotations

import pytest

from nc_sim.blocks import BlockError, parse_block

AXES, SPINDLES = ["X", "Z"], ["S1"]


def test_din_and_axis_specific_forms() -> None:
    b = parse_block("N10 G01 X10 Z-2.5 F500", AXES, SPINDLES)
    assert (b.number, b.motion, b.axes, b.feed) == (10, 1, {"X": 10.0, "Z": -2.5}, 500.0)
    assert parse_block("G74 X1 Z2", AXES).homing == {"X": 1, "Z": 2}
    assert parse_block("#SLOPE[TYPE=TRAPEZ]", AXES).slope_type == 1
    (s,) = parse_block("M3 S1000", AXES, SPINDLES).spindles
    assert (s.spindle, s.m, s.speed_rpm) == ("S", 3, 1000.0)
    (s,) = parse_block("M19 S.POS=90 M4", AXES, SPINDLES).spindles
    assert (s.m, s.pos_deg, s.direction) == (19, 90.0, -1)
    (s,) = parse_block("S1[M19 REV200 POS100]", AXES, SPINDLES).spindles
    assert (s.spindle, s.m, s.speed_rpm, s.pos_deg) == ("S1", 19, 200.0, 100.0)
    assert parse_block("S[G74]", AXES, SPINDLES).spindles[0].g == [74]
    assert parse_block("M8", AXES).m_functions == [8]


@pytest.mark.parametrize(
    ("text", "column"),
    [
        ("G01 X10 Y5", 9),
        ("G01 X1Q", 7),
        ("S[M3 FOO]", 6),
        ("#SLOPE[TYPE=FAST]", 8),
        ("G01 X1 X2", 8),
        ("G2.5 X1", 2),
    ],
)
def test_bad_blocks_name_the_column(text: str, column: int) -> None:
    with pytest.raises(BlockError) as exc:
        parse_block(text, AXES, SPINDLES)
    assert exc.value.column == column


def test_g74_digits_are_the_homing_order_and_s_is_the_main_spindle() -> None:
    """[000 §2.7] `G74 X2 Y1 S1`: S1 homes the spindle with order 1, it is no speed."""
    b = parse_block("G74 X2 Z1 S1", AXES, SPINDLES)
    assert b.homing == {"X": 2, "Z": 1, "S": 1} and b.spindles == []
    assert parse_block("G74 S1", AXES, SPINDLES).homing == {"S": 1}


@pytest.mark.parametrize(
    ("text", "column"),
    [("G74 X1.5", 6), ("G74 X0", 6), ("M3 S-1000", 5), ("S[M3 REV-1000]", 9), ("M19 S-5", 6)],
)
def test_bad_homing_order_and_negative_speed_name_the_column(text: str, column: int) -> None:
    with pytest.raises(BlockError) as exc:
        parse_block(text, AXES, SPINDLES)
    assert exc.value.column == column


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
    with pytest.raises(BlockError, match=why) as exc:
        parse_block(text, AXES, SPINDLES)
    assert exc.value.column == column
