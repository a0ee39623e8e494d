"""The position loop gain assistant [004 §3.6: "to further optimise the position control loop,
P-AXIS-00099 (getriebe[].kv) is used exclusively"]: step and ramp responses of an axis at
several kv, each on a fresh copy of the machine, measured as an engineer reads them
(nc_sim/measure.py), and the highest kv that meets an overshoot and settling target.

- Step: the NC has no position command jump; its interpolator ramps every move. The step is a
  short G00 move of a small distance (default 20 exact-stop windows), so the axis' rapid
  dynamics make the command nearly a jump and the loop shapes what follows. Overshoot is the
  actual position past the target (mm and % of the step), settling the time from the end of
  the command until the actual position stays inside the exact-stop window
  (kenngr.exact_stop_window): the in-position delay the machine waits for.
- Ramp: a G01 move at constant feed; the lag settles to v/kv (DOMAIN.md §2, without
  feedforward; a wrong multi_gain shows as v/k with k ≠ kv). The lag's transient after the
  command reaches constant speed is measured like the step: overshoot beyond the steady lag,
  settling into ±exact-stop window of it.

The loop is a P controller on a drive with a velocity time constant T (DOMAIN.md §2): for
kv·T < 1/4 it is aperiodic, above it overshoots, so overshoot grows with kv while the
settling time first falls as about 1/kv. Axes only: a spindle's position control (M19, C
axis) runs through orientation and gear logic whose timing is not the loop's.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Generator, Sequence
from dataclasses import dataclass

import numpy as np

from nc_sim.assist.experiments import _refusal  # the NC's refusal in its words, as there
from nc_sim.assist.procedure import Wait, on_copy
from nc_sim.assist.result import Change, ExperimentError, Figure, Result, Series
from nc_sim.commands import Accepted, Move
from nc_sim.config import MachineConfig, apply_overrides
from nc_sim.errors import NcUsageError
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.measure import measure
from nc_sim.params import Scope
from nc_sim.sim import Simulation
from nc_sim.units import MM_MIN_PER_MM_S, MS_PER_S, AxisKind, per_minute

NAME = "loop-gain"
SWEEP_FACTORS = (0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0)  # × the axis' kv when none are given
MAX_KVS = 12  # a sweep longer than this is not read by anyone
STEP_WINDOWS = 20.0  # default step: this many exact-stop windows (settling from 5 % of it)
FEED_SHARE = 0.05  # default ramp feed: this share of the rapid speed (vb_eilgang)
SETTLE_TAUS = 10.0  # recorded after the command ends: 1/kv of the lowest kv this many times
RAMP_WINDOW_S = 0.5  # the steady lag is averaged over this at constant speed
MOVE_LIMIT_S = 60.0  # a command still moving by then: the feed or the dynamics are wrong
RAMP_MARGIN_S = 2.0  # the ramp's travel: up to speed and braking within this much more
PLOT_POINTS = 400  # per response series (a sweep carries two per kv)


@dataclass(frozen=True)
class StepResponse:
    """A G00 step, measured on the actual position."""

    overshoot_pct: float  # past the target, % of the step
    overshoot: float  # past the target, mm | °
    settling_s: float | None  # end of command -> inside the window for good; None: never
    t: np.ndarray
    y: np.ndarray  # actual position from the start, mm | °
    error: str | None = None  # a job error during the run


@dataclass(frozen=True)
class RampResponse:
    """A G01 move at constant speed, measured on the lag."""

    lag: float  # steady lag, mm | °
    lag_overshoot_pct: float  # the lag beyond its steady value, % of it
    lag_settling_s: float | None  # constant speed reached -> lag inside ±window for good
    t: np.ndarray
    y: np.ndarray  # lag, mm | °
    error: str | None = None  # a job error during the run


@dataclass(frozen=True)
class KvResponse:
    """What one kv gave."""

    kv: float  # 1/s
    step: StepResponse
    ramp: RampResponse

    @property
    def error(self) -> str | None:
        """A job error during either run."""
        return self.step.error or self.ramp.error

    def meets(self, overshoot_pct: float, settling_s: float) -> bool:
        """Within the target: overshoot and settling of the step, no job error."""
        return (
            self.error is None
            and self.step.overshoot_pct <= overshoot_pct
            and self.step.settling_s is not None
            and self.step.settling_s <= settling_s
        )


def _with_kv(cfg: MachineConfig, axis: str, gear: int, kv: float) -> MachineConfig:
    """A copy of `cfg` with getriebe[gear-1].kv = kv (1/s)."""
    c = copy.deepcopy(cfg)
    apply_overrides(c, Scope.AXIS, axis, {f"getriebe[{gear - 1}].kv": round(kv * 100.0)})
    return c


def _error(m: Machine, axis: str) -> str | None:
    e = m.axis(axis).error_event
    return None if e is None else e.message


def _step(
    m: Machine, axis: str, distance: float, after_s: float, window: float
) -> Generator[Wait, np.ndarray, StepResponse]:
    """A G00 move of `distance`, recorded until the command ends and `after_s` more:
    overshoot and settling of the actual position."""
    ax = m.axis(axis)
    s, dt = ax.slot, m.k.cycle_s
    p0 = float(m.k.st[s, L.S_P_CMD])
    target = p0 + distance
    out = m.submit(Move(ax.name, target, rapid=True))
    if not isinstance(out, Accepted):
        raise _refusal(out)
    phase = f"{ax.name} steps {distance:+g} {ax.pos_unit}"
    chunks: list[np.ndarray] = []
    while True:  # until the interpolator holds the target
        chunks.append((yield Wait(10, phase, after_s)))
        st = m.k.st[s]
        if (st[L.S_V_CMD] == 0.0 and abs(st[L.S_P_CMD] - target) < 1e-9) or _error(m, axis):
            break
        if len(chunks) * 10 * dt > MOVE_LIMIT_S:
            raise ExperimentError(f"the step did not end within {MOVE_LIMIT_S:g} s")
    rec = np.concatenate(chunks)
    moving = np.flatnonzero(
        (rec[:, s, L.R_V_CMD] != 0.0) | (np.abs(rec[:, s, L.R_P_CMD] - target) > 1e-9)
    )
    t_end = (int(moving[-1]) + 1) * dt if moving.size else 0.0
    chunks.append((yield Wait(max(1, round(after_s / dt)), f"{ax.name} settles", after_s)))
    rec = np.concatenate(chunks)
    t = np.arange(rec.shape[0]) * dt
    p = rec[:, s, L.R_P_ACT]
    mes = measure(t, p, band_abs=window, t_ref_s=t_end, final=target)
    past = float(np.max((p - target) * math.copysign(1.0, distance)))
    return StepResponse(
        mes.overshoot_pct or 0.0, max(0.0, past), mes.settling_time_s, t, p - p0, _error(m, axis)
    )


def _ramp(
    m: Machine, axis: str, feed: float, v: float, after_s: float, window: float
) -> Generator[Wait, np.ndarray, RampResponse]:
    """A G01 move at `feed` (v in unit/s, signed), recorded up to constant speed and
    `after_s` plus the averaging window more: the steady lag and its transient."""
    ax = m.axis(axis)
    s, dt = ax.slot, m.k.cycle_s
    p0 = float(m.k.st[s, L.S_P_CMD])
    # as far as the recording needs, and no further (the soft limits stay out of it)
    target = p0 + v * (after_s + RAMP_WINDOW_S + RAMP_MARGIN_S)
    out = m.submit(Move(ax.name, target, rapid=False, feed_mm_min=feed))
    if not isinstance(out, Accepted):
        raise _refusal(out)
    phase = f"{ax.name} moves at {feed:g} {ax.pos_unit}/min"
    planned = after_s + RAMP_WINDOW_S
    chunks: list[np.ndarray] = []
    for _ in range(round(RAMP_MARGIN_S / dt / 10)):  # up to speed first
        chunks.append((yield Wait(10, phase, planned)))
        if abs(m.k.st[s, L.S_V_CMD] - v) <= 1e-9 * abs(v) or _error(m, axis):
            break
    chunks.append((yield Wait(max(1, round(planned / dt)), phase, planned)))
    rec = np.concatenate(chunks)
    t = np.arange(rec.shape[0]) * dt
    lag = rec[:, s, L.R_LAG]
    constant = np.abs(rec[:, s, L.R_V_CMD] - v) <= 1e-9 * abs(v)
    last = t >= t[-1] - RAMP_WINDOW_S
    error = _error(m, axis)
    if error is None and not constant.any():
        raise ExperimentError("the ramp never reached constant speed: a lower feed")
    if error is None and not constant[last].all():
        raise ExperimentError("the ramp did not hold constant speed to the end: a lower feed")
    t_const = float(t[np.flatnonzero(constant)[0]]) if constant.any() else float(t[0])
    lag_steady = float(np.mean(lag[last]))
    mes = measure(t, lag, band_abs=window, t_ref_s=t_const, final=lag_steady)
    return RampResponse(lag_steady, mes.overshoot_pct or 0.0, mes.settling_time_s, t, lag, error)


def _thin(t: np.ndarray, y: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...]]:
    step = max(1, math.ceil(len(t) / PLOT_POINTS))
    return tuple(float(v) for v in t[::step]), tuple(float(v) for v in y[::step])


def sweep(kv_now: float, kvs: Sequence[float] | None) -> list[float]:
    """The kv values to try (1/s), ascending: `kvs`, or SWEEP_FACTORS × the axis' kv."""
    chosen = list(kvs) if kvs else [round(kv_now * f, 2) for f in SWEEP_FACTORS]
    if any(not math.isfinite(k) or k <= 0 for k in chosen):
        raise ExperimentError("kv values must be > 0 (1/s)")
    if len(chosen) > MAX_KVS:
        raise ExperimentError(f"at most {MAX_KVS} kv values, not {len(chosen)}")
    return sorted(set(chosen))


