"""Bounds for sequences: how long a phase may take before it ends in a job error (90023).

Every phase of a sequence (a move or jog, a speed change, a homing phase, M19, a gear change,
waiting for the PLC) gets a bound from its own parameters: the duration of its setpoint plan,
the distance to search at the search speed, or the acknowledgement timeout. The bound adds a
margin for what the plan does not contain (settling into the exact-stop window, the loop's
lag 1/kv, the drive), so a healthy sequence never meets it and a stuck one always does.

A curve-controlled speed change has no plan: its duration is the integral of dn / a(n) from
the current to the target speed. A curve that gives no usable acceleration somewhere on the
way (below 1 °/s² or not finite, e.g. coefficients of 1e308) could never get there; that is
refused before the change starts (90024) instead of waiting for the bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nc_sim.accel_curve import CurveParams
from nc_sim.profiles.plan import plan_duration

MARGIN_FACTOR = 2.0  # the bound is at least twice the expected duration ...
MARGIN_S = 1.0  # ... plus one second for settling, lag and the drive


def bound_s(expected_s: float) -> float:
    """The watchdog bound (s) of a phase expected to take `expected_s` seconds."""
    return MARGIN_FACTOR * max(expected_s, 0.0) + MARGIN_S


def plan_s(seg: np.ndarray, n: int) -> float:
    """Duration (s) of a setpoint plan of n segments."""
    return float(plan_duration(seg, n))


def search_s(distance: float, speed: float) -> float:
    """Time (s) to cover `distance` at `speed` (a homing search); inf when it cannot move."""
    if speed <= 0.0 or not math.isfinite(distance):
        return math.inf
    return abs(distance) / speed


@dataclass(frozen=True)
class CurveTime:
    """Duration (s) of a curve-controlled speed change, or the speed (°/s) where the curve
    gives no usable acceleration (then `seconds` is inf)."""

    seconds: float
    dead_speed: float | None = None


def curve_s(curve: CurveParams, v_from: float, v_to: float) -> CurveTime:
    """Integral of dn / a(n) from v_from to v_to (°/s, signed), the slowest end of every
    sub-interval taken, so the result is an upper estimate of the kernel's ramp."""
    if v_from == v_to:
        return CurveTime(0.0)
    dead = curve.dead_speed(v_from, v_to)
    if dead is not None:
        return CurveTime(math.inf, dead)
    speeds = curve.speeds(v_from, v_to)
    accel = [curve.accel(float(n)) for n in speeds]
    t = 0.0
    for k in range(1, len(speeds)):
        t += abs(float(speeds[k] - speeds[k - 1])) / min(accel[k], accel[k - 1])
    return CurveTime(t)
