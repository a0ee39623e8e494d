"""Seeded random spindle sessions on the demo lathe, checked against invariants."""

from __future__ import annotations

import random

import numpy as np
import pytest

from nc_sim.commands import HliWrite, Invalid, Mdi, Reset
from nc_sim.errors import Code, is_error
from nc_sim.kernel.curve import curve_accel
from nc_sim.snapshot import AxisState
from tests.nc_sim.sim_helpers import L, make

S = "S1"
# the job errors a random operator may provoke on the demo lathe, all documented
EXPECTED_ERRORS = {
    Code.GEAR_NO_RANGE,  # S above 7000 rpm
    Code.GEAR_WRONG_STAGE,  # M4x with S outside its range
}
POLY = {  # polynomial curve with a_konst equal to the demo's a_beschl
    "typ": 2,
    "n_grenz": 12000000,
    "a_konst": 3000,
    "b1": -0.1,
    "b2": 1e-6,
    "b3": -1e-11,
    "a_min": 800,
}


def _command(rng: random.Random) -> str:
    rpm = rng.choice([rng.uniform(50, 7000), rng.uniform(0, 9000), 0.0])
    angle = rng.uniform(0, 360)
    options = [
        f"M3 S{rpm:.1f}",
        f"M4 S{rpm:.1f}",
        "M5",
        f"M19 S.POS={angle:.3f}",
        f"M19 S.POS={angle:.3f} {rng.choice(['M3', 'M4'])}",
        f"M{rng.randint(40, 45)} S{rpm:.1f}",
        f"S{rpm:.1f}",
        "S[G167]",
        f"S[REV{rpm:.1f}]",
    ]
    return rng.choice(options)


def _session(seed: int) -> None:
    rng = random.Random(seed)
    curve = seed % 2 == 1
    params: dict[str, object] = {}
    if curve:
        params = {
            f"getriebe[{g}].beschl_kennlinie.{k}": v for g in range(6) for k, v in POLY.items()
        }
    sim, m, cfg = make({S: params})
    s = m.axis(S)
    a_cap = cfg.axis(S).eng("getriebe.slope_profil.a_beschl")
    window = cfg.axis(S).eng("kenngr.exact_stop_window")
    vb_max = {g: cfg.axis(S).eng("getriebe.dynamik.vb_max", g) for g in range(1, 7)}
    recs: list[np.ndarray] = []
    for _ in range(12):
        if rng.random() < 0.25:
            m.submit(HliWrite("override", rng.randint(0, 1200), S))
        text = _command(rng)
        # a random block parses; it may be refused while starting (e.g. a wrong gear stage)
        assert not isinstance(m.submit(Mdi(text)), Invalid), text
        rec = sim.new_record(round(rng.uniform(0.3, 4.0) / 0.001))
        sim.run(rec.shape[0], rec)
        recs.append(rec[:, s.slot])
    m.submit(HliWrite("override", 1000, S))
    m.submit(Reset())
    rec = sim.new_record(12000)
    sim.run(rec.shape[0], rec)
    recs.append(rec[:, s.slot])
    r = np.concatenate(recs)

    assert not np.isnan(r).any()
    v, a, gear = r[:, L.R_V_CMD], r[:, L.R_A_CMD], r[:, L.R_GEAR].astype(int)
    limit = np.array([vb_max[g] for g in gear])
    assert np.all(np.abs(v) <= limit + 1e-6), "speed above the gear's vb_max"
    assert np.all(np.abs(a) <= a_cap + 1e-6), "acceleration above a_beschl/a_brems"
    if curve:
        rotating = np.isin(r[:, L.R_STATE], (AxisState.ENDLESS, AxisState.STOPPING))
        both = rotating[1:] & rotating[:-1]
        n_limit = POLY["n_grenz"] * 1e-3  # 0.001 °/s -> °/s
        ak, b1, b2, b3, a_min = (POLY[k] for k in ("a_konst", "b1", "b2", "b3", "a_min"))
        allowed = np.array(
            [curve_accel(2, x, n_limit, ak, b1, b2, b3, a_min, 0.0, 0.0, 0.0) for x in v[:-1]]
        )
        assert np.all(np.abs(a[1:][both]) <= allowed[both] + 1e-6), "above the curve"
    errors = {e.code for e in m.events if is_error(e.code)}
    assert errors <= EXPECTED_ERRORS, errors
    # after reset every command has ended: standstill, no block left, no sequence running
    assert s.state is AxisState.STANDSTILL and s.sequence is None and not m.queued_blocks
    assert abs(v[-1]) == 0.0
    # every M19 that reported its position stood inside the window there (row = cycle - 21)
    for ev in m.events:
        if ev.code == Code.EV_IN_POSITION and ev.m == 19:
            assert ev.value is not None  # the position it reported, °
            p = r[ev.cycle - 21, L.R_P_ACT]
            assert abs((p - ev.value + 180) % 360 - 180) <= window


@pytest.mark.parametrize("seed", range(40))
def test_random_spindle_session_keeps_the_invariants(seed: int) -> None:
    _session(seed)