def loop_gain(
    cfg: MachineConfig,
    axis: str,
    kvs: Sequence[float] | None = None,
    overshoot_pct: float = 5.0,
    settle_ms: float = 200.0,
    step: float | None = None,
    feed_mm_min: float | None = None,
    direction: int = 1,
) -> Result:
    """Step and ramp of `axis` at each kv of `kvs` (1/s; default a sweep around its kv): a
    G00 `step` (mm | °, default 20 exact-stop windows) and a G01 ramp at `feed_mm_min`
    (default 5 % of the rapid speed), in `direction`. Proposes the highest kv whose step
    overshoots at most `overshoot_pct` % and settles into the exact-stop window within
    `settle_ms` after the command ends."""
    try:  # the machine as built (its gear), not powered: what the sweep starts from
        ax = Simulation(cfg.cycle_s).add(copy.deepcopy(cfg)).axis(axis)
    except (NcUsageError, ValueError) as e:
        raise ExperimentError(str(e)) from None
    if ax.kind is AxisKind.SPINDLE:
        raise ExperimentError(f"{ax.name} is a spindle: the loop gain assistant tunes axes")
    if direction not in (1, -1):
        raise ExperimentError("direction must be 1 or -1")
    if overshoot_pct < 0 or settle_ms <= 0:
        raise ExperimentError("targets: overshoot_pct ≥ 0 %, settle_ms > 0 ms")
    g, unit, name = ax.gear, ax.pos_unit, ax.name
    kv_raw = int(ax.cfg.raw("getriebe.kv", g))
    window = ax.cfg.eng("kenngr.exact_stop_window")
    distance = (step if step else STEP_WINDOWS * window) * direction
    if distance == 0:
        raise ExperimentError("the step needs a distance: exact_stop_window is 0, give step")
    feed = feed_mm_min or float(
        f"{per_minute(FEED_SHARE * ax.cfg.eng('getriebe.vb_eilgang', g)):.2g}"
    )
    if feed <= 0:
        raise ExperimentError("the ramp needs a feed: feed_mm_min > 0")
    v = feed / MM_MIN_PER_MM_S * direction
    ff = ax.cfg.eng("lr_param.ff_weight")
    kv_list = sweep(kv_raw / 100.0, kvs)
    after_s = SETTLE_TAUS / kv_list[0]  # the same length for every kv: one time axis
    responses: list[KvResponse] = []
    for kv in kv_list:
        c = _with_kv(cfg, name, g, kv)
        st = on_copy(c, lambda m: _step(m, name, distance, after_s, window))
        rp = on_copy(c, lambda m: _ramp(m, name, feed, v, after_s, window))
        responses.append(KvResponse(kv, st, rp))
    target = Target(overshoot_pct, settle_ms / MS_PER_S)
    setup = Setup(name, g, unit, kv_raw, distance, feed, v, ff, window)
    return _answer(setup, target, responses)


