"""Acceleration curve fit [000 §2.8.4, DOMAIN §4.1]: the coefficients of a spindle gear's
curve a(n) (types 1 hyperbola, 2 polynomial, 3 asynchronous) from interpolation points or
many measured (n, a) points, and the run-up that measures them.

The curve laws are those of nc_sim/accel_curve.py; here they are only inverted:
- polynomial: a - a_konst = b1·Δn + b2·Δn² + b3·Δn³ is linear in (a_konst, b1, b2, b3);
- hyperbola: 1/a = 1/b1 + (b2/b1)·ν² + (b2·b3/b1)·ν⁴ is linear in its three terms;
- asynchronous: a_max, a_max·N1 (= a·n) and a_max·N1·N2 (= a·n²) are plain means per region.
Four (polynomial) or three (hyperbola) points solve exactly, the first being (n_limit, a_konst)
as the manual defines it; more points are fitted by least squares, and without n_limit the
limit speed is searched as well. Speeds in °/s, accelerations in °/s².
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from nc_sim.accel_curve import (
    CURVE_ASYNC,
    CURVE_HYPERBOLA,
    CURVE_POLYNOMIAL,
    CurveParams,
)
from nc_sim.assist.result import Change, Figure, Result, Series, Value
from nc_sim.config import MachineConfig
from nc_sim.errors import NcUsageError
from nc_sim.units import Quantity, to_raw

EXACT_POINTS = {CURVE_HYPERBOLA: 3, CURVE_POLYNOMIAL: 4}
MIN_POINTS = {CURVE_HYPERBOLA: 3, CURVE_POLYNOMIAL: 4, CURVE_ASYNC: 3}
LIMIT_CANDIDATES = 64  # limit speeds tried per refinement when n_limit is searched
CURVE = "beschl_kennlinie."


def _blank(typ: int, a_min: float) -> CurveParams:
    return CurveParams(typ, 0.0, 0.0, 0.0, 0.0, 0.0, a_min, 0.0, 0.0, 0.0, float("inf"))


def _model(curve: CurveParams, n: np.ndarray) -> np.ndarray:
    return np.array([curve.accel(float(x)) for x in n])


def _rel_sse(curve: CurveParams, n: np.ndarray, a: np.ndarray) -> float:
    err = (_model(curve, n) - a) / a
    return float(np.sum(err * err)) if np.all(np.isfinite(err)) else float("inf")


def _polynomial(n: np.ndarray, a: np.ndarray, n_limit: float, a_min: float) -> CurveParams:
    dn = np.clip(n - n_limit, 0.0, None)
    scale = max(float(dn.max()), 1.0)  # columns of order 1: Δn³ reaches 1e13 otherwise
    x = dn / scale
    cols = np.column_stack([np.ones_like(x), x, x**2, x**3])
    w = 1.0 / a  # relative errors: the low tail counts as much as the top
    coef = np.linalg.lstsq(cols * w[:, None], a * w, rcond=None)[0]
    a_konst, b1 = float(coef[0]), float(coef[1]) / scale
    b2, b3 = float(coef[2]) / scale**2, float(coef[3]) / scale**3
    return replace(
        _blank(CURVE_POLYNOMIAL, a_min), n_limit=n_limit, a_konst=a_konst, b1=b1, b2=b2, b3=b3
    )


def _hyperbola(n: np.ndarray, a: np.ndarray, n_limit: float, a_min: float) -> CurveParams:
    above = n >= n_limit
    if np.count_nonzero(above) < 3:
        raise NcUsageError("the hyperbola needs three points at or above the limit speed")
    nu2 = (n[above] / n_limit) ** 2
    cols = np.column_stack([np.ones_like(nu2), nu2, nu2 * nu2])
    # a·(c0 + c1·ν² + c2·ν⁴) = 1: the residual is the relative error of a
    c0, c1, c2 = np.linalg.lstsq(cols * a[above][:, None], np.ones_like(nu2), rcond=None)[0]
    b1 = 1.0 / float(c0)
    b2 = float(c1) * b1
    b3 = float(c2 / c1) if c1 != 0.0 else 0.0
    # a_konst is the curve's value at n_limit: a constant that is not would put a step into
    # the curve there, which a searched limit speed then hides between two points
    a_konst = b1 / (1.0 + b2 * (1.0 + b3))
    return replace(
        _blank(CURVE_HYPERBOLA, a_min), n_limit=n_limit, a_konst=a_konst, b1=b1, b2=b2, b3=b3
    )


def _asynchronous(n: np.ndarray, a: np.ndarray, a_min: float) -> CurveParams:
    """Every split of the sorted points into constant | 1/n | 1/n² regions; the best wins."""
    order = np.argsort(n)
    n, a = n[order], a[order]
    m = len(n)
    best: tuple[float, CurveParams] | None = None
    for i in range(1, m + 1):  # points [0, i) constant
        a_max = float(np.mean(a[:i]))
        for j in range(i, m + 1):  # [i, j) ~ 1/n, [j, m) ~ 1/n²
            k1 = float(np.mean(a[i:j] * n[i:j])) if j > i else a_max * float(n[i - 1])
            n1 = max(k1 / a_max, float(n[i - 1]))
            if j < m:
                k2 = float(np.mean(a[j:] * n[j:] ** 2))
                n2 = max(k2 / (a_max * n1), n1)
            else:
                n2 = 0.0  # no 1/n² region: N2 unset (the law then stays 1/n)
            curve = replace(_blank(CURVE_ASYNC, a_min), a_max3=a_max, n1=n1, n2=n2)
            sse = _rel_sse(curve, n, a)
            if best is None or sse < best[0] - 1e-15:
                best = (sse, curve)
    assert best is not None
    return best[1]


def _search_limit(typ: int, n: np.ndarray, a: np.ndarray, a_min: float) -> CurveParams:
    """The limit speed with the least relative error, on a grid refined twice."""
    fit = _polynomial if typ == CURVE_POLYNOMIAL else _hyperbola
    lo, hi = float(n.min()), float(np.sort(n)[-EXACT_POINTS[typ]])
    best: tuple[float, CurveParams] | None = None
    for _ in range(3):
        for n_limit in np.linspace(lo, hi, LIMIT_CANDIDATES):
            try:
                curve = fit(n, a, float(n_limit), a_min)
            except (NcUsageError, np.linalg.LinAlgError):
                continue
            sse = _rel_sse(curve, n, a)
            if best is None or sse < best[0]:
                best = (sse, curve)
        if best is None:
            break
        step = (hi - lo) / (LIMIT_CANDIDATES - 1)
        lo = max(float(n.min()), best[1].n_limit - step)
        hi = min(float(np.sort(n)[-EXACT_POINTS[typ]]), best[1].n_limit + step)
    if best is None:
        raise NcUsageError("no limit speed fits these points")
    return best[1]


def fit_curve(
    typ: int,
    n_deg_s: Sequence[float] | np.ndarray,
    a_deg_s2: Sequence[float] | np.ndarray,
    *,
    n_limit_deg_s: float | None = None,
    a_min: float = 0.0,
) -> CurveParams:
    """The curve of type `typ` through (or nearest to) the points; see the module docstring.
    Points at or below a_min are where the curve is floored and say nothing about it."""
    if typ not in MIN_POINTS:
        raise NcUsageError(
            f"curve type must be 1 (hyperbola), 2 (polynomial) or 3 (asynchronous), not {typ}"
        )
    n, a = np.asarray(n_deg_s, dtype=float), np.asarray(a_deg_s2, dtype=float)
    if n.shape != a.shape or n.ndim != 1:
        raise NcUsageError("speeds and accelerations must be lists of the same length")
    if not (np.all(np.isfinite(n)) and np.all(np.isfinite(a))) or np.any(n < 0):
        raise NcUsageError("points must be finite, with speeds n >= 0 °/s")
    keep = a > a_min
    n, a = n[keep], a[keep]
    if len(n) < MIN_POINTS[typ]:
        raise NcUsageError(f"curve type {typ} needs at least {MIN_POINTS[typ]} points above a_min")
    if len(np.unique(n)) != len(n):
        raise NcUsageError("two points have the same speed")
    if typ == CURVE_ASYNC:
        return _asynchronous(n, a, a_min)
    fit = _polynomial if typ == CURVE_POLYNOMIAL else _hyperbola
    if n_limit_deg_s is not None:
        return fit(n, a, float(n_limit_deg_s), a_min)
    if len(n) == EXACT_POINTS[typ]:  # the manual's method: P1 = (n_limit, a_konst)
        return fit(n, a, float(n.min()), a_min)
    return _search_limit(typ, n, a, a_min)


def curve_changes(
    curve: CurveParams,
    target: str,
    gear: int,
    before: dict[str, Value] | None = None,
    why: str = "",
) -> tuple[Change, ...]:
    """The curve as list values of gear record `gear` (1-based): speeds in 0.001 °/s,
    accelerations in whole °/s², coefficients as they are."""
    prefix = f"getriebe[{gear - 1}].{CURVE}"
    values: dict[str, Value] = {"typ": curve.typ}
    if curve.typ == CURVE_ASYNC:
        values |= {
            "a_max": round(curve.a_max3),
            "n1": round(to_raw(Quantity.VELOCITY, curve.n1)),
            "n2": round(to_raw(Quantity.VELOCITY, curve.n2)),
        }
    else:
        values |= {
            "n_grenz": round(to_raw(Quantity.VELOCITY, curve.n_limit)),
            "a_konst": round(curve.a_konst),
            "b1": float(f"{curve.b1:.9g}"),
            "b2": float(f"{curve.b2:.9g}"),
            "b3": float(f"{curve.b3:.9g}"),
        }
    old = before or {}
    return tuple(
        Change(target, prefix + name, old.get(prefix + name, ""), value, why)
        for name, value in values.items()
    )


def curve_figures(curve: CurveParams) -> tuple[Figure, ...]:
    """The fitted coefficients in the manual's units."""
    if curve.typ == CURVE_ASYNC:
        return (
            Figure("a_max", curve.a_max3, "°/s²", "acceleration below N1"),
            Figure("n1", curve.n1, "°/s", "speed limit N1 for maximum torque"),
            Figure("n2", curve.n2, "°/s", "speed limit N2 for maximum output"),
        )
    return (
        Figure("n_limit", curve.n_limit, "°/s", "limit speed"),
        Figure("a_konst", curve.a_konst, "°/s²", "constant acceleration below n_limit"),
        Figure("b1", curve.b1, "°/s²" if curve.typ == CURVE_HYPERBOLA else "1/s", ""),
        Figure("b2", curve.b2, "" if curve.typ == CURVE_HYPERBOLA else "1/°", ""),
        Figure("b3", curve.b3, "" if curve.typ == CURVE_HYPERBOLA else "s/°²", ""),
    )


