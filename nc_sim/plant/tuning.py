"""Speed-loop tuning from a measured open loop, as a drive's autotune does it: what the loop
is without its controller follows from the measurement and the controller the drive knows it
ran (its own PI), and every candidate controller (gain, integral time, a notch on the
resonance) is judged on that measured remainder against a stability template's phase and gain
margin. The highest closed-loop bandwidth that keeps both margins wins.

Margins are read on the Nyquist curve itself, so a resonance that lifts the loop above 0 dB
again counts with its own crossover, and a crossing of the negative real axis above the
crossover with |L| ≥ 1 rejects the candidate (it would not be stable). Frequencies in Hz,
times in s, the controller as the drive runs it: C(z) = Kp·(1 + Ts/Tn · z/(z − 1)).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

KP_RANGE = (0.1, 100.0)  # the gains searched, as factors of the measured loop's own
KP_STEPS = 40  # then refined between the last that keeps the template and the first not
KP_REFINE = 6
TN_RANGE_S = (0.5e-3, 100e-3)
TN_STEPS = 24
NOTCH_WIDTHS = (0.15, 0.3, 0.5)  # denominator damping of the notch candidates
NOTCH_DEPTH = 0.1  # numerator over denominator damping: -20 dB at the centre
NOTCH_GAIN = 1.05  # a notch is proposed only when it buys at least this much bandwidth
MAX_POINTS = 800  # frequencies the search judges (log-spaced picks of the measured ones)
# kept beyond the template's margins: what the estimate may be off by between measurements
GUARD_DEG, GUARD_DB = 1.0, 0.5


@dataclass(frozen=True)
class Template:
    """A stability template: the least phase and gain margin the loop must keep."""

    name: str
    phase_margin_deg: float
    gain_margin_db: float


TEMPLATES = {
    1: Template("stiff", 45.0, 8.0),
    2: Template("medium", 55.0, 12.0),
    3: Template("soft", 60.0, 20.0),
}


@dataclass(frozen=True)
class Notch:
    """A band stop at `f_hz`: (s²/ω² + 2·Dn·s/ω + 1) / (s²/ω² + 2·Dd·s/ω + 1)."""

    f_hz: float
    width: float  # Dd
    depth: float  # Dn

    def response(self, f_hz: np.ndarray) -> np.ndarray:
        s = 2j * np.pi * f_hz / (2.0 * np.pi * self.f_hz)
        return np.asarray(
            (s * s + 2.0 * self.depth * s + 1.0) / (s * s + 2.0 * self.width * s + 1.0)
        )


def pi_response(kp: float, tn_s: float, ts: float, f_hz: np.ndarray) -> np.ndarray:
    """The drive's discrete PI at these frequencies (Tn 0: P only)."""
    z = np.exp(2j * np.pi * f_hz * ts)
    integral = ts / tn_s * z / (z - 1.0) if tn_s > 0.0 else 0.0
    return np.asarray(kp * (1.0 + integral))


@dataclass(frozen=True)
class LoopFigures:
    """What a loop's Nyquist curve says (None: not stable, or no crossover in the band)."""

    phase_margin_deg: float
    gain_margin_db: float
    crossover_hz: float
    bandwidth_hz: float
    phase_crossover_hz: float | None  # where the gain margin is read


def _unwrapped_deg(loop: np.ndarray) -> np.ndarray:
    """The phase unwrapped from the lowest frequency on, its start within (-270°, 90°]: a loop
    with the mechanics' integrator and the PI's starts near -180°."""
    phase = np.degrees(np.unwrap(np.angle(loop)))
    return np.asarray(phase - 360.0 * math.ceil((phase[0] - 90.0) / 360.0))


def _at(f: np.ndarray, v: np.ndarray, i: int, level: float) -> float:
    """Where v crosses `level` between i and i + 1, linear in f."""
    t = (level - v[i]) / (v[i + 1] - v[i])
    return float(f[i] + t * (f[i + 1] - f[i]))


def loop_figures(f_hz: np.ndarray, loop: np.ndarray) -> LoopFigures | None:
    """Margins, crossover and closed-loop bandwidth of open loop `loop` over `f_hz`; None
    when it has no crossover in the band or is not stable.

    Stability by Nyquist on the measured band: every crossing of the negative real axis
    outside the unit circle (the phase through -180° mod 360° at |L| > 1) counts +1 upwards,
    -1 downwards, and a start below -180° counts as a crossing down at 0 Hz (a loop with two
    integrators starts at -180° exactly); the sum must be 0. (Below the crossover such a loop
    may dip under -180° and come back: two crossings, no encirclement.) The phase margin is
    the least angle between -1 and the curve where it crosses the unit circle; the gain
    margin is read where the phase crosses -180° above the first crossover."""
    mag_db = 20.0 * np.log10(np.abs(loop))
    phase = _unwrapped_deg(loop)
    above = mag_db >= 0.0
    cross = np.flatnonzero(above[:-1] != above[1:])
    if len(cross) == 0 or not above[0]:
        return None
    pms = []
    for i in cross:
        t = -mag_db[i] / (mag_db[i + 1] - mag_db[i])
        at = float(phase[i] + t * (phase[i + 1] - phase[i]))
        pms.append(180.0 - abs((at + 180.0) % 360.0 - 180.0))
    first = _at(f_hz, mag_db, int(cross[0]), 0.0)
    wound = np.floor((phase + 180.0) / 360.0)  # whole turns past -180°
    net = -1 if phase[0] < -180.0 else 0
    worst_db, where = -math.inf, None
    for i in np.flatnonzero(wound[:-1] != wound[1:]):
        level = 360.0 * max(wound[i], wound[i + 1]) - 180.0
        t = (level - phase[i]) / (phase[i + 1] - phase[i])
        m = float(mag_db[i] + t * (mag_db[i + 1] - mag_db[i]))
        at = float(f_hz[i] + t * (f_hz[i + 1] - f_hz[i]))
        if m > 0.0:
            net += 1 if wound[i + 1] > wound[i] else -1
        elif at > first and m > worst_db:
            worst_db, where = m, at
    if net != 0:
        return None
    closed = np.abs(loop / (1.0 + loop))
    low = np.flatnonzero(closed < 1.0 / math.sqrt(2.0))
    bw = float(f_hz[low[0]]) if len(low) else float(f_hz[-1])
    return LoopFigures(min(pms), -worst_db, first, bw, where)


