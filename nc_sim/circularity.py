"""The circularity test's geometry (ISO 230-4, the NC's own feedback as in its annex E):
fitting the least-squares circle, the deviations the standard defines, and what a ballbar
analysis reads out of the radial deviation: the ellipse (servo mismatch or squareness) and
the reversal spikes at the quadrant points. Pure functions of the recorded path; the
assistant that runs the circle and names the cause builds on them.

Angles are in degrees from the plane's first axis, counter-clockwise; lengths in the path's
unit (mm).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

GAUSS_NEWTON_STEPS = 5  # from the algebraic fit, enough for deviations far below the radius


@dataclass(frozen=True)
class CircleFit:
    """A least-squares circle: centre and radius."""

    x0: float
    y0: float
    radius: float


def fit_circle(x: np.ndarray, y: np.ndarray) -> CircleFit:
    """The geometric least-squares circle through the points (x, y): the algebraic fit,
    refined by Gauss-Newton on the radial distances."""
    a = np.column_stack([x, y, np.ones_like(x)])
    d, e, f = np.linalg.lstsq(a, -(x * x + y * y), rcond=None)[0]
    x0, y0 = -d / 2.0, -e / 2.0
    r = math.sqrt(max(x0 * x0 + y0 * y0 - f, 0.0))
    for _ in range(GAUSS_NEWTON_STEPS):
        dx, dy = x - x0, y - y0
        dist = np.hypot(dx, dy)
        jac = np.column_stack([-dx / dist, -dy / dist, -np.ones_like(x)])
        step = np.linalg.lstsq(jac, -(dist - r), rcond=None)[0]
        x0, y0, r = x0 + step[0], y0 + step[1], r + step[2]
    return CircleFit(float(x0), float(y0), float(r))


def radial_deviation(x: np.ndarray, y: np.ndarray, fit: CircleFit) -> tuple[np.ndarray, np.ndarray]:
    """(angle in degrees 0 … 360, radial deviation from the fitted radius) of each point."""
    dx, dy = x - fit.x0, y - fit.y0
    theta = np.degrees(np.arctan2(dy, dx)) % 360.0
    return theta, np.hypot(dx, dy) - fit.radius


@dataclass(frozen=True)
class Deviations:
    """ISO 230-4's figures of one path about its least-squares centre."""

    circular: float  # G: the radial range containing the path (max - min)
    radius_change: float  # fitted radius minus the nominal
    radial_max: float  # the largest and smallest deviation from the nominal radius
    radial_min: float


def deviations(x: np.ndarray, y: np.ndarray, nominal_radius: float) -> Deviations:
    """The circular deviation, the radius change and the radial deviation's extremes."""
    fit = fit_circle(x, y)
    _, dr = radial_deviation(x, y, fit)
    change = fit.radius - nominal_radius
    return Deviations(
        float(dr.max() - dr.min()),
        change,
        float(dr.max()) + change,
        float(dr.min()) + change,
    )


def bidirectional_deviation(paths: Sequence[tuple[np.ndarray, np.ndarray]]) -> float:
    """G(b): the radial range containing all paths (CW and CCW) about their common
    least-squares centre."""
    x = np.concatenate([p[0] for p in paths])
    y = np.concatenate([p[1] for p in paths])
    _, dr = radial_deviation(x, y, fit_circle(x, y))
    return float(dr.max() - dr.min())


@dataclass(frozen=True)
class Ellipse:
    """The path's ellipse: the second harmonic of its radial deviation."""

    peak_to_valley: float
    axis_deg: float  # direction of the long axis, 0 … 180


def ellipse(theta_deg: np.ndarray, dr: np.ndarray) -> Ellipse:
    """Fit dr ≈ c + a·cos 2θ + b·sin 2θ (the first harmonic absorbs what is left of a
    centre offset): the ellipse's peak-to-valley 2·√(a² + b²) and its long axis."""
    t = np.radians(theta_deg)
    basis = np.column_stack([np.ones_like(t), np.cos(t), np.sin(t), np.cos(2 * t), np.sin(2 * t)])
    coef = np.linalg.lstsq(basis, dr, rcond=None)[0]
    a, b = coef[3], coef[4]
    axis = (math.degrees(math.atan2(b, a)) / 2.0) % 180.0
    return Ellipse(2.0 * math.hypot(a, b), axis)


