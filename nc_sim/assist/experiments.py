"""Experiments on a machine in simulated time, as the manual has the engineer do them by hand:

- `multi_gain_experiment` [004 §3.6.2]: move the axis (or turn the spindle, position-
  controlled) at constant speed v, average the lag s, k = v/s; f = (kv/100)/k (kv in 0.01/s);
  multi_gain_new = multi_gain · f; kv_new = kv / f keeps the loop gain when f > 1.
- `sign_check` [004 §3.5]: a short slow move; a wrong sign of the manipulated variable or of
  the actual value turns the loop into positive feedback, seen as the actual position running
  away from the command long before lag monitoring trips; the servo is switched off at once.
  Which sign is wrong follows from the way the machine really moved (the engineer's eye; on
  the simulated machine its plant): it moved the commanded way -> vz_istw, the other way ->
  vz_stellgr; both wrong leave the loop stable but mirrored -> both.

Each builds its own machine from a configuration (the live machine's parameters, so a run is
a preview on a copy) and answers with a `Result`.
"""

from __future__ import annotations

import math

import numpy as np

from nc_sim.assist.procedure import Procedure, Wait, on_copy
from nc_sim.assist.result import Change, ExperimentError, Figure, Result, Series
from nc_sim.axis.state import Axis
from nc_sim.commands import Accepted, HliWrite, Move, Refused, Reset, SpindleRun
from nc_sim.config import MachineConfig
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.snapshot import AxisState
from nc_sim.units import MM_MIN_PER_MM_S, RPM_TO_DEG_S, AxisKind

MAX_PLOT_POINTS = 2000
MIN_WINDOW_S = 0.2  # the averaging window at constant speed must be at least this long
F_MATCHES = 0.01  # f within this of 1: k equals kv as the experiment can tell, no change
SPINDLE_UP_S = 60.0  # a spindle not at speed by then has a fault of its own


def _check_axis(m: Machine, axis: str) -> Axis:
    try:
        return m.axis(axis)
    except ValueError as e:  # (an unknown axis)
        raise ExperimentError(str(e)) from None


def _stop(m: Machine, ax: Axis) -> None:
    """The run was cancelled: stop what it started (M5 for a spindle, a CNC reset's braking
    for an axis); after an emergency stop nothing is left to stop."""
    if m.estop:
        return
    m.submit(SpindleRun(ax.name, 5) if ax.kind is AxisKind.SPINDLE else Reset())


