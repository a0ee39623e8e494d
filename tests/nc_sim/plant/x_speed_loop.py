"""The demo X's speed loop as python-control builds it from the axis' list
(nc_sim/config/demo/axis_1.lis), block by block: the independent reference the autotune and
the tuning exercise are checked against (the code under test never reads these numbers for
its judgement; the autotune works from its measurements).

    L(z) = PI(z) · z⁻¹ (computing time) · ZOH[low pass · notches · current loop · two masses](z)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import control
import numpy as np

TS = 125e-6
# the demo X (nc_sim/config/demo/axis_1.lis) with its speed gain detuned to a quarter
J_M, RATIO, F_AR, DAMP, VISCOUS = 0.001, 2.5, 65.0, 0.05, 0.0005
KP_DEMO, TN_DEMO = 0.5, 0.012
T_I = 250e-6  # current loop (default)
F_LP, D_LP = 1500.0, 0.7  # current setpoint filter 1
F_R = F_AR * math.sqrt(RATIO)  # the resonance: 102.8 Hz


@dataclass(frozen=True)
class Knobs:
    kp: float
    tn_s: float
    # each (frequency (Hz), denominator and numerator damping), in the current setpoint path
    notches: tuple[tuple[float, float, float], ...] = ()


def mechanics(f_ar: float) -> Any:
    s = control.tf("s")
    jm, jl = J_M, J_M * (RATIO - 1.0)
    k = jl * (2 * np.pi * f_ar) ** 2
    d = 2 * DAMP * np.sqrt(k * jl)
    num = jl * s**2 + (d + VISCOUS) * s + k
    den = s * (jm * jl * s**2 + (d * (jm + jl) + VISCOUS * jm) * s + k * (jm + jl)) + VISCOUS * k
    return num / den


def open_loop(knobs: Knobs, f_ar: float = F_AR) -> Any:
    """The loop; the continuous chain joined block by block in state space (one transfer
    function of all of them loses the high frequencies to round-off)."""
    s = control.tf("s")
    wd = 2 * np.pi * F_LP
    blocks = [
        wd**2 / (s**2 + 2 * D_LP * wd * s + wd**2),
        1 / (T_I * s + 1),
        mechanics(f_ar),
    ]
    for f, dd, dn in knobs.notches:
        w = 2 * np.pi * f
        blocks.insert(1, (s**2 + 2 * dn * w * s + w**2) / (s**2 + 2 * dd * w * s + w**2))
    chain = control.ss(blocks[0])
    for b in blocks[1:]:
        chain = control.series(chain, control.ss(b))
    plant = control.c2d(chain, TS, method="zoh")
    z = control.tf([1.0, 0.0], [1.0], TS)
    integral = 0 if math.isinf(knobs.tn_s) else TS / knobs.tn_s * z / (z - 1)
    pi = knobs.kp * (1 + integral)
    return pi * plant / z


def margins(loop: Any) -> tuple[float, float]:
    """(phase margin: the least angle between -1 and the curve on the unit circle, over every
    gain crossover; gain margin above the first crossover, dB). Stability itself is checked
    on the closed loop's poles."""
    omega = 2 * np.pi * np.geomspace(1.0, 0.499 / TS, 4000)  # up to the drive's Nyquist
    sampled = control.frd(loop, omega)
    gm, pm, _sm, wpc, wgc, _wms = control.stability_margins(sampled, returnall=True)
    wgc = np.atleast_1d(wgc)
    if len(wgc) == 0:
        return -math.inf, -math.inf
    above = [g for g, w in zip(np.atleast_1d(gm), np.atleast_1d(wpc), strict=True) if w > min(wgc)]
    gm_db = 20 * math.log10(min(above)) if above else math.inf
    angles = [180.0 - abs((p - 180.0 + 180.0) % 360.0 - 180.0) for p in np.atleast_1d(pm)]
    return min(angles), gm_db


