"""G130-G133, the weightings of acceleration and ramp times [002 §2.5.1] with the effect
P-CHAN-00001 / P-CHAN-00073 choose [002 §3.2.1], on feed blocks of the demo lathe (Z:
a_beschl = a_brems 2000 mm/s², ramp times 20 ms, a_max 5000, G00 a_grenz 3000)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from nc_sim.commands import Accepted, CycleStart, Invalid, Mdi, ProgramLoad, Reset
from nc_sim.errors import Code
from tests.nc_sim.sim_helpers import L, make, mdi, record


def _z_acc(blocks: list[str], channel: dict[str, Any] | None = None) -> np.ndarray:
    """Z's commanded acceleration while the MDI blocks run (5 s)."""
    sim, m, _cfg = make(channel=channel)
    for b in blocks:
        mdi(m, b)
    rec = record(sim, 5.0)
    return np.asarray(rec[:, m.axis("Z").slot, L.R_A_CMD])


def _ramp_ms(a: np.ndarray, to: float) -> int:
    start = int(np.flatnonzero(np.sign(to) * a > 1e-6)[0])
    return int(np.flatnonzero(np.abs(a[start:] - to) < 1e-6)[0]) + 1


def test_g131_weights_every_axis_acceleration_of_feed_blocks_only() -> None:
    assert np.abs(_z_acc(["G131 = 50", "G01 Z-50 F6000"])).max() == pytest.approx(1000.0)
    # a G00 block keeps a_grenz
    assert np.abs(_z_acc(["G131 = 50", "G00 Z-50"])).max() == pytest.approx(3000.0)


def test_g130_weights_the_named_axes_and_sets_the_others_back_to_100_percent() -> None:
    assert np.abs(_z_acc(["G130 Z50", "G01 Z-50 F6000"])).max() == pytest.approx(1000.0)
    # "each further selection ... signifies 100 %": Z is not named the second time
    assert np.abs(_z_acc(["G130 Z50", "G130 X70", "G01 Z-50 F6000"])).max() == (
        pytest.approx(2000.0)
    )
    # and 50 % twice is 50 %, not 25 %
    assert np.abs(_z_acc(["G131 = 50", "G131 = 50", "G01 Z-50 F6000"])).max() == (
        pytest.approx(1000.0)
    )


def test_a_weighting_above_100_percent_stops_at_a_max() -> None:
    assert np.abs(_z_acc(["G131 = 400", "G01 Z0 F12000"])).max() == pytest.approx(5000.0)


def test_p_chan_00001_chooses_the_acceleration_the_weighting_acts_on() -> None:
    # 2: the deceleration only (1: the acceleration only)
    a = _z_acc(["G131 = 50", "G01 Z0 F6000"], {"prog_start.slope.acceleration": 2})
    assert (a.max(), -a.min()) == (pytest.approx(2000.0), pytest.approx(1000.0))
    a = _z_acc(["G131 = 50", "G01 Z0 F6000"], {"prog_start.slope.acceleration": 1})
    assert (a.max(), -a.min()) == (pytest.approx(1000.0), pytest.approx(2000.0))


def test_g133_weights_the_ramp_times_as_p_chan_00073_chooses() -> None:
    a = _z_acc(["G133 = 200", "G01 Z0 F6000"])  # 0: all four ramp times, 20 -> 40 ms
    assert _ramp_ms(a, 2000.0) == pytest.approx(40, abs=1)
    assert _ramp_ms(a, -2000.0) == pytest.approx(40, abs=1)
    # 3: only T_R,decel,inc (tr_brems_zu)
    a = _z_acc(["G133 = 200", "G01 Z0 F6000"], {"prog_start.slope.ramp_time": 3})
    assert _ramp_ms(a, 2000.0) == pytest.approx(20, abs=1)
    assert _ramp_ms(a, -2000.0) == pytest.approx(40, abs=1)


def test_a_program_starts_and_a_reset_leaves_at_100_percent() -> None:
    sim, m, _cfg = make()
    mdi(m, "G131 = 50")
    assert isinstance(m.submit(ProgramLoad("p", "G01 Z-50 F6000\nM30\n")), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    rec = record(sim, 3.0)
    assert np.abs(rec[:, m.axis("Z").slot, L.R_A_CMD]).max() == pytest.approx(2000.0)
    mdi(m, "G131 = 50")
    assert isinstance(m.submit(Reset()), Accepted)
    mdi(m, "G01 Z-100 F6000")
    rec = record(sim, 3.0)
    assert np.abs(rec[:, m.axis("Z").slot, L.R_A_CMD]).max() == pytest.approx(2000.0)


@pytest.mark.parametrize(
    ("block", "column", "says"),
    [
        ("G131 = 0", 1, "above 0 %"),
        ("G130 X50 G01 Z10", 10, "moves nothing"),
        ("G134 = 50", 1, "G134 = is not supported"),
        ("G130", 1, "needs axes"),
        ("G131 = 50 G130 X20", 11, "two acceleration weightings"),
    ],
)
def test_a_bad_weighting_block_is_refused_at_its_column(block: str, column: int, says: str) -> None:
    _sim, m, _cfg = make()
    outcome = m.submit(Mdi(block))
    assert isinstance(outcome, Invalid)
    assert outcome.code == Code.BLOCK_SYNTAX and outcome.column == column
    assert says in outcome.message
