"""Measurements on one channel of a record, as a commissioning engineer reads a step response.

All work on samples `y` at times `t` (s) of a window. The step goes from the initial value
(the first sample) to the final value (the mean of the last 10 % of the window, at least one
sample). A signal that returns to where it started (a pulse, the lag of a finished move) has no
step: no rise time or overshoot, and its settling band is relative to its largest excursion.
Neither has a signal whose step does not stand out of its noise: NOISE_FACTOR standard
deviations of the white noise, and RIPPLE_FACTOR times the ripple left at the end of the
window (half its peak-to-peak). The second catches quantised signals: a lag that sits on one
encoder increment and now and then reads the next one has differences that are almost all
zero, so the white-noise estimate is 0, yet a first sample one increment off would read as a
"step" of one increment with hundreds of % overshoot. Crossing times are interpolated
linearly between samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FINAL_SHARE = 0.1  # the final value is the mean of this last share of the window
PULSE_SHARE = 0.05  # a step smaller than this share of the excursion counts as none
NOISE_FACTOR = 10.0  # a step must exceed this many noise standard deviations
RIPPLE_FACTOR = 3.0  # ... and this many times the ripple (half peak-to-peak) at its end


@dataclass(frozen=True)
class Measurements:
    """Step-response figures of one channel in one window; None where undefined."""

    samples: int
    initial: float
    final: float  # steady mean: mean over the last 10 % of the window
    minimum: float
    maximum: float
    max_abs: float  # e.g. the maximum lag
    t_max_abs_s: float
    mean: float
    overshoot_pct: float | None  # beyond the final value, in % of the step
    rise_time_s: float | None  # 10 % → 90 % of the step
    settling_time_s: float | None  # from `t_ref_s` until y stays inside final ± band
    band: float  # absolute half-width of the settling band used
    noise: float  # noise standard deviation: white noise, or the settled end where larger
    step_found: bool  # a step stands out of the noise and does not come back


def noise_std(y: np.ndarray) -> float:
    """Standard deviation of white noise on y, from the differences of neighbouring samples
    (median absolute deviation): steps, ramps and slow responses hardly change it."""
    if y.size < 3:
        return 0.0
    d = np.diff(y)
    mad = float(np.median(np.abs(d - np.median(d))))
    return mad / 0.6745 / math.sqrt(2.0)  # MAD of a normal = 0.6745 σ; a difference: √2 σ


def _crossing(t: np.ndarray, y: np.ndarray, level: float, rising: bool) -> float | None:
    """First time y reaches `level` in the given direction (linear interpolation)."""
    hit = np.flatnonzero(y >= level) if rising else np.flatnonzero(y <= level)
    if hit.size == 0:
        return None
    i = int(hit[0])
    if i == 0:
        return float(t[0])
    y0, y1 = float(y[i - 1]), float(y[i])
    frac = (level - y0) / (y1 - y0) if y1 != y0 else 1.0
    return float(t[i - 1] + frac * (t[i] - t[i - 1]))


def measure(
    t: np.ndarray,
    y: np.ndarray,
    band_pct: float = 2.0,
    band_abs: float | None = None,
    t_ref_s: float | None = None,
    final: float | None = None,
) -> Measurements:
    """Measurements of y(t). The settling band is `band_abs` when given, else `band_pct` % of
    the step (of the largest excursion from the final value when there is no step); settling
    is timed from `t_ref_s` (default: the window start, e.g. pass the trigger time). `final`
    is the value y settles to when it is known (a commanded target), else the window's end
    tells it."""
    if t.size == 0 or t.size != y.size:
        raise ValueError("measure: t and y need the same non-zero length")
    n_final = max(1, round(y.size * FINAL_SHARE))
    initial = float(y[0])
    final = float(np.mean(y[-n_final:])) if final is None else final
    step = final - initial
    end = y[-n_final:]
    white = noise_std(y)
    ripple = 0.5 * float(np.max(end) - np.min(end))
    noise = max(white, float(np.std(end)))
    if abs(step) < PULSE_SHARE * float(np.max(np.abs(y - initial))):
        step = 0.0  # it came back (a pulse, a move's lag): no step to rise or overshoot
    if abs(step) <= NOISE_FACTOR * white or abs(step) <= RIPPLE_FACTOR * ripple:
        step = 0.0  # not told from the noise
    i_abs = int(np.argmax(np.abs(y)))
    # without a step (a pulse, a speed back to zero) the band is relative to the excursion
    scale = abs(step) if step != 0 else float(np.max(np.abs(y - final)))
    band = band_abs if band_abs is not None else scale * band_pct / 100.0
    overshoot = rise = None
    if step != 0:
        rising = step > 0
        peak = float(np.max(y)) if rising else float(np.min(y))
        overshoot = max(0.0, (peak - final) / step * 100.0)
        t10 = _crossing(t, y, initial + 0.1 * step, rising)
        t90 = _crossing(t, y, initial + 0.9 * step, rising)
        if t10 is not None and t90 is not None:
            rise = t90 - t10
    t_ref = float(t[0]) if t_ref_s is None else t_ref_s
    outside = np.flatnonzero(np.abs(y - final) > band)
    settling: float | None
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] == y.size - 1:
        settling = None  # never settles inside the window
    else:
        settling = max(0.0, float(t[outside[-1] + 1]) - t_ref)
    return Measurements(
        samples=int(y.size),
        initial=initial,
        final=final,
        minimum=float(np.min(y)),
        maximum=float(np.max(y)),
        max_abs=float(abs(y[i_abs])),
        t_max_abs_s=float(t[i_abs]),
        mean=float(np.mean(y)),
        overshoot_pct=overshoot,
        rise_time_s=rise,
        settling_time_s=settling,
        band=float(band),
        noise=noise,
        step_found=step != 0,
    )