def curve_series(curve: CurveParams, n: np.ndarray, a: np.ndarray) -> tuple[Series, Series]:
    """The points and the fitted curve over their speed range, for one plot."""
    grid = np.linspace(0.0, float(n.max()), 201)
    return (
        Series("points", tuple(map(float, n)), tuple(map(float, a)), "°/s", "°/s²"),
        Series(
            "fit", tuple(map(float, grid)), tuple(map(float, _model(curve, grid))), "°/s", "°/s²"
        ),
    )


def curve_fit(
    typ: int,
    points: Sequence[tuple[float, float]],
    *,
    n_limit_deg_s: float | None = None,
    a_min: float = 0.0,
    target: str = "S1",
    gear: int = 1,
) -> Result:
    """The curve-fit calculator: points (n °/s, a °/s²) -> coefficients as list changes.
    Check [000 §2.8.4]: (12000, 16000), (24000, 8000), (36000, 4000), (48000, 2000) give the
    polynomial b3 = -1.92901234e-10, b2 = 2.08333333e-5, b1 = -0.88888888; the first three
    the hyperbola b1 = 2.285714e4, b2 = 4.166666e-1, b3 = 2.857142e-2."""
    n = np.array([p[0] for p in points], dtype=float)
    a = np.array([p[1] for p in points], dtype=float)
    curve = fit_curve(typ, n, a, n_limit_deg_s=n_limit_deg_s, a_min=a_min)
    rel = (_model(curve, n) - a) / a
    used = a > a_min
    how = (
        "interpolation"
        if len(n) == EXACT_POINTS.get(typ) and n_limit_deg_s is None
        else "least squares"
    )
    return Result(
        "curve-fit",
        figures=(
            *curve_figures(curve),
            Figure(
                "max_error",
                float(np.max(np.abs(rel[used]))),
                "",
                "largest relative error at a point",
            ),
        ),
        changes=curve_changes(curve, target, gear, why=f"type {typ} by {how} from {len(n)} points"),
        series=curve_series(curve, n, a),
        inputs={
            "typ": typ,
            "points": ",".join(f"{x:g}:{y:g}" for x, y in points),
            "a_min": a_min,
            "target": target,
            "gear": gear,
            **({} if n_limit_deg_s is None else {"n_limit_deg_s": n_limit_deg_s}),
        },
    )


