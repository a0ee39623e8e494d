"""RX/RY/RZ, the effective distances of a rotary move [003 §1.2]: with them the path feed
counts the arc the tool contact point travels about the rotary axis, so F is the speed at the
tool; without them the rotary axis only follows the linear axes. The manual's spiral groove
at the end face on the demo lathe (its main spindle as the C axis)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc_sim.commands import Invalid, Mdi
from tests.nc_sim.sim_helpers import L, make, run_program

# 003 Fig. 1-3: "N0144 G00 X-30 Y0 Z501 C90 ... N0146 G01 X-70 C-270 RX50 F1200"
APPROACH = "G01 X-30 C90 F3000\n"
GROOVE = "G01 X-70 C-270 RX50 F1200\n"


def _cruise(program: str) -> tuple[float, float]:
    """X (mm/s) and C (°/s) at their steadiest on the groove block (line 2)."""
    _sim, m, rec = run_program(program + "M30\n", 20.0)
    on_groove = rec[:, m.channel_slot, L.R_LINE] == 2
    vx = np.abs(rec[on_groove, m.axis("X").slot, L.R_V_CMD])
    vc = np.abs(rec[on_groove, m.axis("S1").slot, L.R_V_CMD])
    assert rec[-1, m.axis("X").slot, L.R_P_CMD] == pytest.approx(-70.0)
    return float(np.median(vx[vx > 0])), float(np.median(vc[vc > 0]))


def test_rx_makes_f_the_speed_at_the_tool_on_the_spiral_groove() -> None:
    # 40 mm along X and 360° at 50 mm from the centre: sqrt(40² + (2π·50)²) = 316.70 mm of
    # path at F1200 = 20 mm/s
    path = math.hypot(40.0, 2 * math.pi * 50.0)
    vx, vc = _cruise(APPROACH + GROOVE)
    assert vx == pytest.approx(20.0 * 40.0 / path, rel=1e-6)
    assert vc == pytest.approx(20.0 * 360.0 / path, rel=1e-6)
    assert math.radians(vc) * 50.0 == pytest.approx(20.0 * 2 * math.pi * 50.0 / path, rel=1e-6)


def test_without_rx_the_rotary_axis_only_follows_the_linear_move() -> None:
    vx, vc = _cruise(APPROACH + GROOVE.replace(" RX50", ""))
    assert vx == pytest.approx(20.0) and vc == pytest.approx(20.0 * 360.0 / 40.0)


@pytest.mark.parametrize(
    ("block", "says", "column"),
    [("G02 X10 Z-95 R5 RX50 F100", "only in G00/G01", 17), ("RY20", "needs a move", 1)],
)
def test_rx_outside_a_straight_move_is_refused(block: str, says: str, column: int) -> None:
    _sim, m, _cfg = make()
    outcome = m.submit(Mdi(block))
    assert isinstance(outcome, Invalid) and says in outcome.message
    assert outcome.column == column
