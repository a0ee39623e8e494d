"""Step-response measurements against analytic responses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc_sim.measure import measure

TAU = 0.05  # s


def test_first_order_step_rise_and_settling_times() -> None:
    t = np.arange(0, 1.0, 1e-4)
    y = 2.0 * (1 - np.exp(-t / TAU))
    m = measure(t, y, band_pct=2.0)
    assert m.final == pytest.approx(2.0, abs=1e-6)
    assert m.rise_time_s == pytest.approx(TAU * math.log(9), abs=2e-4)  # 10 → 90 %
    assert m.settling_time_s == pytest.approx(TAU * math.log(50), abs=2e-4)  # into ±2 %
    assert m.overshoot_pct == pytest.approx(0.0, abs=1e-4)


@pytest.mark.parametrize("zeta", [0.2, 0.5, 0.7])
def test_second_order_overshoot(zeta: float) -> None:
    wn = 60.0
    wd = wn * math.sqrt(1 - zeta**2)
    t = np.arange(0, 2.0, 1e-5)
    phi = math.acos(zeta)
    y = 1 - np.exp(-zeta * wn * t) * np.sin(wd * t + phi) / math.sqrt(1 - zeta**2)
    m = measure(t, y)
    expected = 100 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))
    assert m.overshoot_pct == pytest.approx(expected, rel=1e-3)
    assert m.t_max_abs_s == pytest.approx(math.pi / wd, abs=1e-4)  # the peak time


def test_falling_step_settling_from_a_reference_and_absolute_band() -> None:
    t = np.arange(0, 1.0, 1e-3)
    y = np.where(t < 0.2, 5.0, 5.0 * np.exp(-(t - 0.2) / TAU))
    m = measure(t, y, band_abs=0.05, t_ref_s=0.2)
    assert m.overshoot_pct == pytest.approx(0.0, abs=1e-3)
    assert m.band == 0.05
    # |y - final| ≤ 0.05 once 5 e^{-x/τ} ≤ 0.05 + final (final ≈ 0)
    assert m.settling_time_s == pytest.approx(TAU * math.log(5.0 / 0.05), abs=1.5e-3)
    assert m.max_abs == 5.0 and m.minimum >= 0.0


def test_a_pulse_settles_into_a_band_relative_to_its_peak() -> None:
    t = np.arange(0, 2.0, 1e-3)
    y = np.where(t < 0.5, 100.0 * t / 0.5, 100.0 * np.exp(-(t - 0.5) / TAU))  # up, then decays
    m = measure(t, y, band_pct=2.0)
    assert m.band == pytest.approx(2.0, rel=1e-3)  # 2 % of the 100 peak
    assert m.settling_time_s == pytest.approx(0.5 + TAU * math.log(50), abs=1.5e-3)


def test_never_settling_and_flat_signals() -> None:
    t = np.arange(0, 1.0, 1e-3)
    ramp = measure(t, t * 10)
    assert ramp.settling_time_s is None
    flat = measure(t, np.full(t.size, 0.5))
    assert flat.rise_time_s is None and flat.overshoot_pct is None
    assert flat.settling_time_s == 0.0 and flat.mean == 0.5


def test_noise_alone_has_no_step_overshoot_or_rise() -> None:
    """White noise (σ = 0.01) around zero: no step to speak of, whatever the first sample."""
    rng = np.random.default_rng(7)
    t = np.arange(0, 1.0, 1e-3)
    sigma = 0.01
    y = rng.normal(0.0, sigma, t.size)
    y[0] = 3 * sigma  # an unlucky first sample: the 'step' would be 3 σ
    m = measure(t, y)
    assert not m.step_found
    assert m.overshoot_pct is None and m.rise_time_s is None
    assert m.noise == pytest.approx(sigma, rel=0.1)


def test_a_step_with_noise_is_measured_and_its_noise_estimated() -> None:
    """Second-order step (ζ = 0.5) plus white noise of 0.1 % of the step."""
    rng = np.random.default_rng(11)
    zeta, wn = 0.5, 60.0
    wd = wn * math.sqrt(1 - zeta**2)
    t = np.arange(0, 2.0, 1e-4)
    y = 1 - np.exp(-zeta * wn * t) * np.sin(wd * t + math.acos(zeta)) / math.sqrt(1 - zeta**2)
    sigma = 1e-3
    m = measure(t, y + rng.normal(0.0, sigma, t.size))
    assert m.step_found
    assert m.noise == pytest.approx(sigma, rel=0.1)
    expected = 100 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))  # 16.3 %
    assert m.overshoot_pct == pytest.approx(expected, abs=0.5)  # noise peaks: 4 σ ≈ 0.4 %
    assert m.rise_time_s is not None and m.rise_time_s > 0.01  # not one sample


def test_a_step_smaller_than_ten_noise_deviations_is_not_a_step() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(0, 1.0, 1e-3)
    noise = rng.normal(0.0, 0.01, t.size)
    assert not measure(t, np.where(t < 0.5, 0.0, 0.05) + noise).step_found  # 5 σ
    assert measure(t, np.where(t < 0.5, 0.0, 0.2) + noise).step_found  # 20 σ


def test_a_quantised_steady_signal_has_no_step() -> None:
    """A spindle's lag at steady speed: 480° (800 rpm at kv 10/s) read in encoder increments of
    360°/8192 = 0.0439°, now and then one increment off. Nearly every difference is zero, so
    the white-noise estimate is 0; a first sample one increment high must still not make a
    'step' of one increment with its hundreds of % overshoot."""
    rng = np.random.default_rng(5)
    inc = 360.0 / 8192
    t = np.arange(0, 1.0, 1e-3)
    y = 480.0 + inc * rng.choice([-1, 0, 0, 0, 0, 0, 0, 0, 0, 1], t.size)
    y[0] = 480.0 + inc
    m = measure(t, y)
    assert not m.step_found
    assert m.overshoot_pct is None and m.rise_time_s is None
    assert 0 < m.noise < inc  # the increment ripple, not zero


def test_a_quantised_step_of_many_increments_is_measured() -> None:
    """A first-order step of 100 increments read through the same quantisation: found, its
    10-90 % rise time τ·ln 9 within a sample, no overshoot."""
    inc = 360.0 / 8192
    t = np.arange(0, 1.0, 1e-3)
    y = inc * np.round(100 * (1 - np.exp(-t / TAU)))
    m = measure(t, y)
    assert m.step_found
    assert m.rise_time_s == pytest.approx(TAU * math.log(9), abs=2e-3)
    assert m.overshoot_pct == pytest.approx(0.0, abs=1e-9)


def test_a_known_final_value_is_the_one_overshoot_and_settling_refer_to() -> None:
    """A window cut before the response has settled: its end is not the final value, the
    commanded target is. A first-order step to 1 cut at 2τ: without `final` the end (≈ 0.85)
    would be taken as final and the response would "overshoot" it; with final = 1 there is no
    overshoot and it never settles into ±2 % inside the window (it needs τ·ln 50 ≈ 3.9τ)."""
    t = np.arange(0, 2 * TAU, 1e-4)
    y = 1 - np.exp(-t / TAU)
    guessed = measure(t, y)
    assert guessed.overshoot_pct is not None and guessed.overshoot_pct > 0
    m = measure(t, y, final=1.0)
    assert m.final == 1.0
    assert m.overshoot_pct == pytest.approx(0.0, abs=1e-9)
    assert m.settling_time_s is None