def curve_fit_of(
    cfg: MachineConfig,
    axis: str,
    gear: int,
    typ: int,
    points: Sequence[dict[str, float]],
    n_limit_deg_s: float | None,
    a_min: float,
) -> Result:
    """`curve_fit` for the spindle `axis` of the machine, from points {n_deg_s, a_deg_s2}
    (the assistants' registry)."""
    if not cfg.axis(axis).is_spindle:
        raise NcUsageError(f"axis: {axis} is not a spindle (the curve is a spindle gear's)")
    pairs = [(p["n_deg_s"], p["a_deg_s2"]) for p in points]
    return curve_fit(typ, pairs, n_limit_deg_s=n_limit_deg_s, a_min=a_min, target=axis, gear=gear)


def measured_accel(
    v_act: np.ndarray, open_loop: np.ndarray, cycle_s: float, window_s: float = 0.02
) -> tuple[np.ndarray, np.ndarray]:
    """(n, a) per cycle from the recorded actual speed: a moving average over `window_s`
    against the encoder's quantisation, then a central difference over the same window.
    Samples near a change of the control mode are NaN: when the loop opens, the actual speed
    is simulated from the command and jumps by the lag [000 §2.4.2]."""
    w = max(1, round(window_s / cycle_s))
    smooth = np.convolve(v_act, np.ones(w) / w, mode="same")
    a = np.full_like(smooth, np.nan)
    a[w:-w] = (smooth[2 * w :] - smooth[: -2 * w]) / (2 * w * cycle_s)
    a[: w + w // 2 + 1] = np.nan  # the average is cut off at the ends
    a[-(w + w // 2 + 1) :] = np.nan
    for k in np.flatnonzero(np.diff(open_loop) != 0):
        a[max(0, k - 2 * w) : k + 2 * w + 1] = np.nan
    return smooth, a


def binned(n: np.ndarray, a: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """Median acceleration per speed bin (robust against single bad samples)."""
    edges = np.linspace(float(n.min()), float(n.max()), bins + 1)
    idx = np.clip(np.digitize(n, edges) - 1, 0, bins - 1)
    out_n, out_a = [], []
    for b in range(bins):
        sel = idx == b
        if np.count_nonzero(sel) >= 3:
            out_n.append(float(np.median(n[sel])))
            out_a.append(float(np.median(a[sel])))
    return np.array(out_n), np.array(out_a)


__all__ = [
    "binned",
    "curve_changes",
    "curve_figures",
    "curve_fit",
    "curve_series",
    "fit_curve",
    "measured_accel",
]