@dataclass(frozen=True)
class Target:
    """What the step must meet."""

    overshoot_pct: float
    settling_s: float


@dataclass(frozen=True)
class Setup:
    """The sweep's fixed inputs, as the answer reports them."""

    axis: str
    gear: int
    unit: str  # mm | °
    kv_raw: int  # getriebe[g].kv now, 0.01/s
    step: float  # signed, mm | °
    feed: float  # unit/min
    v: float  # signed, unit/s
    ff: float  # feedforward weight, 0..1
    window: float  # exact-stop window, mm | °


def _figures(su: Setup, r: KvResponse) -> list[Figure]:
    """One kv's figures, named `quantity@kv` (kv in 1/s)."""
    u, at = su.unit, f"@{r.kv:g}"
    expected = abs(su.v) * (1.0 - su.ff) / r.kv
    out = [
        Figure("overshoot_pct" + at, r.step.overshoot_pct, "%", "step: past the target"),
        Figure("overshoot" + at, r.step.overshoot, u, "step: past the target"),
    ]
    if r.step.settling_s is not None:
        out.append(
            Figure("settling_ms" + at, r.step.settling_s * MS_PER_S, "ms", "step: into the window")
        )
    out += [
        Figure("lag" + at, abs(r.ramp.lag), u, "ramp: steady lag"),
        Figure("lag_expected" + at, expected, u, "ramp: v/kv (·(1 − ff))"),
        Figure("lag_overshoot_pct" + at, r.ramp.lag_overshoot_pct, "%", "ramp: lag past steady"),
    ]
    if r.ramp.lag_settling_s is not None:
        out.append(
            Figure(
                "lag_settling_ms" + at, r.ramp.lag_settling_s * MS_PER_S, "ms", "ramp: lag settled"
            )
        )
    return out