@dataclass(frozen=True)
class Spike:
    """A reversal spike: how far the path leaves its smooth shape near a quadrant point."""

    angle_deg: float
    height: float  # signed: outward positive


QUADRANTS_DEG = (0.0, 90.0, 180.0, 270.0)  # where one axis of the plane reverses


def reversal_spikes(
    theta_deg: np.ndarray, dr: np.ndarray, half_width_deg: float = 15.0, harmonics: int = 4
) -> list[Spike]:
    """At each quadrant point the largest departure of dr from its smooth shape (a Fourier
    series up to `harmonics`, fitted away from the quadrant points), within ±half_width."""
    t = np.radians(theta_deg)
    near = np.zeros(len(t), dtype=bool)
    for q in QUADRANTS_DEG:
        near |= _within(theta_deg, q, half_width_deg)
    cols = [np.ones_like(t)]
    for k in range(1, harmonics + 1):
        cols += [np.cos(k * t), np.sin(k * t)]
    basis = np.column_stack(cols)
    coef = np.linalg.lstsq(basis[~near], dr[~near], rcond=None)[0]
    residual = dr - basis @ coef
    spikes = []
    for q in QUADRANTS_DEG:
        idx = np.flatnonzero(_within(theta_deg, q, half_width_deg))
        if len(idx) == 0:
            continue
        i = idx[np.argmax(np.abs(residual[idx]))]
        spikes.append(Spike(float(theta_deg[i]), float(residual[i])))
    return spikes


def _within(theta_deg: np.ndarray, centre_deg: float, half_width_deg: float) -> np.ndarray:
    d = (theta_deg - centre_deg + 180.0) % 360.0 - 180.0
    return np.asarray(np.abs(d) <= half_width_deg)


@dataclass(frozen=True)
class LostMotion:
    """The steps where the plane's first and second axis reverse (backlash, and the twist
    friction puts into the drive train), and the ellipse fitted with them."""

    step_a: float
    step_b: float
    ellipse: Ellipse


def lost_motion(
    theta_deg: np.ndarray,
    dr: np.ndarray,
    way_a: np.ndarray,
    way_b: np.ndarray,
    exclude_deg: float,
) -> LostMotion:
    """The lost motion of both axes from the radial deviation of the true path: behind a gap
    b the load trails the motor by b/2 against the way it moves, so an axis' gap adds
    -b/2 · way · (its direction's share of the radius: cos θ or sin θ), a step of b where it
    reverses. Fitted by least squares with the centre and the ellipse (harmonics up to 2),
    leaving out ±`exclude_deg` about the quadrant points where the reversals' transients
    are; `way_a`, `way_b`: the sign of each axis' commanded velocity at each point."""
    t = np.radians(theta_deg)
    near = np.zeros(len(t), dtype=bool)
    for q in QUADRANTS_DEG:
        near |= _within(theta_deg, q, exclude_deg)
    keep = ~near if np.count_nonzero(~near) >= 16 else np.ones(len(t), dtype=bool)
    cols = [np.ones_like(t), np.cos(t), np.sin(t), np.cos(2 * t), np.sin(2 * t)]
    cols += [-0.5 * way_a * np.cos(t), -0.5 * way_b * np.sin(t)]
    coef = np.linalg.lstsq(np.column_stack(cols)[keep], dr[keep], rcond=None)[0]
    a, b = coef[3], coef[4]
    axis = (math.degrees(math.atan2(b, a)) / 2.0) % 180.0
    return LostMotion(float(coef[5]), float(coef[6]), Ellipse(2.0 * math.hypot(a, b), axis))
