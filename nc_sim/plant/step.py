"""The drive cascade and mechanics, one drive step (compiled; the NC cycle steps it).

Per drive step Ts (model and matrices: nc_sim/plant/model.py):

    w_ref  = PT1(speed setpoint)                            [+ excitation at the speed]
    T      = Kp·(e + I/Tn),  e = w_ref - w_motor,  I += e·Ts  [+ excitation at the torque]
             limited to ±T_max; the integral stands still while the limit holds (anti-windup)
    x'     = Ad·x + Bd·(T of the previous step, friction, backlash correction)

Friction is implicit: the linear step is taken without it, then the friction torque is the
one that stops the load exactly within this step if that needs no more than the breakaway
(Stribeck) torque at its speed (it sticks), else that torque against the motion. So a load
at rest stays at rest below breakaway, with no creep and no chatter, at any step size.
Backlash in a two-mass plant: inside the gap the correction input cancels the spring's
torque (stiffness and damping); at either end the spring pushes by the deflection past it.
A rigid plant's backlash is a kinematic gap between motor and load.

The drive trace samples speeds, torque and positions at the start of each drive step (when
the controller reads them) beside the setpoints the controller formed from them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from nc_sim.plant.layout import (
    D_T_SET,
    D_TORQUE,
    D_W_LOAD,
    D_W_MOTOR,
    D_W_REF,
    D_W_SET,
    D_X_LOAD,
    D_X_MOTOR,
    INJECT_SPEED,
    INJECT_SPEED_OPEN,
    INJECT_TORQUE,
    NU,
    NX_MAX,
    PL_AD,
    PL_BD,
    PL_BREAKAWAY,
    PL_COULOMB,
    PL_D,
    PL_HALF_PLAY,
    PL_INV_TN,
    PL_K,
    PL_KP,
    PL_NX,
    PL_SP_ALPHA,
    PL_STRIBECK,
    PL_T_MAX,
    PL_TWO_MASS,
    PL_UNIT_PER_RAD,
    PR_COUNT,
    PR_LEN,
    PR_POINT,
    PR_POS,
    PR_SLOT,
    PR_WRAP,
    PS_INTEGRAL,
    PS_NEXT,
    PS_T_LATE,
    PS_W_REF,
    U_FRICTION,
    U_PLAY,
    U_TORQUE,
    X_DEF,
    X_TORQUE,
    X_TRAVEL,
    X_WL,
    X_WM,
)


@njit(cache=True)
def motor_offset(pl: np.ndarray, ps: np.ndarray, s: int, play: float) -> float:
    """How far the motor is ahead of the load, in load units: the coupling's deflection of a
    two-mass plant, the gap's position of a rigid one."""
    if pl[s, PL_TWO_MASS] == 1.0:
        return float(ps[s, X_DEF] * pl[s, PL_UNIT_PER_RAD])
    return play


@njit(cache=True)
def _brake(pl: np.ndarray, ps: np.ndarray, s: int) -> float:
    """No enables: no torque, the holding brake stops the motor, and the load comes to rest
    where the coupling holds no torque (within the backlash gap). Returns how far the load
    moved settling (load units)."""
    for i in range(NX_MAX):
        if i != X_DEF:
            ps[s, i] = 0.0
    ps[s, PS_INTEGRAL] = 0.0
    ps[s, PS_T_LATE] = 0.0
    ps[s, PS_W_REF] = 0.0
    half = pl[s, PL_HALF_PLAY] if pl[s, PL_TWO_MASS] == 1.0 else 0.0
    de = ps[s, X_DEF]
    rest = min(max(de, -half), half)
    ps[s, X_DEF] = rest
    return float((de - rest) * pl[s, PL_UNIT_PER_RAD])


@njit(cache=True)
def _friction(pl: np.ndarray, ps: np.ndarray, s: int, wi: int) -> None:
    """Add the friction torque's effect to the step in PS_NEXT (see the module docstring)."""
    coulomb = pl[s, PL_COULOMB]
    breakaway = pl[s, PL_BREAKAWAY]
    if breakaway <= 0.0:
        return
    nx = int(pl[s, PL_NX])
    w0 = ps[s, wi]
    ratio = w0 / pl[s, PL_STRIBECK]
    f = coulomb + (breakaway - coulomb) * math.exp(-ratio * ratio)
    beta = pl[s, PL_BD + wi * NU + U_FRICTION]
    w_free = ps[s, PS_NEXT + wi]
    # it sticks (exactly at rest after this step) when that takes no more than f
    tf = -w_free / beta if abs(w_free) <= beta * f else (-f if w_free > 0.0 else f)
    for r in range(nx):
        ps[s, PS_NEXT + r] += pl[s, PL_BD + r * NU + U_FRICTION] * tf


