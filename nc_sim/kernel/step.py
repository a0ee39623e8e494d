"""The compiled cycle: setpoint, position loop, drive, encoder and monitors for every slot.

`run_cycles` advances all slots by up to `n` cycles in one call and returns early, after the
cycle in which any slot raised an event, so the Python layer reacts within the same cycle.
One axis, one cycle [DOMAIN §2]:

    setpoint plan -> p_cmd, v_cmd, a_cmd
    encoder: x (where the last cycle left the load) × factor + seeded noise, quantised to
             one increment, sign(vz_istw) -> p_act;  lag = p_cmd - p_act (the one lag)
    u  = kv·lag + ff·v_cmd                          (P controller + velocity feedforward)
    da = u · 0.06 · multi_gain · sign(vz_stellgr)   (digits for 1 m/min or 1000 °/min), clipped
    drive: v_motor -> da / (0.06 · true gain), less Coulomb friction, as a first-order lag
           with acceleration limit, moving the load x over the cycle (through any backlash)

With `sim.plant` DRIVE_CASCADE the drive line is nc_sim/plant's cascade and mechanics at the
drive's own rate instead, and the encoder reads the motor or the load (the measuring system).
The encoder factor, noise, friction and backlash are the plant's training faults
(nc_sim/axis/plant.py); a sound plant has 1, 0, 0, 0 and runs exactly as without them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from nc_sim.kernel.curve import curve_accel
from nc_sim.kernel.layout import (
    COUPLE_TAP,
    E_ARC,
    E_CX,
    E_CY,
    E_DIR,
    E_DPHI,
    E_I0,
    E_I1,
    E_K,
    E_KIND,
    E_LEN,
    E_LIN,
    E_LINE,
    E_P0,
    E_PHI0,
    E_PHI_IN,
    E_PHI_OUT,
    E_PHI_TOT,
    E_R,
    E_S0,
    E_SPDL,
    E_TH0,
    EV_BLOCK,
    EV_CAM,
    EV_IN_POS,
    EV_LAG,
    EV_LOOP,
    EV_PLAN_DONE,
    EV_SPEED_REACHED,
    EV_SWLIMIT,
    I_CAM,
    I_CURVE,
    I_ENABLED,
    I_EVENTS,
    I_GEAR,
    I_HOMED,
    I_IN_POS,
    I_JOB_ERROR,
    I_LIMITS_ON,
    I_LINE,
    I_MARK_ARMED,
    I_MON_ACTIVE,
    I_MON_INVALID,
    I_NOISE_STATE,
    I_OPEN_LOOP,
    I_PLAN_K,
    I_PLAN_N,
    I_ROLE,
    I_ROTARY_MODE,
    I_SPEED_CTRL_ARMED,
    I_SPEED_REACHED,
    I_STATE,
    I_STOPPED,
    LOOP_CLOSED,
    LOOP_CONTROL_LIMIT,
    LOOP_SPEED_CONTROL,
    P_A_CAP,
    P_A_KONST,
    P_A_MIN,
    P_B1,
    P_B2,
    P_B3,
    P_BACKLASH,
    P_CAM_POS,
    P_CURVE_A_MAX,
    P_CURVE_TYPE,
    P_DA_MAX,
    P_DRV_A_MAX,
    P_DRV_ALPHA,
    P_DRV_GAIN,
    P_ENC_FACTOR,
    P_ENC_INC,
    P_ENC_NOISE,
    P_ENC_OFFSET,
    P_ENC_SIGN,
    P_FF,
    P_FRICTION,
    P_INPOS_WIN,
    P_KV,
    P_LAG_MAX,
    P_MG,
    P_MODULO,
    P_MOTOR_SIGN,
    P_N1,
    P_N2,
    P_N_LIMIT,
    P_SENSORLESS,
    P_SIGN_CMD,
    P_SIGN_FB,
    P_SPEED_BAND,
    P_SWE_NEG,
    P_SWE_POS,
    P_V_CTRL_LIMIT,
    P_V_RESO,
    P_V_SPEED_CTRL,
    P_V_ZERO,
    PI_AX0,
    PI_COUNT,
    PI_HEAD,
    PI_NAX,
    PI_SLOT,
    R_A_CMD,
    R_DA,
    R_GEAR,
    R_HOMED,
    R_IN_POS,
    R_JOB_ERROR,
    R_LAG,
    R_LINE,
    R_MON_ACTIVE,
    R_MON_INVALID,
    R_MVNEG,
    R_MVPOS,
    R_OPEN_LOOP,
    R_OVERRIDE,
    R_P_ACT,
    R_P_CMD,
    R_P_TRUE,
    R_READY,
    R_ROTARY_MODE,
    R_SPEED_REACHED,
    R_STATE,
    R_STOPPED,
    R_V_ACT,
    R_V_CMD,
    ROLE_AXIS,
    ROLE_CHANNEL,
    ROLE_PATH_AXIS,
    S_A_CMD,
    S_DA,
    S_LAG,
    S_LAG_MODEL,
    S_MAN_A,
    S_MAN_P,
    S_MAN_TARGET,
    S_MAN_V,
    S_OVERRIDE,
    S_P_ACT,
    S_P_CMD,
    S_P_TRUE,
    S_PLAY,
    S_SEG_P0,
    S_SEG_TAU,
    S_SEG_V0,
    S_TARGET,
    S_U,
    S_V_ACT,
    S_V_CMD,
    S_V_GOAL,
    S_V_MODEL,
    S_V_MOTOR,
    S_V_TARGET,
    S_X_MOTOR,
)
from nc_sim.plant.layout import (
    D_P_ACT,
    D_P_REF,
    INJECT_POSITION,
    INJECT_SPEED_OPEN,
    MODEL_CASCADE,
    PL_DIRECT,
    PL_MODEL,
    PL_POS_IN_DRIVE,
    PL_SUBSTEPS,
    PL_UNIT_PER_RAD,
    PR_LEN,
    PR_POINT,
    PR_POS,
    PR_SLOT,
)
from nc_sim.plant.step import drive_step, load_speed, motor_offset
from nc_sim.profiles.plan import SEG_A0, SEG_J, SEG_SHAPE, SEG_T, seg_eval

V_ACT_FILTER_S = 0.005  # time constant of the actual-speed filter
PER_M_MIN = 0.06  # 1 m/min = 1000 mm / 60 s, so digits = u[mm/s] · 0.06 · multi_gain


@njit(cache=True)
def _advance_curve(st: np.ndarray, pr: np.ndarray, ist: np.ndarray, s: int, dt: float) -> int:
    """Speed change of an endlessly rotating spindle along its acceleration curve a(n).

    The acceleration is the curve's at the speed at the start of the cycle (never above the
    cap), so the speed never gains more than a(n)·dt in a cycle; returns EV_PLAN_DONE at the
    target speed.
    """
    v = st[s, S_V_CMD]
    goal = st[s, S_V_TARGET]
    a = curve_accel(
        int(pr[s, P_CURVE_TYPE]),
        v,
        pr[s, P_N_LIMIT],
        pr[s, P_A_KONST],
        pr[s, P_B1],
        pr[s, P_B2],
        pr[s, P_B3],
        pr[s, P_A_MIN],
        pr[s, P_CURVE_A_MAX],
        pr[s, P_N1],
        pr[s, P_N2],
    )
    a = min(a, pr[s, P_A_CAP])
    step = a * dt
    dv = min(max(goal - v, -step), step)
    v_new = v + dv
    st[s, S_P_CMD] += 0.5 * (v + v_new) * dt
    st[s, S_V_CMD] = v_new
    st[s, S_A_CMD] = dv / dt
    if v_new == goal:
        ist[s, I_CURVE] = 0
        st[s, S_A_CMD] = 0.0
        return EV_PLAN_DONE
    return 0


@njit(cache=True)
def _advance_plan(
    st: np.ndarray, ist: np.ndarray, plan: np.ndarray, s: int, dt: float, out: int, tcol: int
) -> int:
    """Move slot s by dt along its plan (segment rows `plan`), writing position, velocity and
    acceleration to the columns from `out` on (S_P_CMD, or S_MAN_P for a G201 manual motion)
    with its target in `tcol`; EV_PLAN_DONE when it ends."""
    n = ist[s, I_PLAN_N]
    left = dt
    k = ist[s, I_PLAN_K]
    while True:
        T = plan[k, SEG_T]
        tau = st[s, S_SEG_TAU]
        a0 = plan[k, SEG_A0]
        j = plan[k, SEG_J]
        shape = plan[k, SEG_SHAPE]
        if tau + left < T:
            tau += left
            p, v, a = seg_eval(st[s, S_SEG_P0], st[s, S_SEG_V0], a0, j, shape, T, tau)
            st[s, S_SEG_TAU] = tau
            st[s, out] = p
            st[s, out + 1] = v
            st[s, out + 2] = a
            return 0
        left -= T - tau
        p, v, a = seg_eval(st[s, S_SEG_P0], st[s, S_SEG_V0], a0, j, shape, T, T)
        k += 1
        st[s, S_SEG_P0] = p
        st[s, S_SEG_V0] = v
        st[s, S_SEG_TAU] = 0.0
        ist[s, I_PLAN_K] = k
        if k >= n:
            ist[s, I_PLAN_N] = 0
            target = st[s, tcol]
            if not math.isnan(target):  # position plan: end exactly on the target, at rest
                st[s, out] = target
                st[s, out + 1] = 0.0
            else:  # velocity plan: keep the final speed (a stop ends at 0, not at round-off)
                if abs(v) < 1e-9:
                    v = 0.0
                st[s, out] = p + v * left
                st[s, out + 1] = v
            st[s, out + 2] = 0.0
            return EV_PLAN_DONE


@njit(cache=True)
def _advance_setpoint(
    st: np.ndarray, pr: np.ndarray, ist: np.ndarray, seg: np.ndarray, s: int, dt: float
) -> int:
    """Move the setpoint of slot s by dt along its plan; returns EV_PLAN_DONE when it ends."""
    n = ist[s, I_PLAN_N]
    if n == 0 and ist[s, I_CURVE] == 1:
        return _advance_curve(st, pr, ist, s, dt)
    if n == 0:  # no plan: hold the commanded velocity
        st[s, S_P_CMD] += st[s, S_V_CMD] * dt
        st[s, S_A_CMD] = 0.0
        return 0
    return _advance_plan(st, ist, seg[s], s, dt, S_P_CMD, S_TARGET)


@njit(cache=True)
def _advance_coupled(
    st: np.ndarray, ist: np.ndarray, pel: np.ndarray, p: int, e: int, c: int
) -> int:
    """A spindle-coupled element: the path length u follows the spindle's actual angle.

    phi = dir · (angle - E_TH0) is the rotation since the coupling point, k the path length
    per degree. Tapping (G63): u = k·phi while the spindle runs its own position move; the
    element ends when the spindle is in position. Thread (G33): the path waits for phi = 0
    (the zero passage plus the offset), accelerates over E_PHI_IN degrees (u quadratic in phi),
    runs at u = k·(phi - PHI_IN/2) and brakes over E_PHI_OUT degrees to the end at E_PHI_TOT:
    u is a function of the angle alone, so every pass of a thread runs in the same groove.
    Sets the channel slot's length, speed and acceleration; EV_PLAN_DONE at the end.
    """
    spdl = int(pel[p, e, E_SPDL]) - 1
    d = pel[p, e, E_DIR]
    k = pel[p, e, E_K]
    length = pel[p, e, E_LEN]
    phi = d * (st[spdl, S_P_ACT] - pel[p, e, E_TH0])
    w = d * st[spdl, S_V_ACT]  # °/s along the thread
    alpha = d * st[spdl, S_A_CMD]
    du = 0.0  # du/dphi
    ddu = 0.0  # d²u/dphi²
    if int(pel[p, e, E_KIND]) == COUPLE_TAP:
        done = ist[spdl, I_PLAN_N] == 0 and ist[spdl, I_IN_POS] == 1
        u = min(max(k * phi, 0.0), length)
        if 0.0 < u < length:
            du = k
    else:
        f_in = pel[p, e, E_PHI_IN]
        f_out = pel[p, e, E_PHI_OUT]
        f_tot = pel[p, e, E_PHI_TOT]
        done = phi >= f_tot
        if phi <= 0.0:
            u = 0.0
        elif phi < f_in:
            u = k * phi * phi / (2.0 * f_in)
            du = k * phi / f_in
            ddu = k / f_in
        elif phi < f_tot - f_out:
            u = k * (phi - 0.5 * f_in)
            du = k
        else:
            r = f_tot - phi
            u = length - k * r * r / (2.0 * f_out)
            du = k * r / f_out
            ddu = -k / f_out
    ev = 0
    if done:  # at the end at rest, decoupled
        u, du, ddu = length, 0.0, 0.0
        pel[p, e, E_SPDL] = 0.0
        ev = EV_PLAN_DONE
    st[c, S_P_CMD] = pel[p, e, E_S0] + u
    st[c, S_V_CMD] = du * w
    st[c, S_A_CMD] = ddu * w * w + du * alpha
    return ev


@njit(cache=True)
def _advance_path(
    st: np.ndarray,
    ist: np.ndarray,
    seg: np.ndarray,
    pi: np.ndarray,
    pel: np.ndarray,
    pplan: np.ndarray,
    p: int,
    dt: float,
) -> tuple[int, int]:
    """Coupled path mode: advance path p's length along its plan (the channel slot) and set
    every path axis' command position, velocity and acceleration from the geometry element
    the length lies in, plus the axis' G201 manual offset (its own plan moves that).

    Returns the channel's events (EV_BLOCK on entering the next element, EV_PLAN_DONE when
    the plan ends with the path at rest) and 1 when an axis' manual motion ended (its slot
    has EV_PLAN_DONE)."""
    c = pi[p, PI_SLOT]
    if pi[p, PI_COUNT] == 0:
        return 0, 0
    ev = 0
    manual_done = 0
    head = pi[p, PI_HEAD]
    if pel[p, head, E_SPDL] > 0.0:
        ev |= _advance_coupled(st, ist, pel, p, head, c)
    elif ist[c, I_PLAN_N] > 0:
        ev |= _advance_plan(st, ist, pplan[p], c, dt, S_P_CMD, S_TARGET)
    s = st[c, S_P_CMD]
    while pi[p, PI_COUNT] > 1:
        e = pi[p, PI_HEAD]
        if s < pel[p, e, E_S0] + pel[p, e, E_LEN]:
            break
        pi[p, PI_HEAD] = (e + 1) % pel.shape[1]
        pi[p, PI_COUNT] -= 1
        ev |= EV_BLOCK
    e = pi[p, PI_HEAD]
    length = pel[p, e, E_LEN]
    u = min(max(s - pel[p, e, E_S0], 0.0), length)
    v = st[c, S_V_CMD]
    a = st[c, S_A_CMD]
    line = int(pel[p, e, E_LINE])
    ist[c, I_LINE] = line
    for i in range(pi[p, PI_NAX]):
        slot = pi[p, PI_AX0 + i]
        if ist[slot, I_ROLE] != ROLE_PATH_AXIS:
            continue  # not on the path now (a spindle in spindle mode)
        # G201: the axis' manual motion on top of the path
        manual = ist[slot, I_PLAN_N] > 0
        if manual and _advance_plan(st, ist, seg[slot], slot, dt, S_MAN_P, S_MAN_TARGET) != 0:
            ist[slot, I_EVENTS] |= EV_PLAN_DONE
            manual_done = 1
        lin = pel[p, e, E_LIN + i]
        st[slot, S_P_CMD] = pel[p, e, E_P0 + i] + lin * u
        st[slot, S_V_CMD] = lin * v
        st[slot, S_A_CMD] = lin * a
        ist[slot, I_LINE] = line
    if pel[p, e, E_ARC] == 1.0 and length > 0.0:
        r = pel[p, e, E_R]
        w = pel[p, e, E_DPHI] / length  # rad per unit of path length
        phi = pel[p, e, E_PHI0] + w * u
        cs = math.cos(phi)
        sn = math.sin(phi)
        s0 = pi[p, PI_AX0 + int(pel[p, e, E_I0])]
        s1 = pi[p, PI_AX0 + int(pel[p, e, E_I1])]
        st[s0, S_P_CMD] = pel[p, e, E_CX] + r * cs
        st[s1, S_P_CMD] = pel[p, e, E_CY] + r * sn
        # d/ds of the point: r·w·(-sin, cos); second derivative: -r·w²·(cos, sin)
        st[s0, S_V_CMD] = -r * w * sn * v
        st[s1, S_V_CMD] = r * w * cs * v
        st[s0, S_A_CMD] = -r * w * sn * a - r * w * w * cs * v * v
        st[s1, S_A_CMD] = r * w * cs * a - r * w * w * sn * v * v
    for i in range(pi[p, PI_NAX]):
        slot = pi[p, PI_AX0 + i]
        if ist[slot, I_ROLE] == ROLE_PATH_AXIS:
            st[slot, S_P_CMD] += st[slot, S_MAN_P]
            st[slot, S_V_CMD] += st[slot, S_MAN_V]
            st[slot, S_A_CMD] += st[slot, S_MAN_A]
    return ev, manual_done


@njit(cache=True)
def _xorshift(ist: np.ndarray, s: int) -> float:
    """The slot's next uniform number in (0, 1) from its xorshift32 state (Marsaglia 13/17/5,
    kept in 32 bits of the int64 column): deterministic, a state of its own per slot."""
    x = int(ist[s, I_NOISE_STATE])
    if x == 0:  # the generator's one fixed point: a zero state would never move
        x = 1
    x ^= (x << 13) & 0xFFFFFFFF
    x ^= x >> 17
    x ^= (x << 5) & 0xFFFFFFFF
    ist[s, I_NOISE_STATE] = x
    return (x + 0.5) / 4294967296.0


@njit(cache=True)
def _gauss(ist: np.ndarray, s: int) -> float:
    """A standard normal number from two uniform ones (Box-Muller)."""
    u1 = _xorshift(ist, s)
    u2 = _xorshift(ist, s)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@njit(cache=True)
def _encoder(
    st: np.ndarray,
    pr: np.ndarray,
    ist: np.ndarray,
    pl: np.ndarray,
    ps: np.ndarray,
    s: int,
    x_load: float,
    play: float,
) -> float:
    """The actual position the measuring system gives for the load at `x_load` (and the
    motor ahead of it where it reads the motor): factor, noise, one increment, sign and the
    homing offset, in NC coordinates."""
    x = x_load
    if pl[s, PL_MODEL] == MODEL_CASCADE and pl[s, PL_DIRECT] == 0.0:  # encoder on the motor
        x += motor_offset(pl, ps, s, play)
    x *= pr[s, P_ENC_FACTOR]
    if pr[s, P_ENC_NOISE] > 0.0:
        x += pr[s, P_ENC_NOISE] * _gauss(ist, s)
    inc = pr[s, P_ENC_INC]
    counts = x if inc <= 0.0 else math.floor(x / inc + 0.5) * inc
    return float(pr[s, P_ENC_SIGN] * pr[s, P_SIGN_FB] * counts + pr[s, P_ENC_OFFSET])


@njit(cache=True)
def _position_law(st: np.ndarray, pr: np.ndarray, s: int, lag: float) -> float:
    """The position controller and D/A for this lag: the speed it commands the drive
    (unit/s at the load, as the drive really turns for it). Writes S_U and S_DA.

    The controller works in measuring-system increments: a lag below half an increment
    cannot be measured, so it commands nothing. A settled P loop then rests inside the
    increment of its command instead of hunting across an increment edge it cannot resolve
    (the load coasts kv·T·inc after the last count, far less than one increment)."""
    inc = pr[s, P_ENC_INC]
    if inc > 0.0:
        lag = math.floor(lag / inc + 0.5) * inc
    u = pr[s, P_KV] * lag + pr[s, P_FF] * st[s, S_V_CMD]
    return _output(st, pr, s, u)


@njit(cache=True)
def _output(st: np.ndarray, pr: np.ndarray, s: int, u: float) -> float:
    """The D/A for the velocity command u (unit/s) and the speed the drive turns for it."""
    if pr[s, P_V_RESO] > 0.0:  # speed-controlled spindle: the v_reso scaling [000 §2.2.4]
        da = u * pr[s, P_V_RESO] * pr[s, P_SIGN_CMD]
    else:
        da = u * PER_M_MIN * pr[s, P_MG] * pr[s, P_SIGN_CMD]
    lim = pr[s, P_DA_MAX]
    da = min(max(da, -lim), lim)
    st[s, S_U] = u
    st[s, S_DA] = da
    return float(da / (PER_M_MIN * pr[s, P_DRV_GAIN]) * pr[s, P_MOTOR_SIGN])


@njit(cache=True)
def _measure(
    st: np.ndarray,
    pr: np.ndarray,
    ist: np.ndarray,
    pl: np.ndarray,
    ps: np.ndarray,
    probe: np.ndarray,
    s: int,
    dt: float,
) -> None:
    """Read the encoder at the start of the cycle and form this cycle's lag.

    The actual position is the one the load reached at the end of the previous cycle; the
    controller acts on `lag = p_cmd - p_act` of this very sample, and the same pair is what
    the HLI, the traces and the scope show (one definition of the lag everywhere).
    """
    p_prev = st[s, S_P_ACT]
    p_act = _encoder(st, pr, ist, pl, ps, s, st[s, S_X_MOTOR], st[s, S_PLAY])
    st[s, S_P_ACT] = p_act
    # the same instant as a laser or ballbar would read it: no encoder error, no motor side
    sign = pr[s, P_ENC_SIGN] * pr[s, P_SIGN_FB]
    st[s, S_P_TRUE] = sign * st[s, S_X_MOTOR] + pr[s, P_ENC_OFFSET]
    # actual speed from the encoder difference, smoothed as a drive's speed filter would be
    alpha = dt / (dt + V_ACT_FILTER_S)
    st[s, S_V_ACT] += ((p_act - p_prev) / dt - st[s, S_V_ACT]) * alpha
    mode = ist[s, I_OPEN_LOOP]
    if pr[s, P_SENSORLESS] == 1.0:  # no encoder: the actual values are the command's
        st[s, S_P_ACT] = st[s, S_P_CMD]
        st[s, S_V_ACT] = st[s, S_V_CMD]
    elif mode == LOOP_CONTROL_LIMIT:
        # no valid measurement: actual position simulated from the lag; the encoder is
        # re-based onto it, so counting resumes from here when the loop closes
        p_sim = st[s, S_P_CMD] - st[s, S_LAG_MODEL]
        pr[s, P_ENC_OFFSET] += p_sim - p_act
        st[s, S_P_ACT] = p_sim
        st[s, S_V_ACT] = st[s, S_V_CMD]
    elif mode == LOOP_SPEED_CONTROL:
        # the command position is not considered in speed control; keep it where position
        # control would have it against this measurement, so the switch-back needs no
        # standstill and takes over exactly the modelled lag [001 §2.3]
        shift = p_act + st[s, S_LAG_MODEL] - st[s, S_P_CMD]
        st[s, S_P_CMD] += shift
        st[s, S_SEG_P0] += shift
    # no enables, or a speed step of the drive probe with the position loop open: the NC
    # follows the actual position
    opened = probe[PR_SLOT] == s and probe[PR_POINT] == INJECT_SPEED_OPEN
    if ist[s, I_ENABLED] == 0 or (opened and probe[PR_POS] < probe[PR_LEN]):
        st[s, S_P_CMD] = st[s, S_P_ACT]
        st[s, S_V_CMD] = 0.0
        st[s, S_A_CMD] = 0.0
    st[s, S_LAG] = st[s, S_P_CMD] - st[s, S_P_ACT]


@njit(cache=True)
def _cascade(
    st: np.ndarray,
    pr: np.ndarray,
    ist: np.ndarray,
    pl: np.ndarray,
    ps: np.ndarray,
    probe: np.ndarray,
    pexc: np.ndarray,
    prec: np.ndarray,
    s: int,
    dt: float,
    v_target: float,
    closed: bool,
) -> None:
    """The drive cascade and mechanics over the NC cycle, a drive step at a time, with the
    speed `v_target` the NC's position controller commanded (unit/s).

    Where the position loop closes in the drive (PL_POS_IN_DRIVE) it runs at every drive
    step instead: the NC's command continued at its speed over the cycle (the drive's fine
    interpolation) against the drive's own reading of the same measuring system. Its first
    step is the NC's own sample, so the lag the NC shows is the one the drive acts on."""
    n = int(pl[s, PL_SUBSTEPS])
    ts = dt / n
    upr = pl[s, PL_UNIT_PER_RAD]
    enabled = ist[s, I_ENABLED] == 1
    pos0 = probe[PR_POS]
    probing = probe[PR_SLOT] == s
    opened = probing and probe[PR_POINT] == INJECT_SPEED_OPEN and pos0 < probe[PR_LEN]
    in_drive = closed and pl[s, PL_POS_IN_DRIVE] == 1.0 and not opened
    at_position = probing and probe[PR_POINT] == INJECT_POSITION
    x, play = st[s, S_X_MOTOR], st[s, S_PLAY]
    u, da = st[s, S_U], st[s, S_DA]  # the cycle's sample, as the NC shows it
    p_act = st[s, S_P_ACT]
    for k in range(n):
        pos = probe[PR_POS]
        live = pos < probe[PR_LEN]
        p_ref = st[s, S_P_CMD] + (pexc[pos] if at_position and live else 0.0)
        if in_drive:
            p_ref += st[s, S_V_CMD] * k * ts
            if k > 0:
                p_act = _encoder(st, pr, ist, pl, ps, s, x, play)
                v_target = _position_law(st, pr, s, p_ref - p_act)
        elif at_position and live:  # the NC's command, held over its cycle
            p_ref = st[s, S_P_CMD] + pexc[pos0]
        x, play = drive_step(pl, ps, probe, pexc, prec, s, v_target / upr, enabled, x, play, ts)
        if probing and live:
            prec[pos, D_P_REF] = p_ref
            prec[pos, D_P_ACT] = p_act
    st[s, S_X_MOTOR] = x
    st[s, S_PLAY] = play
    st[s, S_V_MOTOR] = load_speed(pl, ps, s)
    st[s, S_U] = u
    st[s, S_DA] = da


