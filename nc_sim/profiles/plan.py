"""Setpoint plans: exact piecewise-jerk segments for velocity changes and position moves.

A plan is a list of segments, each `(duration T, start acceleration a0, mean jerk j, shape)`;
acceleration goes from a0 to a0 + j·T over the segment, linearly (shape 0: step-shaped and
trapezoidal profiles) or as sin² (shape 1: the sine-square profile [002 §2.2.3]). Position and
velocity carry over from segment to segment, so the kernel samples the continuous profile
exactly at every cycle.

Velocity change (v0, a0) -> v1 [002 §2.2.2]: acceleration built up over tr_zu to at most a,
held, and reduced over tr_ab; a ramp time of 0 (or below one cycle) is a step.
Position move: velocity change to a peak speed, cruise, velocity change to rest; the peak speed
is the largest one (≤ v_max) whose braking still ends on the target, found by bisection.
From rest to rest this is the time-optimal third-order profile.

All functions are numba-compiled so the kernel can re-plan inside the cycle loop.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# --- segment table columns ---------------------------------------------------------------
SEG_T = 0
SEG_A0 = 1
SEG_J = 2
SEG_SHAPE = 3
SEG_COLS = 4
MAX_SEGMENTS = 12

SHAPE_LINEAR = 0.0
SHAPE_SIN2 = 1.0

# --- dynamic limits of one plan (a row of the `lim` array) -----------------------------------
LIM_A_ACC = 0  # acceleration while |v| grows
LIM_A_DEC = 1  # deceleration while |v| falls
LIM_TR_ACC_UP = 2  # ramp time building up acceleration (s), 0 = step
LIM_TR_ACC_DOWN = 3
LIM_TR_DEC_UP = 4
LIM_TR_DEC_DOWN = 5
LIM_SHAPE = 6  # SHAPE_LINEAR or SHAPE_SIN2
LIM_A_ACC2 = 7  # step-shaped, second stage above LIM_V12 (0 = single stage)
LIM_A_DEC2 = 8
LIM_V12 = 9
LIM_COLS = 10

_INV_PI2 = 1.0 / (math.pi * math.pi)


@njit(cache=True)
def seg_eval(
    p: float, v: float, a0: float, j: float, shape: float, T: float, tau: float
) -> tuple[float, float, float]:
    """Position, velocity and acceleration `tau` seconds into a segment starting at (p, v)."""
    if shape == SHAPE_SIN2 and T > 0.0:
        da = j * T
        w = math.pi / T
        s = math.sin(0.5 * w * tau)
        a = a0 + da * s * s
        v1 = v + a0 * tau + da * (0.5 * tau - math.sin(w * tau) / (2.0 * w))
        p1 = (
            p
            + v * tau
            + 0.5 * a0 * tau * tau
            + da * (0.25 * tau * tau + T * T * 0.5 * _INV_PI2 * (math.cos(w * tau) - 1.0))
        )
        return p1, v1, a
    return (
        p + v * tau + 0.5 * a0 * tau * tau + j * tau * tau * tau / 6.0,
        v + a0 * tau + 0.5 * j * tau * tau,
        a0 + j * tau,
    )


@njit(cache=True)
def _push(seg: np.ndarray, k: int, T: float, a0: float, j: float, shape: float) -> int:
    if T <= 1e-12:  # drop rounding slivers
        return k
    if k >= seg.shape[0]:
        raise ValueError("plan has more segments than MAX_SEGMENTS")
    seg[k, SEG_T] = T
    seg[k, SEG_A0] = a0
    seg[k, SEG_J] = j
    seg[k, SEG_SHAPE] = shape
    return k + 1


@njit(cache=True)
def _jerk(a: float, tr: float, cycle_s: float) -> float:
    """Jerk a/tr; ramp times shorter than one cycle degrade to a step (infinite jerk)."""
    if tr < cycle_s or tr <= 0.0:
        return math.inf
    return a / tr


@njit(cache=True)
def _step_change(
    seg: np.ndarray, k: int, v0: float, v1: float, a1: float, a2: float, v12: float
) -> int:
    """Step-shaped change within one sign: a1 while |v| < v12, a2 above (a2 = 0: one stage)."""
    s = 1.0 if v1 >= v0 else -1.0
    if a2 <= 0.0 or v12 <= 0.0:
        return _push(seg, k, abs(v1 - v0) / a1, s * a1, 0.0, SHAPE_LINEAR)
    m0, m1 = abs(v0), abs(v1)
    lo_m, hi_m = min(m0, m1), max(m0, m1)
    below = max(0.0, min(hi_m, v12) - lo_m)  # part of the change under the changeover speed
    above = (hi_m - lo_m) - below
    if m1 > m0:
        k = _push(seg, k, below / a1, s * a1, 0.0, SHAPE_LINEAR)
        return _push(seg, k, above / a2, s * a2, 0.0, SHAPE_LINEAR)
    k = _push(seg, k, above / a2, s * a2, 0.0, SHAPE_LINEAR)
    return _push(seg, k, below / a1, s * a1, 0.0, SHAPE_LINEAR)


@njit(cache=True)
def velocity_change(
    seg: np.ndarray, k: int, v0: float, a0: float, v1: float, lim: np.ndarray, cycle_s: float
) -> int:
    """Append segments that take (v0, a0) to (v1, 0); returns the new segment count."""
    if v0 * v1 < 0.0:  # through zero: brake with the braking set, then accelerate
        k = _change_one_sign(seg, k, v0, a0, 0.0, lim, cycle_s)
        return _change_one_sign(seg, k, 0.0, 0.0, v1, lim, cycle_s)
    return _change_one_sign(seg, k, v0, a0, v1, lim, cycle_s)


@njit(cache=True)
def _change_one_sign(
    seg: np.ndarray, k: int, v0: float, a0: float, v1: float, lim: np.ndarray, cycle_s: float
) -> int:
    speeding_up = abs(v1) > abs(v0)
    if speeding_up:
        a_max = lim[LIM_A_ACC]
        a_2 = lim[LIM_A_ACC2]
        j_up = _jerk(a_max, lim[LIM_TR_ACC_UP], cycle_s)
        j_dn = _jerk(a_max, lim[LIM_TR_ACC_DOWN], cycle_s)
    else:
        a_max = lim[LIM_A_DEC]
        a_2 = lim[LIM_A_DEC2]
        j_up = _jerk(a_max, lim[LIM_TR_DEC_UP], cycle_s)
        j_dn = _jerk(a_max, lim[LIM_TR_DEC_DOWN], cycle_s)
    if math.isinf(j_up) and math.isinf(j_dn):
        return _step_change(seg, k, v0, v1, a_max, a_2, lim[LIM_V12])
    shape = lim[LIM_SHAPE]
    inv_up = 0.0 if math.isinf(j_up) else 0.5 / j_up
    inv_dn = 0.0 if math.isinf(j_dn) else 0.5 / j_dn
    # speed reached if acceleration were reduced to zero right now
    v_free = v0 + a0 * abs(a0) * inv_dn
    if abs(v1 - v_free) < 1e-12 and abs(a0) > 0.0:
        T3 = 0.0 if math.isinf(j_dn) else abs(a0) / j_dn
        sgn = 1.0 if a0 > 0.0 else -1.0
        return _push(seg, k, T3, a0, -sgn * (j_dn if T3 > 0 else 0.0), shape)
    s = 1.0 if v1 > v_free else -1.0
    need = s * (v1 - v0)  # signed speed change along s
    a_lim = max(a_max, abs(a0)) if a0 * s > 0.0 else a_max
    t_hold = (need - (a_lim * a_lim - a0 * a0) * inv_up - a_lim * a_lim * inv_dn) / a_lim
    if t_hold >= 0.0:
        a_p = a_lim
    else:
        t_hold = 0.0
        a_p = math.sqrt(max(0.0, (need + a0 * a0 * inv_up) / (inv_up + inv_dn)))
    # segment 1: a0 -> s·a_p
    da = s * a_p - a0
    if math.isinf(j_up):
        a_start = s * a_p
    else:
        T1 = abs(da) / j_up
        k = _push(seg, k, T1, a0, da / T1 if T1 > 0.0 else 0.0, shape)
        a_start = s * a_p
    k = _push(seg, k, t_hold, a_start, 0.0, shape)
    if math.isinf(j_dn):
        return k
    T3 = a_p / j_dn
    return _push(seg, k, T3, s * a_p, -s * j_dn, shape)


@njit(cache=True)
def plan_distance(seg: np.ndarray, k0: int, k1: int, v0: float) -> tuple[float, float]:
    """Distance covered and final speed of segments k0..k1-1 starting at speed v0."""
    p = 0.0
    v = v0
    for k in range(k0, k1):
        p, v, _a = seg_eval(
            p, v, seg[k, SEG_A0], seg[k, SEG_J], seg[k, SEG_SHAPE], seg[k, SEG_T], seg[k, SEG_T]
        )
    return p, v


@njit(cache=True)
def plan_duration(seg: np.ndarray, n: int) -> float:
    """Total duration of the first n segments."""
    t = 0.0
    for k in range(n):
        t += seg[k, SEG_T]
    return t


@njit(cache=True)
def _move_distance(
    seg: np.ndarray,
    v0: float,
    a0: float,
    vp: float,
    lim: np.ndarray,
    cycle_s: float,
    v_end: float = 0.0,
) -> float:
    """Distance of (v0, a0) -> peak vp -> (v_end, 0), without a cruise."""
    k = velocity_change(seg, 0, v0, a0, vp, lim, cycle_s)
    k2 = velocity_change(seg, k, vp, 0.0, v_end, lim, cycle_s)
    d, _v = plan_distance(seg, 0, k2, v0)
    return d


@njit(cache=True)
def position_move(
    seg: np.ndarray,
    p0: float,
    v0: float,
    a0: float,
    p1: float,
    v_max: float,
    lim: np.ndarray,
    cycle_s: float,
) -> int:
    """Fill `seg` with a move from (p0, v0, a0) to rest at p1; returns the segment count.

    With v_max = 0 the plan only brakes to standstill (override 0 %, feedhold).
    """
    k_stop = velocity_change(seg, 0, v0, a0, 0.0, lim, cycle_s)
    d_stop, _v = plan_distance(seg, 0, k_stop, v0)
    dist = p1 - (p0 + d_stop)
    if v_max <= 0.0 or abs(dist) < 1e-12:
        return k_stop
    d = 1.0 if dist > 0.0 else -1.0
    if v0 * d < 0.0 or (v0 == 0.0 and a0 * d < 0.0):
        # moving away from the target: stop first, then a move from rest
        return _move_toward(seg, k_stop, 0.0, 0.0, dist, v_max, lim, cycle_s)
    return _move_toward(seg, 0, v0, a0, p1 - p0, v_max, lim, cycle_s)


@njit(cache=True)
def _move_toward(
    seg: np.ndarray,
    k0: int,
    v0: float,
    a0: float,
    need: float,
    v_max: float,
    lim: np.ndarray,
    cycle_s: float,
) -> int:
    """Segments from index k0: reach a peak speed towards the target, cruise, brake to rest."""
    d = 1.0 if need > 0.0 else -1.0
    scratch = np.empty_like(seg)
    d_full = _move_distance(scratch, v0, a0, d * v_max, lim, cycle_s)
    if (d_full - need) * d <= 0.0:
        k = velocity_change(seg, k0, v0, a0, d * v_max, lim, cycle_s)
        k = _push(seg, k, (need - d_full) / (d * v_max), 0.0, 0.0, SHAPE_LINEAR)
        return velocity_change(seg, k, d * v_max, 0.0, 0.0, lim, cycle_s)
    lo = 0.0
    hi = v_max
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        if (_move_distance(scratch, v0, a0, d * mid, lim, cycle_s) - need) * d <= 0.0:
            lo = mid
        else:
            hi = mid
    k = velocity_change(seg, k0, v0, a0, d * lo, lim, cycle_s)
    d_lo = _move_distance(scratch, v0, a0, d * lo, lim, cycle_s)
    if lo > 0.0:  # absorb the last rounding residue in a tiny cruise
        k = _push(seg, k, (need - d_lo) / (d * lo), 0.0, 0.0, SHAPE_LINEAR)
    return velocity_change(seg, k, d * lo, 0.0, 0.0, lim, cycle_s)


def new_plan() -> np.ndarray:
    """An empty segment table for one plan."""
    return np.zeros((MAX_SEGMENTS, SEG_COLS))


def make_limits(
    a_acc: float,
    a_dec: float,
    tr_acc_up: float = 0.0,
    tr_acc_down: float = 0.0,
    tr_dec_up: float = 0.0,
    tr_dec_down: float = 0.0,
    shape: float = SHAPE_LINEAR,
    a_acc2: float = 0.0,
    a_dec2: float = 0.0,
    v12: float = 0.0,
) -> np.ndarray:
    """A limits row for the planner (accelerations in unit/s², ramp times in s)."""
    lim = np.zeros(LIM_COLS)
    lim[LIM_A_ACC] = a_acc
    lim[LIM_A_DEC] = a_dec
    lim[LIM_TR_ACC_UP] = tr_acc_up
    lim[LIM_TR_ACC_DOWN] = tr_acc_down
    lim[LIM_TR_DEC_UP] = tr_dec_up
    lim[LIM_TR_DEC_DOWN] = tr_dec_down
    lim[LIM_SHAPE] = shape
    lim[LIM_A_ACC2] = a_acc2
    lim[LIM_A_DEC2] = a_dec2
    lim[LIM_V12] = v12
    return lim


@njit(cache=True)
def change_distance(
    scratch: np.ndarray, v0: float, a0: float, v1: float, lim: np.ndarray, cycle_s: float
) -> float:
    """Distance a velocity change (v0, a0) -> (v1, 0) covers."""
    k = velocity_change(scratch, 0, v0, a0, v1, lim, cycle_s)
    d, _v = plan_distance(scratch, 0, k, v0)
    return d


@njit(cache=True)
def speed_within(
    dist: float, v_from: float, v_cap: float, braking: bool, lim: np.ndarray, cycle_s: float
) -> float:
    """The highest speed v ≤ v_cap (all speeds ≥ 0) that can still brake to v_from within
    `dist` (braking), or that can be reached from v_from at rest acceleration within `dist`."""
    scratch = np.zeros((MAX_SEGMENTS, SEG_COLS))

    def fits(v: float) -> bool:
        if braking:
            return change_distance(scratch, v, 0.0, v_from, lim, cycle_s) <= dist
        return change_distance(scratch, v_from, 0.0, v, lim, cycle_s) <= dist

    if v_cap <= v_from or fits(v_cap):
        return max(v_cap, 0.0) if v_cap > v_from else v_cap
    lo = v_from
    hi = v_cap
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if fits(mid):
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def move_through(
    seg: np.ndarray,
    k0: int,
    v0: float,
    a0: float,
    dist: float,
    v_cap: float,
    v_end: float,
    lim: np.ndarray,
    cycle_s: float,
) -> tuple[int, float]:
    """Append segments covering `dist` (> 0) from (v0 ≥ 0, a0) to (v_end, 0) with a peak or
    cruise speed ≤ v_cap: the fastest such profile. Returns (segment count, end speed): the
    end speed is below v_end when v_end cannot be reached within `dist`; when braking from v0
    to v_end needs more than `dist`, the profile brakes as planned and runs past `dist` (the
    caller's look-ahead keeps that from happening)."""
    scratch = np.zeros((MAX_SEGMENTS, SEG_COLS))
    d_direct = change_distance(scratch, v0, a0, v_end, lim, cycle_s)
    if d_direct > dist:
        if v_end > v0:  # cannot reach v_end: accelerate as far as the distance allows
            lo, hi = v0, v_end
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if change_distance(scratch, v0, a0, mid, lim, cycle_s) <= dist:
                    lo = mid
                else:
                    hi = mid
            return velocity_change(seg, k0, v0, a0, lo, lim, cycle_s), lo
        return velocity_change(seg, k0, v0, a0, v_end, lim, cycle_s), v_end

    def through(vp: float) -> float:
        return _move_distance(scratch, v0, a0, vp, lim, cycle_s, v_end)

    lo = min(max(v_end, 0.0), v_cap)
    hi = v_cap
    if through(hi) <= dist:
        lo = hi
    else:
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if through(mid) <= dist:
                lo = mid
            else:
                hi = mid
    k = velocity_change(seg, k0, v0, a0, lo, lim, cycle_s)
    d_used = through(lo)
    if lo > 1e-9 and dist - d_used > 0.0:  # cruise the rest
        k = _push(seg, k, (dist - d_used) / lo, 0.0, 0.0, SHAPE_LINEAR)
    return velocity_change(seg, k, lo, 0.0, v_end, lim, cycle_s), v_end
