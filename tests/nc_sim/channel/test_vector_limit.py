"""#VECTOR LIMIT [002 §2.5.2]: the path's own velocity, acceleration and deceleration limits,
from the program or from the channel list (P-CHAN-00090/00002/00208 in the unit of
P-CHAN-00351), on feed blocks, rapid blocks or both; the demo lathe's Z: F up to 30 m/min,
a_beschl = a_brems 2000 mm/s², G00 333.3 mm/s."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from nc_sim.commands import Invalid, Mdi
from tests.nc_sim.sim_helpers import L, make, mdi, record

# the manual's channel list excerpt
MANUAL = {"vector.velocity": 1500, "vector.acceleration": 1000, "vector.acc_dec_unit": "MM_S2"}


def _z(blocks: list[str], channel: dict[str, Any] | None = None) -> tuple[float, float, float]:
    """Z's top speed (mm/s), top acceleration and deceleration (mm/s²) over the blocks."""
    sim, m, _cfg = make(channel=channel)
    for b in blocks:
        mdi(m, b)
    rec = record(sim, 6.0)
    z = m.axis("Z").slot
    v, a = np.abs(rec[:, z, L.R_V_CMD]), rec[:, z, L.R_A_CMD]
    return float(v.max()), float(a.max()), float(-a.min())


def test_on_all_takes_the_channel_lists_limits() -> None:
    v, acc, dec = _z(["#VECTOR LIMIT ON ALL", "G01 Z0 F6000"], MANUAL)
    assert v == pytest.approx(1500 / 60)  # vector.velocity, mm/min
    assert acc == pytest.approx(1000.0)  # vector.acceleration, MM_S2
    # vector.deceleration's default does not limit: braking from 25 mm/s over the 20 ms ramps
    # reaches more than the 1000 mm/s² the acceleration is held to
    assert dec > 1.5 * 1000.0


def test_on_dec_takes_the_lists_deceleration() -> None:
    channel = {"vector.deceleration": 500, "vector.acc_dec_unit": "MM_S2"}
    v, acc, dec = _z(["#VECTOR LIMIT ON [DEC]", "G01 Z0 F6000"], channel)
    assert [v, acc, dec] == pytest.approx([100.0, 2000.0, 500.0])


def test_programmed_limits_and_the_unit_of_p_chan_00351() -> None:
    v, acc, dec = _z(["#VECTOR LIMIT ON [VEL=3000 ACC=3600000 DEC=1800000]", "G01 Z0 F6000"])
    assert v == pytest.approx(50.0)
    assert [acc, dec] == pytest.approx([1000.0, 500.0])  # mm/min²: /3600


def test_feed_limits_leave_rapid_blocks_alone_and_off_ends_them() -> None:
    assert _z(["#VECTOR LIMIT ON [VEL=1500 FEED]", "G00 Z0"])[0] == pytest.approx(333.333)
    assert _z(["#VECTOR LIMIT ON [VEL=1500 FEED]", "G01 Z0 F6000"])[0] == pytest.approx(25.0)
    assert _z(["#VECTOR LIMIT ON [VEL=1500 RAPID]", "G00 Z0"])[0] == pytest.approx(25.0)
    off = ["#VECTOR LIMIT ON [VEL=1500]", "#VECTOR LIMIT OFF [VEL]", "G01 Z0 F6000"]
    assert _z(off)[0] == pytest.approx(100.0)


@pytest.mark.parametrize(
    ("block", "says"),
    [
        ("#VECTOR LIMIT ON [JERK=5]", "not 'JERK=5'"),
        ("#VECTOR LIMIT ON [VEL=0]", "above 0"),
        ("#VECTOR LIMIT ON", "needs"),
        ("#VECTOR LIMIT OFF [VEL=5]", "without a value"),
    ],
)
def test_a_bad_vector_limit_is_refused(block: str, says: str) -> None:
    _sim, m, _cfg = make()
    outcome = m.submit(Mdi(block))
    assert isinstance(outcome, Invalid) and says in outcome.message
    assert outcome.column is not None and outcome.column >= 1