@njit(cache=True)
def _control_and_drive(
    st: np.ndarray,
    pr: np.ndarray,
    ist: np.ndarray,
    pl: np.ndarray,
    ps: np.ndarray,
    probe: np.ndarray,
    pexc: np.ndarray,
    prec: np.ndarray,
    s: int,
    dt: float,
) -> None:
    """Position controller, D/A, drive and load of slot s for one cycle: the ideal drive
    here, or the drive cascade and mechanics of nc_sim/plant at the drive's own rate."""
    v_target = 0.0
    # a probe exciting the position loop: its value for this cycle goes onto the command
    pos0 = probe[PR_POS]
    excite = probe[PR_SLOT] == s and probe[PR_POINT] == INJECT_POSITION and pos0 < probe[PR_LEN]
    p_exc = pexc[pos0] if excite else 0.0
    enabled = ist[s, I_ENABLED] == 1
    closed = ist[s, I_OPEN_LOOP] == LOOP_CLOSED
    if enabled:
        if not closed:  # speed control: the command speed goes out
            v_target = _output(st, pr, s, st[s, S_V_CMD])
        else:
            v_target = _position_law(st, pr, s, st[s, S_LAG] + p_exc)
    else:
        st[s, S_U] = 0.0
        st[s, S_DA] = 0.0
    if pl[s, PL_MODEL] == MODEL_CASCADE:
        _cascade(st, pr, ist, pl, ps, probe, pexc, prec, s, dt, v_target, closed and enabled)
        return
    v_m = st[s, S_V_MOTOR]
    if enabled:
        friction = pr[s, P_FRICTION]
        if friction > 0.0:  # Coulomb friction: a speed loss against the motion, or stuck
            if v_target > friction:
                v_target -= friction
            elif v_target < -friction:
                v_target += friction
            else:
                v_target = 0.0
        dv = (v_target - v_m) * pr[s, P_DRV_ALPHA]
        a_lim = pr[s, P_DRV_A_MAX]
        if a_lim > 0.0:
            dv = min(max(dv, -a_lim * dt), a_lim * dt)
    else:  # no enables: holding brake
        dv = -v_m
    v_new = v_m + dv
    dx = 0.5 * (v_m + v_new) * dt
    half_play = 0.5 * pr[s, P_BACKLASH]
    if half_play > 0.0:  # backlash: the motor moves the load only at either end of the play
        play = st[s, S_PLAY] + dx
        if play > half_play:
            st[s, S_X_MOTOR] += play - half_play
            play = half_play
        elif play < -half_play:
            st[s, S_X_MOTOR] += play + half_play
            play = -half_play
        st[s, S_PLAY] = play
    else:
        st[s, S_X_MOTOR] += dx
    st[s, S_V_MOTOR] = v_new


