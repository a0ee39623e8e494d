"""The service-axis view: expected lag v/kv, measured gain k = v/lag, limits with sources.

Numbers from the demo's lists (X: getriebe[0].kv 2000 = 20/s, hb.vb_max 166666 µm/s =
10 m/min, hb.a_max 1000 mm/s², tr 20 ms, vb_max 30 m/min) and the physics of a P loop:
lag = v/kv at constant speed, and with the drive's gain off by f, k = kv/f [004 §3.6.2].
"""

from __future__ import annotations

import numpy as np
import pytest

from nc_sim.commands import Accepted, HliWrite, JogStart
from nc_sim.machine.machine import Machine
from nc_sim.machine.service import axis_service, service_view
from nc_sim.sim import Simulation
from nc_sim.snapshot import AxisServiceSnapshot
from tests.nc_sim.sim_helpers import make, mdi, record

KV_X = 20.0  # getriebe[0].kv 2000 in 0.01/s


def _x(m: Machine, rec: np.ndarray) -> AxisServiceSnapshot:
    return axis_service(m, m.by_name["X"], rec)


def _run(sim: Simulation, seconds: float) -> np.ndarray:
    return record(sim, seconds)


def test_expected_lag_and_measured_gain_at_constant_feed() -> None:
    sim, m, _ = make()
    mdi(m, "G01 G91 X150 F1000")  # 16.67 mm/s, for 9 s
    rec = _run(sim, 2.0)
    x = _x(m, rec)
    v = 1000.0 / 60.0
    assert x.kv_per_s == pytest.approx(KV_X)
    assert x.v_cmd == pytest.approx(v)
    assert x.lag_expected == pytest.approx(v / KV_X)  # 0.833 mm
    assert x.gain.why_not is None
    assert x.gain.k_per_s == pytest.approx(KV_X, rel=0.01)


def test_a_wrong_drive_gain_shows_in_the_measured_gain() -> None:
    # the drive makes 22857 digits per 1 m/min where multi_gain assumes 10000: the loop gain
    # the axis shows is kv · 10000/22857 = 8.75 /s (the walkthrough's figure)
    sim, m, _ = make({"X": {"sim.drive_gain": 22857}})
    mdi(m, "G01 G91 X150 F1000")
    x = _x(m, _run(sim, 2.5))
    assert x.lag_expected == pytest.approx(1000.0 / 60.0 / KV_X)  # what the NC expects
    assert x.gain.k_per_s == pytest.approx(KV_X * 10000 / 22857, rel=0.01)


def test_no_gain_at_standstill_or_while_accelerating() -> None:
    sim, m, _ = make()
    rest = _run(sim, 0.6)
    x = _x(m, rest)
    assert x.gain.k_per_s is None and "standstill" in (x.gain.why_not or "")
    mdi(m, "G01 G91 X150 F1000")
    x = _x(
        m, np.concatenate([rest, _run(sim, 0.3)])
    )  # at speed after ~0.1 s, not yet settled for 8/kv = 0.4 s
    assert x.gain.k_per_s is None and "not constant" in (x.gain.why_not or "")


def test_the_lag_floor_hides_k_at_a_crawl() -> None:
    # 0.001 mm/min: lag 0.8 nm, below 100 encoder increments (and 1 nm)
    sim, m, _ = make()
    mdi(m, "G01 G91 X1 F0.001")
    x = _x(m, _run(sim, 1.0))
    assert x.gain.k_per_s is None and "below" in (x.gain.why_not or "")


def test_jog_limits_come_from_the_manual_mode_parameters() -> None:
    sim, m, _ = make()
    assert isinstance(m.submit(JogStart("X", 1)), Accepted)
    x = _x(m, _run(sim, 0.05))
    assert x.velocity.source == "handbetrieb.hb.vb_max"
    assert x.velocity.param_id == "P-AXIS-00213"
    assert x.velocity.value == pytest.approx(166666 * 60 / 1000)  # µm/s in mm/min
    assert x.velocity.override_pct is None
    assert x.acceleration.source == "handbetrieb.hb.a_max"
    assert x.acceleration.value == pytest.approx(1000.0)
    assert x.jerk is not None and x.jerk.value == pytest.approx(1000.0 / 0.020)


def test_a_path_axis_limit_is_its_share_of_the_path_feed_and_at_rest_its_vb_max() -> None:
    """G01 U30 W40 (G91 X30 Z-40 here): a 3-4-5 line at F 1000: X may carry 3/5 of the path
    speed (600 mm/min), Z 4/5 (800); at rest, before any F, the most a motion of X may
    have: getriebe[0].dynamik.vb_max, not a feed of 0."""
    sim, m, cfg = make()
    x = _x(m, _run(sim, 0.05))
    vb_max = cfg.axis("X").eng("getriebe.dynamik.vb_max") * 60.0  # mm/min
    assert x.velocity.source == "getriebe[0].dynamik.vb_max"
    assert x.velocity.value == pytest.approx(vb_max) and x.velocity.override_pct is None
    mdi(m, "G01 G91 X30 Z-40 F1000")
    rec = _run(sim, 0.1)
    views = {a.name: a for a in service_view(m, rec)}
    assert views["X"].velocity.value == pytest.approx(600.0)
    assert views["Z"].velocity.value == pytest.approx(800.0)
    assert views["X"].velocity.source == "F (path) × 0.6"


def test_override_and_reduced_speed_as_sources() -> None:
    sim, m, _ = make({"X": {"getriebe[0].vb_max_red": 5000}})  # µm/s: 5 mm/s = 300 mm/min
    assert isinstance(m.submit(HliWrite("override", 500)), Accepted)  # 50 %
    mdi(m, "G01 G91 X150 F1000")
    x = _x(m, _run(sim, 0.1))
    assert x.velocity.source == "F (path) × 1"  # the block moves X alone
    assert x.velocity.value == pytest.approx(500.0)  # F 1000 × 50 %
    assert x.velocity.override_pct == pytest.approx(50.0)
    # a_beschl 2000 mm/s² below a_max 5000 mm/s²
    assert x.acceleration.source == "getriebe[0].slope_profil.a_beschl"
    assert x.acceleration.param_id == "P-AXIS-00001"
    assert x.acceleration.value == pytest.approx(2000.0)
    sim2, mm, _ = make({"X": {"getriebe[0].vb_max_red": 5000}})
    assert isinstance(mm.submit(HliWrite("reduced_speed", 1, "X")), Accepted)
    assert isinstance(mm.submit(JogStart("X", 1)), Accepted)
    x2 = _x(mm, _run(sim2, 0.05))
    assert x2.velocity.kind == "reduced_speed"
    assert x2.velocity.source == "getriebe[0].vb_max_red"
    assert x2.velocity.param_id == "P-AXIS-00214"
    assert x2.velocity.value == pytest.approx(300.0)


def test_spindle_speed_limit_from_s_and_gear_record() -> None:
    sim, m, _ = make()
    mdi(m, "M3 S800")
    s = axis_service(m, m.by_name["S1"], _run(sim, 0.1))
    assert s.velocity.source == "S"
    assert s.velocity.unit == "rpm"
    assert s.velocity.value == pytest.approx(800.0)
    assert s.gear == 3  # M42, 700–3500 rpm
    assert s.kv_per_s == pytest.approx(10.0)
