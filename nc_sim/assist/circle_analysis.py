"""What the circularity test found (nc_sim/assist/circle_test.py runs it): ISO 230-4's
figures about the least-squares centre, the ellipse and what makes it (servo mismatch turns
over with the direction, squareness and scale do not), reversal spikes, lost motion, the
effective kv of both axes with the proposal to match them, and the cause in words with the
parameter to look at. Lengths in µm in the figures, angles in degrees from the plane's first
axis towards its second.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nc_sim.assist.result import Change, Figure, Result, Series
from nc_sim.axis.state import Axis
from nc_sim.circularity import (
    bidirectional_deviation,
    deviations,
    fit_circle,
    lost_motion,
    radial_deviation,
    reversal_spikes,
)

UM = 1000.0  # µm per mm
POLAR_POINTS = 720  # per direction in the plot
DIAGONAL_TOL_DEG = 20.0  # an ellipse this close to 45°/135° lies on a diagonal
TURNS_OVER_DEG = 60.0  # CW and CCW axes at least this far apart: it turns over
MIN_SHAPE_UM = 1.0  # below this no shape is worth a diagnosis
SHAPE_SHARE = 0.25  # ... nor one below this share of the circular deviation
SPIKE_UM = 1.0
BACKLASH_UM = 0.5
TRANSIENT_KV_TAUS = 5.0  # a reversal's transient lasts this many 1/kv
NAMES = {2: "cw", 3: "ccw"}


@dataclass(frozen=True)
class Turn:
    """One direction's measured turn (n points × the plane's two axes): commanded and
    measured positions (mm), the NC's lag (mm) and commanded velocity (mm/s)."""

    g: int
    cmd: np.ndarray
    act: np.ndarray
    lag: np.ndarray
    vel: np.ndarray
    cycle_s: float


@dataclass(frozen=True)
class _Shape:
    g: int
    theta: np.ndarray
    dr: np.ndarray
    circular: float
    radius_change: float
    ellipse_pv: float
    ellipse_deg: float
    spike: float
    spike_deg: float
    lost: tuple[float, float]  # the steps where the first and the second axis reverse


def effective_kv(turns: list[Turn], axis: int) -> float:
    """The position loop's effective gain of one axis (1/s): v = k·lag + c·d(lag)/dt fitted
    over the turns by least squares (the derivative takes the loop's own lag of the lag: a
    first-order loop gives exactly its kv, with feedforward the larger gain it acts like)."""
    rows, rhs = [], []
    for t in turns:
        lag = t.lag[:, axis]
        rows.append(np.column_stack([lag, np.gradient(lag, t.cycle_s)]))
        rhs.append(t.vel[:, axis])
    coef = np.linalg.lstsq(np.concatenate(rows), np.concatenate(rhs), rcond=None)[0]
    return float(coef[0])


def _shape(t: Turn, radius: float, exclude_deg: float) -> _Shape:
    x, y = t.act[:, 0], t.act[:, 1]
    d = deviations(x, y, radius)
    theta, dr = radial_deviation(x, y, fit_circle(x, y))
    spikes = reversal_spikes(theta, dr)
    top = max(spikes, key=lambda s: abs(s.height)) if spikes else None
    ways = np.sign(t.vel)
    lost = lost_motion(theta, dr, ways[:, 0], ways[:, 1], exclude_deg)
    el = lost.ellipse
    return _Shape(
        t.g,
        theta,
        dr,
        d.circular,
        d.radius_change,
        el.peak_to_valley,
        el.axis_deg,
        top.height if top else 0.0,
        top.angle_deg if top else 0.0,
        (lost.step_a, lost.step_b),
    )


def _near(deg: float, target: float) -> float:
    """Distance of two axis directions (mod 180°)."""
    return abs((deg - target + 90.0) % 180.0 - 90.0)