@njit(cache=True)
def _monitors(st: np.ndarray, pr: np.ndarray, ist: np.ndarray, s: int, dt: float) -> int:
    """Lag, software limits, reference cam and speed monitoring; returns event bits."""
    ev = 0
    kv = pr[s, P_KV]
    # the lag an ideal loop would have: this kv and feedforward, a drive with the same time
    # constant but exactly the gain the NC assumes (so a wrong multi_gain or sign shows)
    if ist[s, I_ENABLED] == 0:
        st[s, S_LAG_MODEL] = st[s, S_LAG]
        st[s, S_V_MODEL] = st[s, S_V_ACT]
    else:
        # the model holds this cycle's lag (command step of this cycle minus the motion the
        # modelled drive made in the last one), like S_LAG
        if (
            ist[s, I_OPEN_LOOP] == LOOP_CLOSED
            and abs(st[s, S_LAG] - st[s, S_LAG_MODEL]) > pr[s, P_LAG_MAX]
        ):
            ev |= EV_LAG
        u_m = kv * st[s, S_LAG_MODEL] + pr[s, P_FF] * st[s, S_V_CMD]
        v_m = st[s, S_V_MODEL]
        st[s, S_V_MODEL] = v_m + (u_m - v_m) * pr[s, P_DRV_ALPHA]
        st[s, S_LAG_MODEL] += (st[s, S_V_CMD] - 0.5 * (v_m + st[s, S_V_MODEL])) * dt
    if ist[s, I_LIMITS_ON] == 1:
        p = st[s, S_P_CMD]
        if p < pr[s, P_SWE_NEG] - 1e-9 or p > pr[s, P_SWE_POS] + 1e-9:
            ev |= EV_SWLIMIT
    mod = pr[s, P_MODULO]
    if mod > 0.0:  # spindle: the encoder's zero mark passes once per revolution
        cam = math.floor((st[s, S_X_MOTOR] - pr[s, P_CAM_POS]) / mod)
    else:
        cam = 1 if st[s, S_X_MOTOR] >= pr[s, P_CAM_POS] else 0
    if cam != ist[s, I_CAM]:
        ist[s, I_CAM] = cam
        # a turning spindle passes its mark every revolution: report it only when asked
        if mod <= 0.0 or ist[s, I_MARK_ARMED] == 1:
            ev |= EV_CAM
    # speed monitoring [000 §2.6] on the filtered actual speed. A flag flips back only when the
    # speed has moved past its threshold by more than the measurement resolves: one increment
    # within the filter raises the filtered speed by at most inc/(dt + T_filter), so the
    # ripple of a quantised encoder (a lone count while creeping to rest, 68 or 69 counts per
    # cycle at speed) cannot toggle it. One edge, one event.
    v_meas = st[s, S_V_ACT]
    inc = pr[s, P_ENC_INC]
    resolution = inc / (dt + V_ACT_FILTER_S) if inc > 0.0 else 0.0
    v_act = abs(v_meas)
    if ist[s, I_STOPPED] == 1:
        stopped = 0 if v_act > pr[s, P_V_ZERO] + resolution else 1
    else:
        stopped = 1 if v_act < pr[s, P_V_ZERO] else 0
    ist[s, I_STOPPED] = stopped
    goal_v = st[s, S_V_GOAL]
    reached = 0
    if goal_v != 0.0:
        band = pr[s, P_SPEED_BAND] * abs(goal_v)
        if ist[s, I_SPEED_REACHED] == 1:
            band += resolution
        if abs(v_meas - goal_v) <= band:
            reached = 1
    if reached == 1 and ist[s, I_SPEED_REACHED] == 0:
        ev |= EV_SPEED_REACHED
    ist[s, I_SPEED_REACHED] = reached
    changing = ist[s, I_PLAN_N] > 0 or ist[s, I_CURVE] == 1
    ist[s, I_MON_INVALID] = (
        1
        if ist[s, I_MON_ACTIVE] == 1 and (changing or ist[s, I_OPEN_LOOP] == LOOP_CONTROL_LIMIT)
        else 0
    )
    target = st[s, S_TARGET]
    in_pos = 0
    if not changing and not math.isnan(target):
        in_pos = 1 if abs(target - st[s, S_P_ACT]) <= pr[s, P_INPOS_WIN] else 0
    if in_pos == 1 and ist[s, I_IN_POS] == 0:
        ev |= EV_IN_POS
    ist[s, I_IN_POS] = in_pos
    return ev