@njit(cache=True, inline="always")
def drive_step(
    pl: np.ndarray,
    ps: np.ndarray,
    probe: np.ndarray,
    pexc: np.ndarray,
    prec: np.ndarray,
    s: int,
    w_set: float,
    enabled: bool,
    x_load: float,
    play: float,
    ts: float,
) -> tuple[float, float]:
    """Run slot s's drive and mechanics over one drive step ts with the speed setpoint w_set
    (rad/s at the motor). `x_load` is the load's position and `play` where a rigid plant's
    gap stands (load units). Returns the new load position and gap. A probe on this slot
    adds its excitation and records this step's trace row."""
    nx = int(pl[s, PL_NX])
    g = pl[s, PL_UNIT_PER_RAD]
    two = pl[s, PL_TWO_MASS] == 1.0
    half = pl[s, PL_HALF_PLAY]
    kp, inv_tn, lim = pl[s, PL_KP], pl[s, PL_INV_TN], pl[s, PL_T_MAX]
    wi = X_WL if two else X_WM
    pos = probe[PR_POS]
    probing = probe[PR_SLOT] == s and pos < probe[PR_LEN]
    exc = pexc[pos] if probing else 0.0
    at_speed = probe[PR_POINT] == INJECT_SPEED or probe[PR_POINT] == INJECT_SPEED_OPEN
    t = 0.0
    w_ref = 0.0
    if probing:  # the samples of this instant
        prec[pos, D_W_SET] = w_set
        prec[pos, D_W_MOTOR] = ps[s, X_WM]
        prec[pos, D_W_LOAD] = ps[s, wi]
        prec[pos, D_TORQUE] = ps[s, X_TORQUE]
        prec[pos, D_X_LOAD] = x_load
        prec[pos, D_X_MOTOR] = x_load + motor_offset(pl, ps, s, play)
    if not enabled:
        x_load += _brake(pl, ps, s)
    else:
        ps[s, PS_W_REF] += (w_set - ps[s, PS_W_REF]) * pl[s, PL_SP_ALPHA]
        w_ref = ps[s, PS_W_REF]
        if probing and at_speed:
            w_ref += exc
        e = w_ref - ps[s, X_WM]
        integral = ps[s, PS_INTEGRAL] + e * ts
        t = kp * (e + inv_tn * integral)
        if probing and probe[PR_POINT] == INJECT_TORQUE:
            t += exc
        if t > lim:
            t = lim
        elif t < -lim:
            t = -lim
        else:
            ps[s, PS_INTEGRAL] = integral
        c = 0.0  # backlash correction
        if two and half > 0.0:
            de = ps[s, X_DEF]
            if de > half:
                c = pl[s, PL_K] * half
            elif de < -half:
                c = -pl[s, PL_K] * half
            else:
                c = pl[s, PL_K] * de + pl[s, PL_D] * (ps[s, X_WM] - ps[s, X_WL])
        t_late = ps[s, PS_T_LATE]
        for r in range(nx):
            acc = pl[s, PL_BD + r * NU + U_TORQUE] * t_late + pl[s, PL_BD + r * NU + U_PLAY] * c
            row = PL_AD + r * NX_MAX
            for q in range(nx):
                acc += pl[s, row + q] * ps[s, q]
            ps[s, PS_NEXT + r] = acc
        _friction(pl, ps, s, wi)
        for r in range(nx):
            ps[s, r] = ps[s, PS_NEXT + r]
        ps[s, PS_T_LATE] = t
    if probing:  # what the controller made of them
        prec[pos, D_W_REF] = w_ref
        prec[pos, D_T_SET] = t
        nxt = pos + 1
        probe[PR_POS] = 0 if nxt == probe[PR_LEN] and probe[PR_WRAP] == 1 else nxt
        probe[PR_COUNT] += 1
    dx = ps[s, X_TRAVEL] * g
    ps[s, X_TRAVEL] = 0.0
    if not two and half > 0.0:  # rigid: the load moves only at either end of the gap
        play += dx
        if play > half:
            x_load += play - half
            play = half
        elif play < -half:
            x_load += play + half
            play = -half
    else:
        x_load += dx
    return x_load, play


@njit(cache=True)
def load_speed(pl: np.ndarray, ps: np.ndarray, s: int) -> float:
    """The load's speed (unit/s)."""
    wi = X_WL if pl[s, PL_TWO_MASS] == 1.0 else X_WM
    return float(ps[s, wi] * pl[s, PL_UNIT_PER_RAD])