def _thin(t: np.ndarray, y: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...]]:
    step = max(1, len(t) // MAX_PLOT_POINTS)
    return tuple(float(v) for v in t[::step]), tuple(float(v) for v in y[::step])


def _refusal(out: object) -> ExperimentError:
    """The NC's refusal of the experiment's motion, in its own words (the job error's text)."""
    why = out.error.message if isinstance(out, Refused) else str(out)
    return ExperimentError(f"the motion was refused: {why}")


def _fraction(value: float, denominator: int) -> tuple[int, int]:
    """A factor as the integer pair the lists hold: 2.2857 -> 2286/1000 (the manual's form);
    a denominator that is already large is kept."""
    n = denominator if denominator >= 1000 else denominator * 1000
    return max(1, round(value * n)), n


def multi_gain_experiment(
    cfg: MachineConfig,
    axis: str,
    feed_mm_min: float | None = None,
    speed_rpm: float | None = None,
    window_s: float = 1.0,
    direction: int = 1,
) -> Result:
    """`multi_gain` on a fresh copy of the machine `cfg` describes (the preview)."""
    return on_copy(cfg, lambda m: multi_gain(m, axis, feed_mm_min, speed_rpm, window_s, direction))


def multi_gain(
    m: Machine,
    axis: str,
    feed_mm_min: float | None = None,
    speed_rpm: float | None = None,
    window_s: float = 1.0,
    direction: int = 1,
) -> Procedure:
    """004 §3.6.2 on `axis`: a linear or rotary axis moves at `feed_mm_min` (mm/min or
    °/min), a spindle turns position-controlled at `speed_rpm`; the lag is averaged over
    `window_s` at constant speed once the loop has settled."""
    ax = _check_axis(m, axis)
    cycle_s = m.k.cycle_s
    direction = -1 if direction < 0 else 1
    spindle = ax.kind is AxisKind.SPINDLE
    if spindle:
        if not speed_rpm or speed_rpm <= 0:
            raise ExperimentError("a spindle needs its speed: speed_rpm > 0")
        v = speed_rpm * RPM_TO_DEG_S * direction
        unit, v_shown, v_unit = "°", speed_rpm, "rpm"
    else:
        if not feed_mm_min or feed_mm_min <= 0:
            raise ExperimentError("an axis needs its feed: feed_mm_min > 0")
        v = feed_mm_min / MM_MIN_PER_MM_S * direction
        unit = "mm" if ax.kind is AxisKind.LINEAR else "°"
        v_shown, v_unit = feed_mm_min, f"{unit}/min"
    # the loop settles within a few time constants, even when its gain is a third of kv
    settle_s = 5.0 * 3.0 / (int(ax.cfg.raw("getriebe.kv", ax.gear)) / 100.0)
    total_s = 2.0 + settle_s + max(window_s, MIN_WINDOW_S)  # (an axis: its ramp first)
    if spindle:
        out = m.submit(SpindleRun(ax.name, 3 if direction > 0 else 4, speed_rpm))
    else:
        p0 = float(m.k.st[ax.slot, L.S_P_CMD])
        target = p0 + direction * abs(v) * (total_s + 2.0)
        out = m.submit(Move(ax.name, target, rapid=False, feed_mm_min=feed_mm_min))
    if not isinstance(out, Accepted):
        raise _refusal(out)
    try:
        if spindle:  # up to speed first (a gear change, the acceleration curve): not measured
            waited = 0
            while not m.k.ist[ax.slot, L.I_SPEED_REACHED] and waited * cycle_s < SPINDLE_UP_S:
                yield Wait(10, f"{ax.name} runs up to {speed_rpm:g} rpm", total_s + 1.0)
                waited += 10
            settle_s = 5.0 * 3.0 / (int(ax.cfg.raw("getriebe.kv", ax.gear)) / 100.0)
            total_s = settle_s + max(window_s, MIN_WINDOW_S) + 0.5  # in the gear it chose
            if m.motion.loop_mode(ax) != L.LOOP_CLOSED:
                m.submit(SpindleRun(ax.name, 5))
                raise ExperimentError(
                    f"{ax.name} is not position-controlled at {speed_rpm:g} rpm (speed control "
                    "above P-AXIS-00767 or the control limit): a lower speed"
                )
        recorded_s = total_s + 1.0
        whole_s = recorded_s if spindle else total_s + 2.0  # an axis goes on to its target
        phase = f"{ax.name} at {v_shown:g} {v_unit}: the lag is recorded"
        rec = yield Wait(round(recorded_s / cycle_s), phase, whole_s)
        if spindle:
            m.submit(SpindleRun(ax.name, 5))
        while ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):  # (live: at rest)
            yield Wait(10, f"{ax.name} comes to rest", whole_s)
    except GeneratorExit:
        _stop(m, ax)
        raise
    g = ax.gear
    kv_raw = int(ax.cfg.raw("getriebe.kv", g))
    kv = kv_raw / 100.0
    mg_z = int(ax.cfg.raw("getriebe.multi_gain_z", g))
    mg_n = int(ax.cfg.raw("getriebe.multi_gain_n", g))
    t = np.arange(rec.shape[0]) * cycle_s
    v_cmd = rec[:, ax.slot, L.R_V_CMD]
    lag = rec[:, ax.slot, L.R_LAG]
    steady = np.flatnonzero(np.abs(v_cmd - v) <= 1e-9 * max(1.0, abs(v)))
    notes: list[str] = []
    figures = [Figure("v", v_shown, v_unit, "the speed of the experiment")]
    series = [Series("lag", *_thin(t, lag), "s", unit)]
    error = ax.error_event
    if error is not None:
        notes.append(f"the run ended in a job error: {error.message}")
    elif len(steady) == 0 or (t[steady[-1]] - t[steady[0]]) < settle_s + MIN_WINDOW_S:
        notes.append("no constant speed long enough to measure: a longer window or a lower speed")
    if notes:
        return Result("multi-gain", tuple(figures), (), tuple(series), tuple(notes), False)
    t0 = t[steady[0]] + settle_s
    # the window asked for, not all the constant speed there was (a live run's axis may
    # keep its speed for longer than the window)
    window = steady[(t[steady] >= t0) & (t[steady] < t0 + max(window_s, MIN_WINDOW_S))]
    s = float(np.mean(lag[window]))
    k = v / s if s != 0.0 else math.inf
    f = kv / k
    mg = mg_z / mg_n
    new_z, new_n = _fraction(mg * f, mg_n)
    kv_new = max(1, round(kv_raw / f))
    gi = g - 1
    figures += [
        Figure("s", s, unit, "mean lag at constant speed"),
        Figure("k", k, "1/s", "effective loop gain k = v/s"),
        Figure("kv", kv, "1/s", f"getriebe[{gi}].kv (P-AXIS-00099)"),
        Figure("f", f, "", "f = kv/k (004: (kv/100)/k with kv in 0.01/s)"),
        Figure("multi_gain", mg, "", "multi_gain_z/multi_gain_n now"),
        Figure("multi_gain_new", new_z / new_n, "", "multi_gain · f"),
        Figure("kv_new", kv_new / 100.0, "1/s", "kv / f: the same loop gain"),
        Figure(
            "averaged_s",
            float(t[window[-1]] - t[window[0]]),
            "s",
            "the lag averaged over (constant speed, settled)",
        ),
    ]
    changes = [
        Change(ax.name, f"getriebe[{gi}].multi_gain_z", mg_z, new_z, "multi_gain · f"),
        Change(ax.name, f"getriebe[{gi}].multi_gain_n", mg_n, new_n, "multi_gain · f"),
        Change(ax.name, f"getriebe[{gi}].kv", kv_raw, kv_new, "kv / f keeps the loop gain"),
    ]
    if f > 1.005:
        notes.append(
            f"f = {f:.3f} > 1: the new multi_gain raises the loop gain by f; kv/f keeps it "
            "(004 §3.6.2 NOTICE). Optimise the loop with kv afterwards."
        )
    if abs(f - 1.0) <= F_MATCHES:
        # k equals kv: a residue of f would only churn the lists (and read as a correction)
        changes = []
        notes.append(
            f"f = {f:.4f}: within {F_MATCHES * 100:g} % of 1, multi_gain matches the drive "
            "(004 §3.6.2 equation 1): nothing to apply"
        )
    else:
        notes.append("after applying, run it again: k must equal kv (004 §3.6.2 equation 1)")
    return Result(
        "multi-gain",
        tuple(figures),
        tuple(changes),
        tuple(series),
        tuple(notes),
        True,
        {"axis": ax.name, "v": v_shown, "window_s": window_s},
    )