@njit(cache=True)
def moving_direction(v_act: float, inpos_window: float) -> int:
    """003 §4.2 MVPOS (+1) / MVNEG (-1), 0 at rest: the actual speed beyond the noise of an
    axis at rest, one exact-stop window per second (the status reads it between cycles)."""
    if v_act > inpos_window:
        return 1
    if v_act < -inpos_window:
        return -1
    return 0


@njit(cache=True)
def _loop_mode(st: np.ndarray, pr: np.ndarray, ist: np.ndarray, s: int) -> int:
    """Open the position loop above the control limit or the changeover speed; close it
    again below the control limit [000 §2.4.2, 001 §2.3]. Returns EV_LOOP on a change."""
    mode = ist[s, I_OPEN_LOOP]
    if pr[s, P_SENSORLESS] == 1.0 or pr[s, P_V_RESO] > 0.0:  # never position-controlled
        ist[s, I_OPEN_LOOP] = LOOP_SPEED_CONTROL
        return 0 if mode == LOOP_SPEED_CONTROL else EV_LOOP
    v = abs(st[s, S_V_CMD])
    new = mode
    if v > pr[s, P_V_CTRL_LIMIT]:
        new = LOOP_CONTROL_LIMIT
    elif mode == LOOP_CONTROL_LIMIT:
        armed = ist[s, I_SPEED_CTRL_ARMED] == 1 and v > pr[s, P_V_SPEED_CTRL]
        new = LOOP_SPEED_CONTROL if armed else LOOP_CLOSED
    elif mode == LOOP_CLOSED and ist[s, I_SPEED_CTRL_ARMED] == 1 and v > pr[s, P_V_SPEED_CTRL]:
        new = LOOP_SPEED_CONTROL
    if new == mode:
        return 0
    ist[s, I_OPEN_LOOP] = new
    if new == LOOP_CONTROL_LIMIT:
        ist[s, I_HOMED] = 0  # the measuring system lost track: reference lost
    return EV_LOOP