def _answer(su: Setup, target: Target, responses: list[KvResponse]) -> Result:
    gi = su.gear - 1
    meeting = [r for r in responses if r.meets(target.overshoot_pct, target.settling_s)]
    chosen = meeting[-1] if meeting else None
    figures = [
        Figure("kv", su.kv_raw / 100.0, "1/s", f"getriebe[{gi}].kv (P-AXIS-00099) now"),
        Figure("step", abs(su.step), su.unit, "G00 step"),
        Figure("feed", su.feed, f"{su.unit}/min", "G01 ramp"),
        Figure("window", su.window, su.unit, "exact-stop window (settling band)"),
        Figure("overshoot_max_pct", target.overshoot_pct, "%", "target: step overshoot"),
        Figure("settle_max_ms", target.settling_s * MS_PER_S, "ms", "target: step settling"),
    ]
    if chosen is not None:
        figures.append(Figure("kv_new", chosen.kv, "1/s", "the highest kv meeting the target"))
    series: list[Series] = []
    for r in responses:
        figures += _figures(su, r)
        series.append(Series(f"step@{r.kv:g}", *_thin(r.step.t, r.step.y), "s", su.unit))
    for r in responses:
        series.append(Series(f"ramp_lag@{r.kv:g}", *_thin(r.ramp.t, r.ramp.y), "s", su.unit))
    kvs = tuple(r.kv for r in responses)
    settled = [r for r in responses if r.step.settling_s is not None]
    series += [
        Series("overshoot_vs_kv", kvs, tuple(r.step.overshoot_pct for r in responses), "1/s", "%"),
        Series(
            "settling_vs_kv",
            tuple(r.kv for r in settled),
            tuple(r.step.settling_s * MS_PER_S for r in settled if r.step.settling_s is not None),
            "1/s",
            "ms",
        ),
        Series("lag_vs_kv", kvs, tuple(abs(r.ramp.lag) for r in responses), "1/s", su.unit),
    ]
    notes = [
        f"kv = {r.kv:g}/s: the run ended in a job error: {r.error}" for r in responses if r.error
    ]
    aim = f"overshoot ≤ {target.overshoot_pct:g} %, settling ≤ {target.settling_s * MS_PER_S:g} ms"
    changes: list[Change] = []
    if chosen is None:
        slow = all(
            r.step.settling_s is None or r.step.settling_s > target.settling_s for r in responses
        )
        why = (
            "none settles in time: a longer settling target"
            if slow
            else "a lower overshoot target is not met"
        )
        notes.append(f"no kv in the sweep meets the target ({aim}): {why}, or another sweep")
    else:
        kv_new_raw = round(chosen.kv * 100.0)
        if kv_new_raw != su.kv_raw:
            changes.append(
                Change(
                    su.axis,
                    f"getriebe[{gi}].kv",
                    su.kv_raw,
                    kv_new_raw,
                    f"the highest kv with {aim}",
                )
            )
        else:
            notes.append(f"kv = {chosen.kv:g}/s now is already the highest meeting the target")
        if chosen is responses[-1]:
            notes.append(
                "the highest kv of the sweep meets the target: the limit lies above it; "
                "sweep higher to find it"
            )
    if su.ff > 0:
        notes.append(
            f"feedforward ff_weight = {su.ff:g}: the ramp's lag is v/kv·(1 − ff), less than v/kv"
        )
    notes.append(
        "measured on a copy: the simulated drive (its time constant and limits) sets the limit; "
        "a real machine's mechanics (resonances) may set a lower one: raise kv in steps there"
    )
    return Result(
        NAME,
        tuple(figures),
        tuple(changes),
        tuple(series),
        tuple(notes),
        chosen is not None,
        {
            "axis": su.axis,
            "kvs": ",".join(f"{r.kv:g}" for r in responses),
            "overshoot_pct": target.overshoot_pct,
            "settle_ms": target.settling_s * MS_PER_S,
            "step": abs(su.step),
            "feed_mm_min": su.feed,
            "direction": 1 if su.step > 0 else -1,
        },
    )