def _polar(s: _Shape) -> Series:
    order = np.argsort(s.theta)
    every = max(1, len(order) // POLAR_POINTS)
    pick = order[::every]
    return Series(
        NAMES[s.g].upper(),
        tuple(float(v) for v in s.theta[pick]),
        tuple(float(v) * UM for v in s.dr[pick]),
        "°",
        "µm",
    )


def analyse(
    axes: tuple[Axis, Axis],
    turns: list[Turn],
    radius: float,
    feed_mm_min: float,
    true_path: bool,
    inputs: dict[str, float | int | str],
) -> Result:
    """The figures, the kv proposal and the diagnosis of the measured turns."""
    a, b = (ax.name for ax in axes)
    kv = (effective_kv(turns, 0), effective_kv(turns, 1))
    omega = feed_mm_min / 60.0 / radius
    exclude = min(40.0, max(3.0, math.degrees(TRANSIENT_KV_TAUS * omega / min(kv))))
    shapes = [_shape(t, radius, exclude) for t in turns]
    figures: list[Figure] = []
    for s in shapes:
        n = NAMES[s.g]
        d = n.upper()
        figures += [
            Figure(f"circular_{n}_um", s.circular * UM, "µm", f"circular deviation G, {d}"),
            Figure(f"radius_change_{n}_um", s.radius_change * UM, "µm", f"radius change, {d}"),
            Figure(f"ellipse_{n}_um", s.ellipse_pv * UM, "µm", f"ellipse peak to valley, {d}"),
            Figure(f"ellipse_{n}_deg", s.ellipse_deg, "°", f"its long axis from {a}, {d}"),
            Figure(f"spike_{n}_um", s.spike * UM, "µm", f"largest reversal spike, {d}"),
            Figure(f"spike_{n}_deg", s.spike_deg, "°", f"where, {d}"),
        ]
    worst = max(s.circular for s in shapes)
    figures.insert(0, Figure("circular_um", worst * UM, "µm", "circular deviation G (the worse)"))
    if len(turns) == 2:
        g_b = bidirectional_deviation([(t.act[:, 0], t.act[:, 1]) for t in turns])
        figures.insert(1, Figure("bidirectional_um", g_b * UM, "µm", "bidirectional G(b)"))
    gaps = [float(np.mean([s.lost[i] for s in shapes])) for i in (0, 1)]
    for name, gap in zip((a, b), gaps, strict=True):
        figures.append(
            Figure(f"lost_motion_{name}_um", gap * UM, "µm", f"{name}: step where it reverses")
        )
    figures += [
        Figure(f"kv_{a}", kv[0], "1/s", f"{a}: effective kv (v over lag)"),
        Figure(f"kv_{b}", kv[1], "1/s", f"{b}: effective kv (v over lag)"),
        Figure(
            "kv_mismatch_ms",
            (1.0 / kv[0] - 1.0 / kv[1]) * 1000.0,
            "ms",
            f"1/kv of {a} minus 1/kv of {b}",
        ),
    ]
    notes = _diagnosis(axes, shapes, kv, radius, feed_mm_min, worst, gaps, true_path)
    changes = _kv_match(axes, kv, shapes, worst)
    how = "the true path (a ballbar's view)" if true_path else "the NC's feedback (annex E)"
    notes.insert(0, f"R{radius:g} at F{feed_mm_min:g} in {a}{b}, measured on {how}")
    return Result(
        "circle",
        tuple(figures),
        changes,
        tuple(_polar(s) for s in shapes),
        tuple(notes),
        True,
        inputs,
    )


def _worth(value: float, worst: float, floor_um: float = MIN_SHAPE_UM) -> bool:
    return abs(value) * UM >= floor_um and abs(value) >= SHAPE_SHARE * worst


def _diagnosis(
    axes: tuple[Axis, Axis],
    shapes: list[_Shape],
    kv: tuple[float, float],
    radius: float,
    feed: float,
    worst: float,
    gaps: list[float],
    true_path: bool,
) -> list[str]:
    a, b = (ax.name for ax in axes)
    v = feed / 60.0
    notes: list[str] = []
    big = [s for s in shapes if _worth(s.ellipse_pv, worst)]
    if big:
        pv = max(s.ellipse_pv for s in big) * UM
        diagonal = all(
            min(_near(s.ellipse_deg, 45), _near(s.ellipse_deg, 135)) <= DIAGONAL_TOL_DEG
            for s in big
        )
        if len(big) == 2:
            turns_over = _near(big[0].ellipse_deg, big[1].ellipse_deg) >= TURNS_OVER_DEG
        else:
            turns_over = None
        expected = v * abs(1 / kv[0] - 1 / kv[1]) * UM
        if diagonal and turns_over and expected >= 0.5 * pv:
            slow = a if kv[0] < kv[1] else b
            notes.append(
                f"servo mismatch: an ellipse of {pv:.1f} µm on a diagonal that turns over with "
                f"the direction; {a} follows with kv {kv[0]:.2f}/s, {b} with {kv[1]:.2f}/s "
                f"({slow} lags more; F·|1/kv_{a} − 1/kv_{b}| = {expected:.1f} µm). Match the "
                "effective kv (getriebe[i].kv; a gain the drive adds: multi_gain, the "
                "multi-gain assistant; feedforward lr_param.ff_weight alike on both)"
            )
        elif diagonal and turns_over:
            notes.append(
                f"an ellipse of {pv:.1f} µm on a diagonal that turns over with the direction, "
                f"though {a} and {b} follow with about the same kv ({kv[0]:.2f}, {kv[1]:.2f}/s): "
                "their drives answer differently on the curve; compare their frequency responses"
            )
        elif diagonal and turns_over is False:
            notes.append(
                f"squareness: an ellipse of {pv:.1f} µm on a diagonal that stays with the "
                f"direction: {a} and {b} are about {pv * 1000 / radius:.0f} µm/m out of square "
                "(mechanical alignment; the NC's feedback cannot see it, a ballbar can)"
            )
        elif turns_over is False:
            longer = a if min(_near(s.ellipse_deg, 0) for s in big) < 45 else b
            notes.append(
                f"scale mismatch: an ellipse of {pv:.1f} µm along {longer} in both directions: "
                f"{longer} travels about {pv * 1000 / radius:.0f} µm/m further than the other "
                "axis; check getriebe[i].wegaufz/wegaufn with the resolution check (the NC's "
                "feedback shows its own scale: a ballbar or laser shows the true one)"
            )
        elif turns_over is None:
            notes.append(
                f"an ellipse of {pv:.1f} µm at {big[0].ellipse_deg:.0f}°: run both directions "
                "to tell servo mismatch (turns over) from squareness or scale (does not)"
            )
    for name, gap, where in zip((a, b), gaps, ("0° and 180°", "90° and 270°"), strict=True):
        if gap * UM >= BACKLASH_UM:
            notes.append(
                f"lost motion on {name}: a step of {gap * UM:.1f} µm where it reverses ({where}): "
                "backlash (screw nut, coupling, bearings) and the twist friction puts into "
                "the drive train; remove the play or compensate it"
            )
    if not true_path and any(str(ax.cfg.raw("sim.measuring_system")) != "DIRECT" for ax in axes):
        notes.append(
            "measured on a motor encoder: backlash and twist behind the motor do not show "
            "here; the true path (a ballbar) shows them"
        )
    spiky = [s for s in shapes if s.spike * UM >= SPIKE_UM and abs(s.spike) >= 0.1 * worst]
    if spiky:
        top = max(spiky, key=lambda s: abs(s.spike))
        which = a if min(_near(top.spike_deg, 0), _near(top.spike_deg, 180)) < 45 else b
        notes.append(
            f"reversal spikes up to {top.spike * UM:.1f} µm (at {top.spike_deg:.0f}°, where "
            f"{which} reverses): friction the speed loop takes time to overcome; a stiffer "
            "speed loop (drive.speed_kp, drive.speed_tn) or friction compensation"
        )
    shrink = [s.radius_change for s in shapes]
    # each axis' share by its own kv: the fitted radius is their mean
    omega = v / radius
    shrink_expected = float(
        np.mean([radius * (1.0 - 1.0 / math.sqrt(1.0 + (omega / k) ** 2)) for k in kv])
    )
    if max(abs(c) for c in shrink) * UM >= MIN_SHAPE_UM and min(shrink) < 0:
        notes.append(
            f"the radius shrinks by {-min(shrink) * UM:.1f} µm: the position loop's lag on the "
            f"curve, R(1 − 1/√(1 + (ω/kv)²)) = {shrink_expected * UM:.1f} µm with ω = F/R and "
            f"the axes' kv ({kv[0]:.1f}, {kv[1]:.1f}/s; a sampled loop a little less); "
            "feedforward (lr_param.ff_weight) or a higher kv makes it smaller"
        )
    if len(notes) == 0:
        notes.append("round: no shape stands out")
    return notes


def _kv_match(
    axes: tuple[Axis, Axis], kv: tuple[float, float], shapes: list[_Shape], worst: float
) -> tuple[Change, ...]:
    """kv matching (AST's path interpolation): the faster axis' kv brought down to the
    slower one's effective gain, so both follow the path alike (the mismatch ellipse goes)."""
    if not any(_worth(s.ellipse_pv, worst) for s in shapes) or abs(kv[0] / kv[1] - 1) < 0.01:
        return ()
    fast = 0 if kv[0] > kv[1] else 1
    ax = axes[fast]
    gi = ax.gear - 1
    before = int(ax.cfg.raw("getriebe.kv", ax.gear))
    after = max(1, round(before * kv[1 - fast] / kv[fast]))
    why = f"equal effective kv: {axes[1 - fast].name} follows with {kv[1 - fast]:.2f}/s"
    return (Change(ax.name, f"getriebe[{gi}].kv", before, after, why),)