@dataclass(frozen=True)
class Tuning:
    """The controller the search chose, what its loop keeps and what stopped it."""

    kp: float
    tn_s: float
    notch: Notch | None
    figures: LoopFigures
    limited_by: str


def _meets(fig: LoopFigures | None, t: Template) -> bool:
    return (
        fig is not None
        and fig.phase_margin_deg >= t.phase_margin_deg
        and (fig.gain_margin_db >= t.gain_margin_db)
    )


def _why(fig: LoopFigures | None, t: Template, resonance_hz: float | None) -> str:
    """What a gain one step higher violates."""
    if fig is None:
        return "stability: a higher gain would make the loop unstable"
    if fig.gain_margin_db < t.gain_margin_db + GUARD_DB:
        at = fig.phase_crossover_hz
        if at is not None and resonance_hz is not None and abs(at / resonance_hz - 1.0) < 0.25:
            return f"the resonance at {resonance_hz:.0f} Hz: the gain margin there"
        where = f" at {at:.0f} Hz" if at is not None else ""
        return f"the gain margin{where} ({t.gain_margin_db:g} dB)"
    return f"the phase margin ({t.phase_margin_deg:g}°)"


def thin(f_hz: np.ndarray, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """At most MAX_POINTS frequencies spaced evenly in log f, and the arrays' values there."""
    if len(f_hz) <= MAX_POINTS:
        return (f_hz, *arrays)
    keep = np.unique(np.searchsorted(f_hz, np.geomspace(f_hz[0], f_hz[-1], MAX_POINTS)))
    keep = keep.clip(0, len(f_hz) - 1)
    return (f_hz[keep], *(a[keep] for a in arrays))


def _judge(f_hz: np.ndarray, shape: np.ndarray, kp: float) -> LoopFigures | None:
    return loop_figures(f_hz, kp * shape)


_NEVER = LoopFigures(0.0, 0.0, 0.0, 0.0, None)  # no gain in the range broke the template


def _highest(
    kps: np.ndarray, judge: Callable[[float], LoopFigures | None], template: Template
) -> tuple[float, LoopFigures, LoopFigures | None] | None:
    """The highest gain that keeps the template (scanning up from the lowest, then bisecting
    to the first that does not), its figures and the figures that broke it (`_NEVER`)."""
    ok: tuple[float, LoopFigures] | None = None
    bad: tuple[float, LoopFigures | None] | None = None
    for kp in kps:
        fig = judge(float(kp))
        if _meets(fig, template):
            assert fig is not None
            ok = (float(kp), fig)
        elif ok is not None:
            bad = (float(kp), fig)
            break
    if ok is None:
        return None
    if bad is None:
        return ok[0], ok[1], _NEVER
    for _ in range(KP_REFINE):
        mid = math.sqrt(ok[0] * bad[0])
        fig = judge(mid)
        if _meets(fig, template):
            assert fig is not None
            ok = (mid, fig)
        else:
            bad = (mid, fig)
    return ok[0], ok[1], bad[1]


def tune(
    f_hz: np.ndarray,
    plant: np.ndarray,
    ts: float,
    template: Template,
    kp_now: float,
    resonance_hz: float | None,
) -> Tuning | None:
    """The PI (and notch on `resonance_hz`) with the highest bandwidth that keeps
    `template` on the loop `plant` (the measured open loop without its controller); gains
    from KP_RANGE × `kp_now`. None when no candidate keeps the template."""
    f, g = thin(f_hz, plant)
    notches: list[Notch | None] = [None]
    if resonance_hz is not None:
        notches += [Notch(resonance_hz, w, w * NOTCH_DEPTH) for w in NOTCH_WIDTHS]
    kps = np.geomspace(KP_RANGE[0] * kp_now, KP_RANGE[1] * kp_now, KP_STEPS)
    best: dict[bool, Tuning] = {}
    for notch in notches:
        shaped = g * (notch.response(f) if notch is not None else 1.0)
        for tn in np.geomspace(*TN_RANGE_S, TN_STEPS):
            c = pi_response(1.0, float(tn), ts, f)
            found = _highest(kps, partial(_judge, f, c * shaped), template)
            if found is None:
                continue
            kp, fig, broke = found
            key = notch is not None
            old = best.get(key)
            if old is None or fig.bandwidth_hz > old.figures.bandwidth_hz:
                why = (
                    "the search's range" if broke is _NEVER else _why(broke, template, resonance_hz)
                )
                best[key] = Tuning(kp, float(tn), notch, fig, why)
    plain, notched = best.get(False), best.get(True)
    if notched is not None and (
        plain is None or notched.figures.bandwidth_hz >= NOTCH_GAIN * plain.figures.bandwidth_hz
    ):
        return notched
    return plain
