"""The modulo range of a spindle [000 §3.2.2]: "For modulo calculation for rotary axes, an
upper modulo limit (e.g. 360°)" P-AXIS-00126 moduloo and "a lower modulo limit (e.g. 0°)"
P-AXIS-00127 modulou. The position is shown within modulou ≤ angle < moduloo, however many
turns the spindle made; a range that is not one revolution is refused with the list."""

from __future__ import annotations

import pytest

from nc_sim.config import apply_overrides, demo_machine
from nc_sim.params import Scope
from nc_sim.params.listfile import ParamListError
from nc_sim.snapshot import AxisSnapshot
from tests.nc_sim.sim_helpers import make, mdi, record

GEARS = range(6)  # the demo S1 has six gear records: the range applies to each


def _s1(lo_deg: float, hi_deg: float, blocks: list[str], seconds: float) -> AxisSnapshot:
    values = {f"getriebe[{g}].modulou": round(lo_deg * 1e4) for g in GEARS}
    values |= {f"getriebe[{g}].moduloo": round(hi_deg * 1e4) for g in GEARS}
    sim, m, _cfg = make({"S1": values})
    for b in blocks:
        mdi(m, b)
        record(sim, seconds)
    return next(a for a in m.snapshot().axes if a.name == "S1")


@pytest.mark.parametrize(("lo", "hi"), [(0.0, 360.0), (-180.0, 180.0)])
def test_a_turning_spindle_is_shown_within_its_range(lo: float, hi: float) -> None:
    """M3 S600 for 3 s: more than ten turns; the angle shown stays in the range."""
    s1 = _s1(lo, hi, ["M3 S600"], 3.0)
    assert s1.vel_act > 400.0  # rpm, still running up its curve
    for p in (s1.pos_cmd, s1.pos_act):
        assert lo <= p < hi


@pytest.mark.parametrize(("lo", "hi", "shown"), [(0.0, 360.0, 270.0), (-180.0, 180.0, -90.0)])
def test_an_oriented_spindle_shows_its_angle_in_the_range(
    lo: float, hi: float, shown: float
) -> None:
    """M19 S.POS=270 after a few turns: 270° in 0 … 360°, the same angle as -90° in -180 …
    180°."""
    s1 = _s1(lo, hi, ["M3 S300", "M19 S.POS=270"], 3.0)
    assert s1.state == "STANDSTILL"
    assert s1.pos_cmd == pytest.approx(shown, abs=1e-6)
    assert s1.pos_act == pytest.approx(shown, abs=0.1)  # within the in-position window


def test_a_range_that_is_not_one_revolution_is_refused_naming_it() -> None:
    cfg = demo_machine()
    with pytest.raises(ParamListError) as e:
        apply_overrides(cfg, Scope.AXIS, "S1", {"getriebe[0].moduloo": 1800000})
    assert "getriebe[0].moduloo" in str(e.value) and "360°" in str(e.value)
    assert cfg.axis("S1").values.get("getriebe[0].moduloo", 3600000) == 3600000  # kept