def sign_check_experiment(
    cfg: MachineConfig,
    axis: str,
    distance: float = 1.0,
    feed_mm_min: float = 100.0,
    observed: int | None = None,
) -> Result:
    """`sign_check` on a fresh copy of the machine `cfg` describes (the preview)."""
    return on_copy(cfg, lambda m: sign_check(m, axis, distance, feed_mm_min, observed))


def sign_check(
    m: Machine,
    axis: str,
    distance: float = 1.0,
    feed_mm_min: float = 100.0,
    observed: int | None = None,
) -> Procedure:
    """004 §3.5 on `axis`: a move of `distance` (mm or °) at `feed_mm_min`. `observed` is the
    way the machine moved as the engineer saw it (+1 / -1); None takes the simulated
    machine's plant (its true load position)."""
    ax = _check_axis(m, axis)
    s = ax.slot
    p0, x0 = float(m.k.st[s, L.S_P_ACT]), float(m.k.st[s, L.S_X_MOTOR])
    lag_max = ax.cfg.eng("getriebe.lag_max", ax.gear)
    out = m.submit(Move(ax.name, float(m.k.st[s, L.S_P_CMD]) + distance, False, feed_mm_min))
    if not isinstance(out, Accepted):
        raise _refusal(out)
    inc = max(float(m.k.pr[s, L.P_ENC_INC]), 1e-6)
    runaway_at = 10.0 * inc  # the actual running the wrong way by this much: positive feedback
    t_move = abs(distance) / (feed_mm_min / MM_MIN_PER_MM_S)
    planned_s = t_move + 2.0
    limit = round(planned_s / m.k.cycle_s)
    trace_t: list[float] = []
    trace_lag: list[float] = []
    runaway = False
    phase = f"{ax.name} moves {distance:g} {ax.pos_unit} at {feed_mm_min:g} {ax.pos_unit}/min"
    try:
        for i in range(limit):  # cycle by cycle: the servo goes off in the cycle it runs away
            yield Wait(1, phase, planned_s)
            lag = float(m.k.st[s, L.S_LAG])
            trace_t.append(i * m.k.cycle_s)
            trace_lag.append(lag)
            moved_nc = float(m.k.st[s, L.S_P_ACT]) - p0
            if moved_nc * math.copysign(1.0, distance) < -runaway_at:
                runaway = True
                m.submit(HliWrite("TorquePermission", 0, ax.name))  # servo off at once
                break
            if ax.error_event is not None:
                break
            if i * m.k.cycle_s > t_move and ax.state is AxisState.STANDSTILL:
                break  # (live: done once at rest; the copy's trace ends the same way)
    except GeneratorExit:
        _stop(m, ax)
        raise
    max_lag = max((abs(v) for v in trace_lag), default=0.0)
    moved_load = float(m.k.st[s, L.S_X_MOTOR]) - x0
    seen = observed if observed is not None else (1 if moved_load * distance > 0 else -1)
    tripped = ax.error_event is not None and not runaway
    figures = [
        Figure("max_lag", max_lag, ax.pos_unit, "largest lag during the check"),
        Figure("lag_max", lag_max, ax.pos_unit, "lag monitoring's limit (getriebe[i].lag_max)"),
        Figure("runaway", float(runaway), "", "the actual ran away from the command"),
        Figure("observed", float(seen), "", "the way the machine moved (+1 as commanded)"),
    ]
    changes: list[Change] = []
    notes: list[str] = []

    def flip(name: str, why: str) -> None:
        before = int(ax.cfg.raw(f"lr_hw.{name}"))
        changes.append(Change(ax.name, f"lr_hw[0].{name}", before, 1 - before, why))

    if runaway and seen > 0:
        flip("vz_istw", "the axis moved as commanded but its actual value counts the other way")
    elif runaway:
        flip("vz_stellgr", "the manipulated variable drives the axis the other way")
    elif seen < 0:
        flip("vz_stellgr", "the axis moves mirrored: both signs are inverted")
        flip("vz_istw", "the axis moves mirrored: both signs are inverted")
    if tripped:
        notes.append("lag monitoring tripped before a wrong sign showed: check the drive first")
    if runaway:
        notes.append(f"the actual position ran away after {trace_t[-1]:.3f} s: servo switched off")
    if not changes and not tripped:
        notes.append("the signs are right: the axis moved as commanded and the loop holds")
    return Result(
        "sign-check",
        tuple(figures),
        tuple(changes),
        (Series("lag", tuple(trace_t), tuple(trace_lag), "s", ax.pos_unit),),
        tuple(notes),
        not tripped,
        {"axis": ax.name, "distance": distance, "feed_mm_min": feed_mm_min},
    )