@njit(cache=True)
def run_cycles(
    st: np.ndarray,
    pr: np.ndarray,
    ist: np.ndarray,
    seg: np.ndarray,
    pi: np.ndarray,
    pel: np.ndarray,
    pplan: np.ndarray,
    pl: np.ndarray,
    ps: np.ndarray,
    probe: np.ndarray,
    pexc: np.ndarray,
    prec: np.ndarray,
    rec: np.ndarray,
    n: int,
    dt: float,
) -> int:
    """Advance every path and every slot by up to n cycles; stop after a cycle that raised
    an event.

    Paths first (they set their axes' setpoints), then each slot's own plan (unless a path
    drives it), position loop, drive and monitors. `rec` (cycles × slots × R_COLS) receives
    one sample per cycle when it has room (pass an array with zero rows to record nothing).
    Returns the cycles done.
    """
    slots = st.shape[0]
    record = rec.shape[0] >= n and rec.shape[1] == slots
    for c in range(n):
        any_event = 0
        for p in range(pi.shape[0]):
            ev, manual_done = _advance_path(st, ist, seg, pi, pel, pplan, p, dt)
            if ev != 0:
                ist[pi[p, PI_SLOT], I_EVENTS] |= ev
                any_event = 1
            any_event |= manual_done
        for s in range(slots):
            role = ist[s, I_ROLE]
            if role == ROLE_CHANNEL:
                ev = 0
            else:
                ev = _advance_setpoint(st, pr, ist, seg, s, dt) if role == ROLE_AXIS else 0
                ev |= _loop_mode(st, pr, ist, s)
                _measure(st, pr, ist, pl, ps, probe, s, dt)
                _control_and_drive(st, pr, ist, pl, ps, probe, pexc, prec, s, dt)
                ev |= _monitors(st, pr, ist, s, dt)
            if ev != 0:
                ist[s, I_EVENTS] |= ev
                any_event = 1
            if record:
                rec[c, s, R_P_CMD] = st[s, S_P_CMD]
                rec[c, s, R_P_ACT] = st[s, S_P_ACT]
                rec[c, s, R_LAG] = st[s, S_LAG]
                rec[c, s, R_V_CMD] = st[s, S_V_CMD]
                rec[c, s, R_V_ACT] = st[s, S_V_ACT]
                rec[c, s, R_A_CMD] = st[s, S_A_CMD]
                rec[c, s, R_STATE] = ist[s, I_STATE]
                rec[c, s, R_JOB_ERROR] = ist[s, I_JOB_ERROR]
                rec[c, s, R_SPEED_REACHED] = ist[s, I_SPEED_REACHED]
                rec[c, s, R_STOPPED] = ist[s, I_STOPPED]
                rec[c, s, R_GEAR] = ist[s, I_GEAR]
                rec[c, s, R_DA] = st[s, S_DA]
                rec[c, s, R_OPEN_LOOP] = ist[s, I_OPEN_LOOP]
                rec[c, s, R_HOMED] = ist[s, I_HOMED]
                rec[c, s, R_IN_POS] = ist[s, I_IN_POS]
                rec[c, s, R_MON_ACTIVE] = ist[s, I_MON_ACTIVE]
                rec[c, s, R_MON_INVALID] = ist[s, I_MON_INVALID]
                rec[c, s, R_OVERRIDE] = st[s, S_OVERRIDE]
                rec[c, s, R_LINE] = ist[s, I_LINE]
                rec[c, s, R_ROTARY_MODE] = ist[s, I_ROTARY_MODE]
                way = moving_direction(st[s, S_V_ACT], pr[s, P_INPOS_WIN])
                rec[c, s, R_MVPOS] = 1.0 if way > 0 else 0.0
                rec[c, s, R_MVNEG] = 1.0 if way < 0 else 0.0
                rec[c, s, R_READY] = ist[s, I_ENABLED]
                rec[c, s, R_P_TRUE] = st[s, S_P_TRUE]
        if any_event == 1:
            return c + 1
    return n
