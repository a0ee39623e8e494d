"""The service-axis view of an axis or spindle (what SINUMERIK's service-axis screen and
TwinCAT's axis dialogs show): the loop's gain and the lag it should give, the gain measured
from the last cycles, the D/A output against its limit, and the dynamic limits in force with
where each comes from. Pure: read from the machine and its newest kernel records.

Steady state at constant speed without feedforward: lag = v / kv [004 §3.6]; with
feedforward weight w the loop only sees (1 − w)·v. The measured gain k = v / lag [004 §3.6.2]
equals kv when multi_gain matches the drive; it means something only after the speed has been
constant long enough for the lag to settle and with a lag well above the encoder's resolution.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from nc_sim.axis.dynamics import Dynamics, Motion, Sourced, param
from nc_sim.axis.state import Axis
from nc_sim.kernel import layout as L
from nc_sim.snapshot import AxisServiceSnapshot, GainReading, LimitInForce
from nc_sim.units import AxisKind, display_velocity, per_second

if TYPE_CHECKING:
    from nc_sim.machine.machine import Machine

SETTLE_TIME_CONSTANTS = 8.0  # constant speed for 8/kv before the lag counts: e^-8 < 0.04 %
AVERAGE_S = 0.1  # the lag is averaged over this much after settling
SPEED_STEADY = 1e-3  # the command speed varies by less than this fraction meanwhile
LAG_FLOOR_INCREMENTS = 100.0  # |lag| at least this many encoder increments (< 1 % quantised)
LAG_FLOOR = 1e-6  # ... and at least this (mm | °) with an ideal encoder
LAG_SCATTER = 2e-3  # the mean lag's standard error below this fraction of it


def _no_loop(m: Machine, ax: Axis) -> str | None:
    """Why the axis has no closed position loop now, None when it has."""
    ist = m.k.ist[ax.slot]
    if not ist[L.I_ENABLED]:
        return "no closed loop: the drive lacks its enables"
    mode = int(ist[L.I_OPEN_LOOP])
    if mode == L.LOOP_SPEED_CONTROL:
        return "speed control: the position loop is open"
    if mode == L.LOOP_CONTROL_LIMIT:
        return "above the control limit vb_regelgrenze: the position loop is open"
    return None


def _window_cycles(kv_per_s: float, cycle_s: float) -> int:
    """Cycles of constant speed k needs: settling over 8/kv, then averaging over 0.1 s."""
    settle = math.ceil(SETTLE_TIME_CONSTANTS / kv_per_s / cycle_s)
    return settle + max(1, math.ceil(AVERAGE_S / cycle_s))


def history_cycles(m: Machine) -> int:
    """Records the service view of every axis of `m` looks back on."""
    kvs = [float(m.k.pr[ax.slot, L.P_KV]) for ax in m.axes]
    return max((_window_cycles(kv, m.k.cycle_s) for kv in kvs if kv > 0), default=1)


def measured_gain(
    rec: np.ndarray, slot: int, cycle_s: float, kv_per_s: float, enc_inc: float
) -> GainReading:
    """k = v / lag (1/s) from the newest kernel records `rec` (cycles × slots × R_COLS, oldest
    first), averaged over AVERAGE_S after the command speed has been constant for
    SETTLE_TIME_CONSTANTS / kv; None with the reason when that does not hold or the lag is
    too small or too scattered to give k within 1 %."""
    if kv_per_s <= 0:
        return GainReading(None, "kv is 0: no position loop gain")
    avg = max(1, math.ceil(AVERAGE_S / cycle_s))
    need = _window_cycles(kv_per_s, cycle_s)
    if rec.shape[0] < need:
        return GainReading(None, f"needs {need * cycle_s:.2f} s of records")
    r = rec[-need:, slot]
    if np.any(r[:, L.R_OPEN_LOOP] != L.LOOP_CLOSED) or not np.all(r[:, L.R_READY]):
        return GainReading(None, "the position loop was not closed throughout")
    v = r[:, L.R_V_CMD]
    v_end = float(v[-1])
    if abs(v_end) < 1e-9:
        return GainReading(None, "at standstill: k = v/lag needs motion at constant speed")
    if float(np.max(np.abs(v - v_end))) > SPEED_STEADY * abs(v_end):
        secs = need * cycle_s
        return GainReading(None, f"speed not constant for the last {secs:.2f} s (8/kv + 0.1 s)")
    lag = r[-avg:, L.R_LAG]
    lag_mean = float(np.mean(lag))
    floor = max(LAG_FLOOR_INCREMENTS * enc_inc, LAG_FLOOR)
    if abs(lag_mean) < floor:
        return GainReading(None, f"|lag| below {floor:.4g}: too small to measure k")
    scatter = float(np.std(lag)) / math.sqrt(avg)
    if scatter > LAG_SCATTER * abs(lag_mean):
        return GainReading(None, "lag too noisy to measure k within 1 %")
    return GainReading(float(np.mean(v[-avg:])) / lag_mean, None)


def _limit(s: Sourced, value: float, unit: str, override_pct: float | None = None) -> LimitInForce:
    return LimitInForce(value, unit, s.source, s.param_id, s.kind, override_pct)


def _limits(
    m: Machine, ax: Axis
) -> tuple[LimitInForce, LimitInForce, LimitInForce | None, str | None]:
    """Velocity, acceleration and jerk in force for what the axis does now (or its G01
    motion at rest), each with its source."""
    unit = ax.pos_unit if ax.kind is AxisKind.LINEAR else "°"
    as_axis = m.moves.as_axis(ax)
    if as_axis:
        motion = ax.motion or Motion.FEED
        v, ovr = m.moves.speed_in_force(ax, motion)
        feed = m.channel.modal[3]  # F of the block the path is in, mm/min
        block = m.channel.path.current
        on_path = m.k.ist[ax.slot, L.I_ROLE] == L.ROLE_PATH_AXIS and block is not None
        if on_path and block is not None and feed and ax in m.ch_host.path_axes:
            # the axis' share of the path's F × channel override: the most of the path speed
            # this block asks of it (a line's direction component, an arc's radius share)
            ovr = m.moves.override(ax)
            share = float(block.weights()[m.ch_host.path_axes.index(ax)])
            v = Sourced(
                per_second(feed) * ovr * share, f"F (path) × {share:.3g}", None, "programmed"
            )
        elif ax.motion is None and not on_path:
            # at rest: no F or jog feed in force, only the most any motion of it may have
            v, ovr = param(ax.cfg, "getriebe.dynamik.vb_max", ax.gear), 1.0
        dyn: Dynamics = m.motion.dynamics(ax, motion)
        kind: AxisKind = AxisKind.ROTARY if ax.kind is AxisKind.SPINDLE else ax.kind
    else:
        vb = m.sp.vb_max_in_force(ax)
        ovr = m.sp.override(ax)
        prog = Sourced(abs(ax.speed_prog) * ovr, "S", None, "programmed")
        v = prog if 0 < prog.value < vb.value else vb
        ovr = ovr if v is prog else 1.0
        dyn = m.sp.dynamics(ax)
        kind = ax.kind
    v_shown, v_unit = display_velocity(v.value, kind)
    velocity = _limit(v, v_shown, v_unit, ovr * 100.0 if ovr != 1.0 else None)
    acceleration = _limit(dyn.a_acc, dyn.a_acc.value, f"{unit}/s²")
    j = dyn.jerk()
    if j is None:
        return velocity, acceleration, None, "step-shaped: jerk not limited"
    return velocity, acceleration, _limit(j, j.value, f"{unit}/s³"), None


def axis_service(m: Machine, ax: Axis, rec: np.ndarray) -> AxisServiceSnapshot:
    """The service-axis view of `ax` now; `rec` its machine's newest kernel records."""
    s = ax.slot
    st, pr = m.k.st[s], m.k.pr[s]
    kv = float(pr[L.P_KV])
    ff = float(pr[L.P_FF])
    v_cmd = float(st[L.S_V_CMD])
    why = _no_loop(m, ax)
    expected = None if why is not None or kv <= 0 else (1.0 - ff) * v_cmd / kv
    if why is None and kv <= 0:
        why = "kv is 0: no position loop gain"
    gain = (
        GainReading(None, why) if why else measured_gain(rec, s, m.k.cycle_s, kv, pr[L.P_ENC_INC])
    )
    velocity, acceleration, jerk, jerk_why = _limits(m, ax)
    return AxisServiceSnapshot(
        name=ax.name,
        gear=ax.gear,
        kv_per_s=kv,
        ff_weight=ff,
        multi_gain=float(pr[L.P_MG]),
        lag_max=float(pr[L.P_LAG_MAX]),
        v_cmd=v_cmd,
        lag_expected=expected,
        lag_expected_why_not=why,
        gain=gain,
        da_digits=float(st[L.S_DA]),
        da_max_digits=float(pr[L.P_DA_MAX]),
        velocity=velocity,
        acceleration=acceleration,
        jerk=jerk,
        jerk_why_none=jerk_why,
    )


def service_view(m: Machine, rec: np.ndarray) -> tuple[AxisServiceSnapshot, ...]:
    """Every axis and spindle of the machine in the service-axis view."""
    return tuple(axis_service(m, ax, rec) for ax in m.axes)
