"""The commissioning calculators against the manuals' worked examples [004 §3.4, §3.6.1,
000 §2.2.4, §2.8.4, DOMAIN §4.1, §7] and the curve fit against a measured run-up."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from nc_sim.accel_curve import curve_accel
from nc_sim.assist.calculators import multi_gain, resolution, speed_scaling
from nc_sim.assist.curve_fit import curve_fit
from nc_sim.assist.result import Result
from nc_sim.assist.run_up import curve_run_up
from nc_sim.config import apply_overrides, demo_machine
from nc_sim.errors import NcUsageError
from nc_sim.params import Scope

POLY = {
    "n_grenz": 12000000,
    "a_konst": 16000,
    "b1": -0.88888888,
    "b2": 2.08333333e-5,
    "b3": -1.92901234e-10,
}
MANUAL_POINTS = [(12000.0, 16000.0), (24000.0, 8000.0), (36000.0, 4000.0), (48000.0, 2000.0)]


def pair(r: Result, z: str, n: str) -> tuple[int, int]:
    after = {c.parameter.split(".", 1)[-1]: c.after for c in r.changes}
    zi, ni = after[z], after[n]
    assert isinstance(zi, int) and isinstance(ni, int)  # list fractions are whole numbers
    return zi, ni


@pytest.mark.parametrize(
    ("gear_ratio", "expected"),
    [
        (1.0, (4096, 50000)),  # example 1: 4096 increments per 5 mm
        (10.0, (4096, 5000)),  # example 2: with i = 10
    ],
)
def test_resolution_linear(gear_ratio: float, expected: tuple[int, int]) -> None:
    r = resolution(4096, pitch_mm=5, gear_ratio=gear_ratio)
    assert pair(r, "wegaufz", "wegaufn") == expected


def test_resolution_rotary_sercos() -> None:
    r = resolution(65536, rotary=True, target="C")
    assert pair(r, "wegaufz", "wegaufn") == (65536, 3600000)
    assert r.changes[0].parameter == "getriebe[0].wegaufz" and r.changes[0].target == "C"


def test_resolution_needs_pitch_or_rotary() -> None:
    with pytest.raises(NcUsageError):
        resolution(4096)
    with pytest.raises(NcUsageError, match="positive"):
        resolution(4096, pitch_mm=-5)


def test_multi_gain_terminal_spindle() -> None:  # 004 §3.6.1.2: 10.1134
    r = multi_gain(full_scale_digits=32767, full_scale_rpm=9000, target="S1")
    assert r.figure("f") == pytest.approx(3.6408, abs=1e-4)
    assert r.figure("n_motor_rpm") == pytest.approx(2.7778, abs=1e-4)
    assert r.figure("multi_gain") == pytest.approx(10.1134, rel=2e-5)
    z, n = pair(r, "multi_gain_z", "multi_gain_n")
    assert Fraction(z, n) == Fraction(32767, 9000) * Fraction(1000, 360)


def test_multi_gain_terminal_spindle_with_gear() -> None:  # 004 §3.6.1.3: i = 5 -> 50.5668
    r = multi_gain(full_scale_digits=32767, full_scale_rpm=9000, gear_ratio=5)
    assert r.figure("n_motor_rpm") == pytest.approx(13.8889, abs=1e-4)
    assert r.figure("multi_gain") == pytest.approx(50.5668, rel=2e-5)


def test_multi_gain_sercos_translatory() -> None:  # 004 §3.6.1.4: 10000/1
    r = multi_gain(speed_weighting_m_per_min=1e-4, pitch_mm=1)
    assert pair(r, "multi_gain_z", "multi_gain_n") == (10000, 1)


def test_multi_gain_sercos_rotary() -> None:  # 004 §3.6.1.5: 10000000/360
    r = multi_gain(speed_weighting_rpm=1e-4)
    assert pair(r, "multi_gain_z", "multi_gain_n") == (10000000, 360)


def test_multi_gain_lightbus() -> None:  # 004 §3.6.1.1: 27962.02 (5 mm pitch)
    r = multi_gain(digits_per_rpm=Fraction(1048576 * 32, 4000 * 60), pitch_mm=5)
    assert r.figure("f") == pytest.approx(139.8101, abs=1e-4)
    assert r.figure("n_motor_rpm") == 200
    assert r.figure("multi_gain") == pytest.approx(27962.02, abs=0.01)
    # the alternative formula of the manual: 10^7 / I_rev · wegaufz / wegaufn · f
    alt = Fraction(10**7, 65536) * Fraction(65536, 50000) * Fraction(1048576 * 32, 4000 * 60)
    z, n = pair(r, "multi_gain_z", "multi_gain_n")
    assert Fraction(z, n) == alt


def test_multi_gain_needs_exactly_one_scaling() -> None:
    with pytest.raises(NcUsageError, match="exactly one"):
        multi_gain(speed_weighting_rpm=1e-4, digits_per_rpm=3)
    with pytest.raises(NcUsageError, match="exactly one"):
        multi_gain()


def test_speed_scaling_sensorless_spindle() -> None:  # 000 §2.2.4.1
    r = speed_scaling(32767, 3000)
    assert pair(r, "v_reso_num", "v_reso_denom") == (32767, 1080000000)
    assert {c.parameter: c.after for c in r.changes}["antr.v_time_base"] == 0


def test_speed_scaling_with_speed_feedback() -> None:  # 000 §2.2.4.2: 1 increment = 1 rpm
    assert pair(speed_scaling(1, 1), "v_reso_num", "v_reso_denom") == (1, 360000)


def test_speed_scaling_per_second_and_per_cycle() -> None:  # the same speed, other time bases
    assert pair(speed_scaling(32767, 3000, time_base=1), "v_reso_num", "v_reso_denom") == (
        32767,
        18000000,
    )
    r = speed_scaling(32767, 3000, time_base=2, cycle_ms=1)
    assert pair(r, "v_reso_num", "v_reso_denom") == (32767, 18000)  # 18° per 1 ms cycle
    with pytest.raises(NcUsageError, match="cycle"):
        speed_scaling(32767, 3000, time_base=2)


def test_polynomial_from_the_manuals_four_points() -> None:  # 000 §2.8.4
    r = curve_fit(2, MANUAL_POINTS)
    assert r.figure("n_limit") == 12000 and r.figure("a_konst") == pytest.approx(16000)
    assert r.figure("b3") == pytest.approx(-1.92901234e-10, rel=1e-7)
    assert r.figure("b2") == pytest.approx(2.08333333e-5, rel=1e-7)
    assert r.figure("b1") == pytest.approx(-0.88888888, rel=1e-7)
    after = {c.parameter: c.after for c in r.changes}
    assert after["getriebe[0].beschl_kennlinie.n_grenz"] == 12000000  # 0.001 °/s as in the list
    assert after["getriebe[0].beschl_kennlinie.typ"] == 2


def test_hyperbola_from_the_manuals_three_points() -> None:  # DOMAIN §4.1 (b3 positive)
    r = curve_fit(1, MANUAL_POINTS[:3])
    assert r.figure("b1") == pytest.approx(2.285714e4, rel=1e-6)
    assert r.figure("b2") == pytest.approx(4.166666e-1, rel=1e-6)
    assert r.figure("b3") == pytest.approx(2.857142e-2, rel=1e-6)


def test_asynchronous_from_points_of_the_manuals_curve() -> None:  # 000 §2.8.4.2
    def a(n: float) -> float:  # a_max 16000, N1 10000, N2 20000, written out
        return 16000.0 if n <= 10000 else 16000 * 10000 / n * (1 if n <= 20000 else 20000 / n)

    r = curve_fit(3, [(n, a(n)) for n in (5000.0, 15000.0, 25000.0)], a_min=4000)
    assert (r.figure("a_max"), r.figure("n1"), r.figure("n2")) == pytest.approx(
        (16000, 10000, 20000)
    )


@pytest.mark.parametrize("typ", [1, 2])
def test_least_squares_finds_the_limit_speed(typ: int) -> None:
    b = {
        1: (2.285714e4, 4.166666e-1, 2.857142e-2),
        2: (-0.88888888, 2.08333333e-5, -1.92901234e-10),
    }[typ]
    speeds = np.linspace(1000.0, 40000.0, 50)
    pts = [(n, curve_accel(typ, n, 12000, 16000, *b, 2000, 0, 0, 0)) for n in speeds]
    r = curve_fit(typ, pts, a_min=2000)
    assert r.figure("max_error") < 1e-4
    assert r.figure("a_konst") == pytest.approx(16000, rel=1e-4)


def test_curve_fit_refuses_too_few_points() -> None:
    with pytest.raises(NcUsageError, match="at least 4"):
        curve_fit(2, MANUAL_POINTS[:3])


def test_run_up_recovers_the_plants_curve_within_2_percent() -> None:
    """S1 in gear 6 with the manual's polynomial: the fit of the measured run-up matches
    the plant's curve everywhere in the measured range within 2 %."""
    cfg = demo_machine()
    values: dict[str, float | int] = {
        f"getriebe[5].beschl_kennlinie.{k}": v for k, v in POLY.items()
    }
    values |= {"getriebe[5].beschl_kennlinie.typ": 2, "getriebe[5].beschl_kennlinie.a_min": 2000}
    apply_overrides(cfg, Scope.AXIS, "S1", values)
    r = curve_run_up(cfg, "S1", 6, 2)
    assert r.figure("run_up_s") > 1.0
    fit = {f.name: f.value for f in r.figures}
    measured_n = r.series[0].x
    assert min(measured_n) < 8000 and max(measured_n) > 40000  # the range covers the curve
    b = (POLY["b1"], POLY["b2"], POLY["b3"])
    for n in np.linspace(min(measured_n), max(measured_n), 400):
        plant = curve_accel(2, n, 12000, 16000, *b, 2000, 0, 0, 0)
        fitted = curve_accel(
            2, n, fit["n_limit"], fit["a_konst"], fit["b1"], fit["b2"], fit["b3"], 2000, 0, 0, 0
        )
        assert fitted == pytest.approx(plant, rel=0.02), n
    changes = {c.parameter: c for c in r.changes}
    assert changes["getriebe[5].beschl_kennlinie.typ"].before == 2
    assert changes["getriebe[5].beschl_kennlinie.n_grenz"].after == pytest.approx(
        12000000, rel=0.03
    )


def test_a_fitted_hyperbola_has_no_step_at_its_limit_speed() -> None:
    """Least squares through the manual's four points: below n_limit the curve is a_konst,
    above it the hyperbola; the two meet (a step there would sit between the points unseen)."""
    r = curve_fit(1, MANUAL_POINTS)
    f = {x.name: x.value for x in r.figures}
    law = (1, f["n_limit"], f["a_konst"], f["b1"], f["b2"], f["b3"], 0, 0, 0, 0)
    below = curve_accel(law[0], f["n_limit"] * 0.999, *law[1:])
    above = curve_accel(law[0], f["n_limit"] * 1.001, *law[1:])
    assert below == pytest.approx(above, rel=0.01)
    assert r.figure("max_error") < 0.05  # and it still passes near the points
