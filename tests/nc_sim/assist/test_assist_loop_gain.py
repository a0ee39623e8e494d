"""The position loop gain assistant on the demo lathe in simulated time [004 §3.6].

The numbers come from the loop's physics (DOMAIN.md §2): a P position controller (kv) on a
drive whose velocity loop is a first-order lag with time constant T (`sim.drive_t`) gives the
closed loop T·s² + s + kv = 0: aperiodic for kv ≤ 1/(4T), else damped with
ζ = 1/(2·√(kv·T)) and a step overshoot of exp(−π·ζ/√(1 − ζ²)). At constant speed the lag
settles to v/kv (no feedforward).

The test plant is the IDEAL one (`sim.plant`) with T = 20 ms, so kv = 12.5/s is critical
damping and the NC's 1 ms cycle (one cycle of dead time, 5 % of T) shifts the figures only a
little; its G00 is made nearly a jump (acceleration 1000 m/s², 1 ms ramp), so the measured
step is the loop's step response.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from nc_sim.assist.loop_gain import loop_gain
from nc_sim.assist.result import ExperimentError, Result
from nc_sim.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.params import Scope

T_S = 0.020  # the plant's drive time constant
STEP_MM = 0.2  # 20 exact-stop windows of 10 µm (the demo's X)
WINDOW_MM = 0.01
FEED = 1000.0  # mm/min
INC_MM = 1e-4  # the demo X's encoder increment


def plant(**x: Any) -> MachineConfig:
    cfg = demo_machine()
    values = {
        "sim.plant": "IDEAL",  # the first-order drive the theory describes
        "sim.drive_t": round(T_S * 1e6),
        "getriebe[0].dynamik.a_max": 1_000_000,
        "getriebe[0].slope_profil.a_grenz": 1_000_000,
        "getriebe[0].slope_profil.tr_grenz": 1000,
        **x,
    }
    apply_overrides(cfg, Scope.AXIS, "X", values)
    return cfg


def overshoot_theory_pct(kv: float) -> float:
    """Second-order loop: 0 when aperiodic (kv ≤ 1/(4T))."""
    zeta = 1.0 / (2.0 * math.sqrt(kv * T_S))
    return 0.0 if zeta >= 1 else 100.0 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))


def settling_theory_s(kv: float) -> float:
    """Aperiodic loop (kv < 1/(4T)): poles p1, p2; the error of a unit step is
    (p2·e^(−p1·t) − p1·e^(−p2·t))/(p2 − p1); the time it falls to window/step (bisection)."""
    root = math.sqrt(1 - 4 * kv * T_S)
    p1, p2 = (1 - root) / (2 * T_S), (1 + root) / (2 * T_S)

    def err(t: float) -> float:
        return (p2 * math.exp(-p1 * t) - p1 * math.exp(-p2 * t)) / (p2 - p1)

    lo, hi = 0.0, 10.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if err(mid) > WINDOW_MM / STEP_MM else (lo, mid)
    return lo


def fig(r: Result, name: str, kv: float) -> float:
    return r.figure(f"{name}@{kv:g}")


def test_the_ramps_steady_lag_is_v_over_kv() -> None:
    """The steady lag of a type-1 loop at constant speed is exactly v/kv; the encoder
    quantises the actual by one increment (0.1 µm), so the mean is within that of it."""
    kvs = [5.0, 20.0, 40.0]
    r = loop_gain(plant(), "X", kvs, feed_mm_min=FEED)
    v = FEED / 60.0
    for kv in kvs:
        assert fig(r, "lag", kv) == pytest.approx(v / kv, abs=INC_MM)
        assert fig(r, "lag_expected", kv) == pytest.approx(v / kv)


def test_overshoot_grows_with_kv_as_the_second_order_loop_has_it() -> None:
    """Aperiodic up to critical damping kv = 1/(4T) = 12.5/s, then exp(−πζ/√(1−ζ²)):
    1.7 % at 20/s, 7.0 % at 30/s, 12.0 % at 40/s. One cycle of dead time adds a little;
    one encoder increment is 0.05 % of the step: within 1 percentage point."""
    kvs = [5.0, 10.0, 1 / (4 * T_S), 20.0, 30.0, 40.0]
    r = loop_gain(plant(), "X", kvs, feed_mm_min=FEED)
    measured = [fig(r, "overshoot_pct", kv) for kv in kvs]
    for kv, os in zip(kvs, measured, strict=True):
        assert os == pytest.approx(overshoot_theory_pct(kv), abs=1.0), kv
    for kv in kvs[:3]:  # aperiodic: not past the target by more than an increment
        assert fig(r, "overshoot", kv) <= INC_MM + 1e-12
    assert measured[3] < measured[4] < measured[5]


def test_settling_follows_the_loops_time_constant() -> None:
    """Below critical damping the step settles as the two real poles say: about
    ln(step/window)·(1/kv + T) for small kv. Timed from the end of a 2-3 ms command: within
    5 % and 5 ms."""
    kvs = [2.0, 5.0, 10.0]
    r = loop_gain(plant(), "X", kvs, feed_mm_min=FEED)
    for kv in kvs:
        expected = settling_theory_s(kv)
        assert fig(r, "settling_ms", kv) / 1000 == pytest.approx(expected, rel=0.05, abs=0.005)
    # and the ordering an engineer reads off: a higher kv settles sooner (aperiodic range)
    assert fig(r, "settling_ms", 2.0) > fig(r, "settling_ms", 5.0) > fig(r, "settling_ms", 10.0)


def test_the_highest_kv_meeting_the_target_is_proposed() -> None:
    """Overshoot ≤ 5 %: the second-order loop reaches 5 % at ζ = 0.690, kv = 1/(4Tζ²) =
    26.3/s. Of 10, 15, 20, 30, 40 the highest meeting it is 20, and 30 misses it."""
    zeta_5 = -math.log(0.05) / math.sqrt(math.pi**2 + math.log(0.05) ** 2)
    kv_limit = 1 / (4 * T_S * zeta_5**2)
    assert kv_limit == pytest.approx(26.3, abs=0.1)
    kvs = [10.0, 15.0, 20.0, 30.0, 40.0]
    r = loop_gain(plant(**{"getriebe[0].kv": 1000}), "X", kvs, 5.0, 300.0, feed_mm_min=FEED)
    assert r.ok
    chosen = r.figure("kv_new")
    assert chosen == 20.0 < kv_limit < 30.0
    assert fig(r, "overshoot_pct", 20.0) <= 5.0 < fig(r, "overshoot_pct", 30.0)
    (change,) = r.changes
    assert (change.parameter, change.before, change.after) == ("getriebe[0].kv", 1000, 2000)


def test_a_settling_target_bounds_kv_from_below() -> None:
    """Settling ≤ 300 ms: at kv = 5/s the theory gives 0.53 s (too slow), at 10/s 0.22 s;
    with no overshoot allowed beyond critical damping (0.2 %), 10 or 12.5 are the candidates."""
    assert settling_theory_s(5.0) > 0.3 > settling_theory_s(10.0)
    kvs = [5.0, 10.0, 12.5, 30.0]
    r = loop_gain(plant(), "X", kvs, 0.2, 300.0, feed_mm_min=FEED)
    assert r.figure("kv_new") == 12.5


def test_no_kv_meeting_the_target_says_so_and_proposes_nothing() -> None:
    r = loop_gain(plant(), "X", [30.0, 40.0], 5.0, 200.0, feed_mm_min=FEED)
    assert not r.ok and not r.changes
    assert any("no kv in the sweep meets the target" in n for n in r.notes)
    with pytest.raises(KeyError):
        r.figure("kv_new")


def test_the_default_sweep_is_around_the_axis_kv_and_proposes_within_it() -> None:
    """Demo X: kv 20/s on a 2 ms drive (critical damping at 125/s): the whole default sweep
    (0.5× to 3×) is aperiodic, so its top meets the target and the note says the limit is
    above the sweep."""
    r = loop_gain(demo_machine(), "X")
    kvs = [float(k) for k in str(r.inputs["kvs"]).split(",")]
    assert kvs[0] == 10.0 and kvs[-1] == 60.0 and 20.0 in kvs
    assert r.figure("kv_new") == 60.0
    assert any("limit lies above" in n for n in r.notes)
    names = {s.name for s in r.series}
    assert {"step@20", "ramp_lag@20", "overshoot_vs_kv", "settling_vs_kv"} <= names


def test_spindles_and_bad_inputs_are_refused() -> None:
    cfg = demo_machine()
    with pytest.raises(ExperimentError, match="spindle"):
        loop_gain(cfg, "S1")
    with pytest.raises(ExperimentError, match="kv values must be > 0"):
        loop_gain(cfg, "X", [0.0, 10.0])
    with pytest.raises(ExperimentError, match="Q"):
        loop_gain(cfg, "Q")
