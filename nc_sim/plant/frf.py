"""Frequency responses from measured signals: excitations, the H1 estimate and what an
engineer reads off a Bode plot (margins, bandwidth, resonances).

H1 = Pxy / Pxx (Welch: Hann window, half overlap) with the coherence Pxy² / (Pxx·Pyy): the
estimate is unbiased by noise on the output, and the coherence says where it can be trusted.
A PRBS excitation is a maximum-length sequence, one segment per period, so the averages
span whole periods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

MAX_RESONANCES = 3  # of each kind, the most prominent


def prbs(order: int, amplitude: float, periods: int, hold: int = 1) -> np.ndarray:
    """`periods` periods of a ±amplitude maximum-length sequence of 2**order - 1 bits, each
    bit held `hold` samples (a lower clock rate puts more power at low frequencies)."""
    bits = signal.max_len_seq(order)[0].astype(np.float64)
    one = np.repeat(amplitude * (2.0 * bits - 1.0), hold)
    return np.tile(one, periods)


def chirp(f0_hz: float, f1_hz: float, seconds: float, fs_hz: float, amplitude: float) -> np.ndarray:
    """A logarithmic sweep from f0 to f1 over `seconds`, sampled at fs."""
    t = np.arange(round(seconds * fs_hz)) / fs_hz
    sweep: np.ndarray = signal.chirp(t, f0_hz, seconds, f1_hz, method="logarithmic")
    return amplitude * sweep


@dataclass(frozen=True)
class Frf:
    """A measured frequency response: frequencies (Hz), complex response, coherence."""

    f_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray

    @property
    def magnitude_db(self) -> np.ndarray:
        return np.asarray(20.0 * np.log10(np.abs(self.h)))

    @property
    def phase_deg(self) -> np.ndarray:
        """Phase unwrapped from the lowest frequency on (°)."""
        return np.asarray(np.degrees(np.unwrap(np.angle(self.h))))

    def band(self, lo_hz: float, hi_hz: float) -> Frf:
        """The part between lo and hi (inclusive)."""
        keep = (self.f_hz >= lo_hz) & (self.f_hz <= hi_hz)
        return Frf(self.f_hz[keep], self.h[keep], self.coherence[keep])


def h1(x: np.ndarray, y: np.ndarray, fs_hz: float, nperseg: int) -> Frf:
    """H1 estimate of the response from x to y (Welch, Hann window, half overlap); the
    zero frequency is left out."""
    f, pxy = signal.csd(x, y, fs=fs_hz, window="hann", nperseg=nperseg, noverlap=nperseg // 2)
    _, pxx = signal.welch(x, fs=fs_hz, window="hann", nperseg=nperseg, noverlap=nperseg // 2)
    _, pyy = signal.welch(y, fs=fs_hz, window="hann", nperseg=nperseg, noverlap=nperseg // 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = pxy / pxx
        coh = np.abs(pxy) ** 2 / (pxx * pyy)
    keep = (f > 0.0) & (pxx > 0.0)
    return Frf(f[keep], h[keep], np.nan_to_num(coh[keep]))


def _crossing(f: np.ndarray, v: np.ndarray, level: float) -> int | None:
    """Index i of the first downward crossing of `level` between i and i + 1."""
    for i in range(len(v) - 1):
        if v[i] >= level > v[i + 1]:
            return i
    return None


def _at(
    f: np.ndarray, v: np.ndarray, i: int, level: float, other: np.ndarray
) -> tuple[float, float]:
    """Frequency where v passes `level` between i and i + 1 (linear in log f), and `other`
    interpolated there."""
    s = (level - v[i]) / (v[i + 1] - v[i])
    lf = math.log10(f[i]) + s * (math.log10(f[i + 1]) - math.log10(f[i]))
    return 10.0**lf, float(other[i] + s * (other[i + 1] - other[i]))


def bandwidth_hz(closed_loop: Frf) -> float | None:
    """Where the closed loop's magnitude first falls below -3 dB."""
    mag = closed_loop.magnitude_db
    i = _crossing(closed_loop.f_hz, mag, -3.0)
    return None if i is None else _at(closed_loop.f_hz, mag, i, -3.0, mag)[0]


def coherence_near(response: Frf, f_hz: float) -> float:
    """The median coherence within ±5 % of `f_hz`: how far the estimate holds there."""
    f = response.f_hz
    near = response.coherence[(f >= 0.95 * f_hz) & (f <= 1.05 * f_hz)]
    return float(np.median(near)) if len(near) else 0.0


def _phase_zero(f: np.ndarray, phase: np.ndarray, i: int, rising: bool) -> float | None:
    """The frequency near index i where the phase (wrapped, °) crosses 0° upwards (`rising`)
    or downwards, interpolated in log f; None without one within ±15 % of f[i]."""
    best: float | None = None
    for j in range(len(f) - 1):
        if not 0.85 * f[i] <= f[j] <= 1.15 * f[i]:
            continue
        a, b = phase[j], phase[j + 1]
        if abs(b - a) > 180.0 or (a < 0.0 <= b) != rising or (a >= 0.0 > b) == rising:
            continue
        s = -a / (b - a)
        at = float(10.0 ** (math.log10(f[j]) + s * (math.log10(f[j + 1]) - math.log10(f[j]))))
        if best is None or abs(at - f[i]) < abs(best - f[i]):
            best = at
    return best


def resonances(
    mechanics: Frf, prominence_db: float = 6.0, min_coherence: float = 0.8
) -> tuple[list[float], list[float]]:
    """(resonance, anti-resonance) frequencies of a mechanics response (torque to motor
    speed): its magnitude's peaks and dips that stand out by `prominence_db` from the
    -20 dB/decade of a rigid body (the magnitude times frequency is flat for a rigid one),
    where the coherence says the estimate holds and the phase turns. Each is placed where
    the phase passes 0°
    (-90° of a rigid body, +90° between anti-resonance and resonance): for a two-mass system
    that is exactly the undamped frequency, which a damped magnitude peak is not."""
    f = mechanics.f_hz
    flat = mechanics.magnitude_db + 20.0 * np.log10(f)
    phase = np.degrees(np.angle(mechanics.h))
    # an anti-resonance leaves little output, so its own bins cohere less: judge the
    # neighbourhood (±5 %)
    trusted = [coherence_near(mechanics, fi) >= min_coherence for fi in f]
    peaks, p_props = signal.find_peaks(flat, prominence=prominence_db)
    dips, d_props = signal.find_peaks(-flat, prominence=prominence_db)

    inner = (f >= 1.05 * f[0]) & (f <= f[-1] / 1.05)  # not at the band's edges

    def place(found: np.ndarray, prominence: np.ndarray, rising: bool) -> list[float]:
        # a peak without the phase's turn is no resonance (friction, a leak of the window);
        # the three that stand out most, one per 5 %, in frequency order
        at = [
            (float(p), _phase_zero(f, phase, int(i), rising))
            for i, p in zip(found, prominence, strict=True)
            if trusted[i] and inner[i]
        ]
        kept: list[float] = []
        for _, hz in sorted((x for x in at if x[1] is not None), reverse=True):
            if hz is not None and all(abs(hz - k) > 0.05 * k for k in kept):
                kept.append(hz)
        return sorted(kept[:MAX_RESONANCES])

    return place(peaks, p_props["prominences"], False), place(dips, d_props["prominences"], True)