def bandwidth_hz(loop: Any) -> float:
    f = np.geomspace(1.0, 3000.0, 3000)
    closed = control.feedback(loop, 1)
    mag = np.abs(np.asarray(control.frequency_response(closed, 2 * np.pi * f).complex).ravel())
    low = np.flatnonzero(mag < 1 / math.sqrt(2))
    return float(f[low[0]])


def stable(loop: Any) -> bool:
    return bool(np.all(np.abs(control.poles(control.feedback(loop, 1))) < 1.0))


def meets(knobs: Knobs, pm_min: float, gm_min: float, f_ar: float = F_AR) -> bool:
    loop = open_loop(knobs, f_ar)
    pm, gm = margins(loop)
    return pm >= pm_min and gm >= gm_min and stable(loop)


OMEGA = 2 * np.pi * np.geomspace(1.0, 0.499 / TS, 3000)  # rad/s, up to the drive's Nyquist


def geometric(loop: np.ndarray) -> tuple[float, float]:
    """(phase margin, gain margin in dB) read off a frequency response: the angle to -1
    where |L| crosses 1, and 1/|L| where the curve crosses the negative real axis above the
    first crossover (-inf when it does so outside the unit circle)."""
    mag = np.abs(loop)
    cross = np.flatnonzero((mag[:-1] >= 1) != (mag[1:] >= 1))
    if len(cross) == 0:
        return -math.inf, -math.inf
    pm = min(180 - abs(math.degrees(np.angle(loop[i]))) for i in cross)
    im = loop.imag
    real_axis = np.flatnonzero((np.signbit(im[:-1]) != np.signbit(im[1:])) & (loop.real[:-1] < 0))
    outside = [-loop.real[i] for i in real_axis if i > cross[0]]
    worst = max(outside, default=0.0)
    return pm, (-math.inf if worst >= 1 else -20 * math.log10(worst) if worst else math.inf)


def best_bandwidth(pm_min: float, gm_min: float, f_ar: float = F_AR) -> float:
    """python-control's own search over the same knobs: for each integral time and notch
    (none, or on the resonance at three widths), the highest gain that keeps the template
    (a scan up to the first that breaks it, then bisection) on the model's response, its
    closed loop stable by its poles;
    the best bandwidth of them."""
    best = 0.0
    f_r = f_ar * math.sqrt(RATIO)
    notches: list[tuple[tuple[float, float, float], ...]] = [()]
    notches += [((f_r, w, w / 10),) for w in (0.15, 0.3, 0.5)]
    z = np.exp(1j * OMEGA * TS)
    for notch in notches:
        # the loop with Kp = 1 and no integral part: the controller is applied in numpy
        unit = open_loop(Knobs(1.0, math.inf, notch), f_ar)
        plant = np.asarray(control.frequency_response(unit, OMEGA).complex).ravel()
        for tn in np.geomspace(1e-3, 50e-3, 10):
            shape = (1 + TS / tn * z / (z - 1)) * plant

            def keeps(kp: float, shape: np.ndarray = shape) -> bool:
                pm, gm = geometric(kp * shape)
                return pm >= pm_min and gm >= gm_min

            # up from the lowest gain to the first that breaks the template (a gain far
            # beyond, whose |L| stays above 1 to the band's end, reads as keeping it)
            kps = np.geomspace(0.05, 10.0, 24)
            lo = hi = None
            for kp in kps:
                if keeps(kp):
                    lo = kp
                elif lo is not None:
                    hi = kp
                    break
            if lo is None or hi is None:
                continue
            for _ in range(5):
                mid = math.sqrt(lo * hi)
                lo, hi = (mid, hi) if keeps(mid) else (lo, mid)
            if stable(open_loop(Knobs(lo, tn, notch), f_ar)):
                closed = np.abs(lo * shape / (1 + lo * shape))
                best = max(
                    best, float(OMEGA[np.flatnonzero(closed < 1 / math.sqrt(2))[0]]) / (2 * np.pi)
                )
    return best
