"""The resolution check [004 §3.4]: move the axis a known distance and compare the travel the
NC counts with the travel measured on the machine (a dial gauge or a laser; on the simulated
machine its plant's true load position).

The NC turns encoder increments into a position with wegaufz/wegaufn (increments per 0.1 µm
or 0.0001°). If the encoder really delivers k times as many increments per unit, the NC counts
k times the true travel: k = NC travel / measured travel, and the right value is
wegaufz/wegaufn · k. A check within the measurement's own resolution proposes nothing.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from nc_sim.assist.calculators import list_fraction
from nc_sim.assist.experiments import _check_axis, _refusal, _stop, _thin
from nc_sim.assist.procedure import Procedure, Wait
from nc_sim.assist.result import Change, ExperimentError, Figure, Result, Series
from nc_sim.commands import Accepted, Move
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.snapshot import AxisState
from nc_sim.units import MM_MIN_PER_MM_S, AxisKind

REST_LIMIT_S = 30.0  # after its planned time an axis not at rest by then has a fault of its own
SETTLE_TAUS = 12.0  # position loop time constants (1/kv) waited at rest before reading
PPM = 1e6
RESOLUTION_UNIT = {AxisKind.LINEAR: "0.1 µm", AxisKind.ROTARY: "0.0001°"}  # wegaufn's
FLOOR_PPM = 20.0  # a travel agreeing within this (and two increments) is right


def _simplest(k: float, within_ppm: float) -> Fraction:
    """The fraction with the smallest denominator within `within_ppm` of k: a measured 49.9 mm
    on 50 mm is 500/499, not the float's 1.00200400..."""
    bound = 10
    while True:
        f = Fraction(k).limit_denominator(bound)
        if abs(float(f) / k - 1.0) * PPM <= within_ppm or bound > 10**9:
            return f
        bound *= 10


def resolution_check(
    m: Machine,
    axis: str,
    distance: float = 10.0,
    feed_mm_min: float = 1000.0,
    measured: float | None = None,
) -> Procedure:
    """004 §3.4 on `axis`: a move of `distance` (mm or °) at `feed_mm_min`; `measured` is the
    travel measured on the machine (None: the simulated plant's true travel)."""
    ax = _check_axis(m, axis)
    s, g = ax.slot, ax.gear
    p0, x0 = float(m.k.st[s, L.S_P_ACT]), float(m.k.st[s, L.S_X_MOTOR])
    out = m.submit(Move(ax.name, float(m.k.st[s, L.S_P_CMD]) + distance, False, feed_mm_min))
    if not isinstance(out, Accepted):
        raise _refusal(out)
    cycle_s = m.k.cycle_s
    t_move = abs(distance) / (feed_mm_min / MM_MIN_PER_MM_S)
    planned_s = t_move + 1.0
    phase = f"{ax.name} moves {distance:g} {ax.pos_unit} at {feed_mm_min:g} {ax.pos_unit}/min"
    # the set-point ends before the axis does: the travels are read once the lag has decayed
    # to e^-SETTLE_TAUS of itself (ppm of any travel worth checking)
    settle_s = SETTLE_TAUS / (int(ax.cfg.raw("getriebe.kv", g)) / 100.0)
    lags: list[np.ndarray] = []
    waited_s, rest_s = 0.0, 0.0
    try:
        while rest_s < settle_s:
            if ax.error_event is not None:
                raise ExperimentError(f"the move ended in a job error: {ax.error_event.message}")
            if waited_s > planned_s + settle_s + REST_LIMIT_S:
                raise ExperimentError(f"{ax.name} did not come to rest after the move")
            rec = yield Wait(10, phase, planned_s + settle_s)
            lags.append(rec[:, s, L.R_LAG])
            waited_s += rec.shape[0] * cycle_s
            at_rest = waited_s > t_move and ax.state is AxisState.STANDSTILL
            rest_s = rest_s + rec.shape[0] * cycle_s if at_rest else 0.0
    except GeneratorExit:
        _stop(m, ax)
        raise
    nc_travel = float(m.k.st[s, L.S_P_ACT]) - p0
    true_travel = float(m.k.st[s, L.S_X_MOTOR]) - x0
    seen = true_travel if measured is None else measured
    if abs(seen) < 1e-9 or seen * nc_travel <= 0:
        raise ExperimentError(f"measured travel {seen:g} {ax.pos_unit}: not the move's way")
    k = nc_travel / seen
    inc = float(m.k.pr[s, L.P_ENC_INC])
    tolerance_ppm = FLOOR_PPM + PPM * 2.0 * inc / abs(nc_travel)
    off_ppm = (k - 1.0) * PPM
    z, n = int(ax.cfg.raw("getriebe.wegaufz", g)), int(ax.cfg.raw("getriebe.wegaufn", g))
    new_z, new_n, note = list_fraction(Fraction(z) * _simplest(k, tolerance_ppm / 10), Fraction(n))
    gi = g - 1
    unit = ax.pos_unit
    figures = (
        Figure("nc_travel", nc_travel, unit, "the travel the NC counted"),
        Figure("measured_travel", seen, unit, "the travel measured on the machine"),
        Figure("k", k, "", "NC travel / measured travel: increments per unit, actual / set"),
        Figure("deviation_ppm", off_ppm, "ppm", "(k - 1) · 10⁶"),
        Figure("tolerance_ppm", tolerance_ppm, "ppm", "what the measurement resolves"),
        Figure(
            "resolution",
            z / n,
            f"incr/{RESOLUTION_UNIT[ax.kind]}",
            f"getriebe[{gi}].wegaufz / wegaufn now",
        ),
    )
    notes: list[str] = [note] if note else []
    changes: tuple[Change, ...] = ()
    if abs(off_ppm) > tolerance_ppm:
        why = f"the encoder delivers k = {k:.6g} × the increments per unit set"
        changes = (
            Change(ax.name, f"getriebe[{gi}].wegaufz", z, new_z, why),
            Change(ax.name, f"getriebe[{gi}].wegaufn", n, new_n, why),
        )
        notes.append(f"the NC counts {off_ppm:+.0f} ppm of the true travel: wegaufz/wegaufn · k")
    else:
        notes.append("wegaufz/wegaufn match the encoder: the travels agree")
    t = np.arange(sum(len(x) for x in lags)) * cycle_s
    lag = np.concatenate(lags) if lags else np.zeros(0)
    return Result(
        "resolution-check",
        figures,
        changes,
        (Series("lag", *_thin(t, lag), "s", unit),),
        tuple(notes),
        True,
        {"axis": ax.name, "distance": distance, "feed_mm_min": feed_mm_min},
    )
