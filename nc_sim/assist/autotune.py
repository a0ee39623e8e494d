"""Speed-loop autotune with a stability template: measure, tune, validate (issue 38).

1. Measure the mechanics (torque to motor speed) for the resonance a notch may go on, and
   the open speed loop as the drive runs it now (nc_sim/assist/frequency_response.py).
2. Divide the drive's own PI out of the open loop: what remains is the measured loop
   without its controller. Search gain, integral time and a notch on the measured resonance
   for the highest bandwidth that keeps the template's margins (nc_sim/plant/tuning.py).
   Nothing of the simulated plant's hidden parameters is used: a soft coupling, friction or
   a training fault are in the measurement, nowhere else.
3. Validate (on a copy): the new values in force, the open loop measured again; achieved
   margins and bandwidth beside the template and the prediction; the old values back.
4. The position loop: kv from the tuned speed loop's bandwidth (a step without overshoot)
   and the lag the feedforward weighting leaves, with the manual's lag formula.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Generator
from functools import partial

import numpy as np

from nc_sim.assist.drive_axis import drive_axis
from nc_sim.assist.frequency_response import MECHANICS, OPEN_SPEED, Measured, measure
from nc_sim.assist.procedure import Procedure, Wait, on_copy
from nc_sim.assist.result import Change, ExperimentError, Figure, Result, Series, Value
from nc_sim.config import AxisConfig, MachineConfig, apply_overrides
from nc_sim.machine.machine import Machine
from nc_sim.params import Scope
from nc_sim.params.plant import CURRENT_FILTERS
from nc_sim.plant import frf
from nc_sim.plant.tuning import TEMPLATES, LoopFigures, Tuning, loop_figures, pi_response, tune

MAX_PLOT_POINTS = 400
UNIT_FEED_MM_MIN = 1000.0  # the lag formula's example speed: 1 m/min


def autotune_experiment(
    cfg: MachineConfig,
    axis: str,
    template: int = 1,
    torque_pct: float = 2.0,
    speed_rpm: float = 10.0,
    offset_rpm: float = 60.0,
    f_min_hz: float = 5.0,
    averages: int = 6,
    window_mm: float = 50.0,
) -> Result:
    """`autotune` on a fresh copy of the machine `cfg` describes, validated on it."""
    return on_copy(
        cfg,
        lambda m: autotune(
            m, axis, template, torque_pct, speed_rpm, offset_rpm, f_min_hz, averages, window_mm
        ),
    )


def autotune(
    m: Machine,
    axis: str,
    template: int = 1,
    torque_pct: float = 2.0,
    speed_rpm: float = 10.0,
    offset_rpm: float = 60.0,
    f_min_hz: float = 5.0,
    averages: int = 6,
    window_mm: float = 50.0,
    validate: bool = True,
) -> Procedure:
    """Measure `axis`' mechanics and open speed loop, tune to `template` (1 stiff, 2 medium,
    3 soft), and with `validate` measure the tuned loop again on this machine (a copy)."""
    if template not in TEMPLATES:
        raise ExperimentError(f"template: 1, 2 or 3, not {template}")
    t = TEMPLATES[template]
    ax, model = drive_axis(m, axis, "the autotune")

    def measured(what: int, name: str) -> Generator[Wait, np.ndarray, Measured]:
        return measure(
            m,
            name,
            what,
            1,
            torque_pct,
            speed_rpm,
            0.1,
            offset_rpm,
            f_min_hz,
            None,
            averages,
            window_mm,
        )

    mech = yield from measured(MECHANICS, ax.name)
    loop = yield from measured(OPEN_SPEED, ax.name)
    peaks, _dips = frf.resonances(mech.h)
    resonance = min(peaks) if peaks else None
    f = loop.h.f_hz
    plant = loop.h.h / pi_response(model.kp, model.tn_s, model.sampling_s, f)
    now = loop_figures(f, loop.h.h)
    found = tune(f, plant, model.sampling_s, t, model.kp, resonance)
    if found is None:
        return Result(
            "autotune",
            _now_figures(now),
            notes=(
                f"no gain and integral time keep the {t.name} template ({t.phase_margin_deg:g}°, "
                f"{t.gain_margin_db:g} dB) on the measured loop: a softer template, or the "
                "mechanics first (the mechanics measurement shows where)",
            ),
            ok=False,
            inputs={"axis": ax.name, "template": template},
        )
    changes = _changes(ax.cfg, ax.name, model.kp, model.tn_s, found, resonance)
    achieved: LoopFigures | None = None
    again: Measured | None = None
    if validate:
        again = yield from _validate(m, ax.name, changes, measured)
        achieved = loop_figures(again.h.f_hz, again.h.h)
    predicted = found.kp * pi_response(1.0, found.tn_s, model.sampling_s, f) * plant
    if found.notch is not None:
        predicted = predicted * found.notch.response(f)
    kv_changes, kv_figures, kv_notes = _position_loop(
        ax.cfg, ax.name, ax.gear, found.figures.bandwidth_hz, m.k.cycle_s
    )
    figures = [
        *_now_figures(now),
        Figure("kp", found.kp, "Nm·s/rad", "proposed speed gain (p1460)"),
        Figure("tn_ms", found.tn_s * 1000.0, "ms", "proposed integral time (p1462)"),
        Figure("target_pm_deg", t.phase_margin_deg, "°", f"template {t.name}: phase margin"),
        Figure("target_gm_db", t.gain_margin_db, "dB", f"template {t.name}: gain margin"),
        Figure("pm_deg", found.figures.phase_margin_deg, "°", "predicted phase margin"),
        Figure("gm_db", found.figures.gain_margin_db, "dB", "predicted gain margin"),
        Figure("crossover_hz", found.figures.crossover_hz, "Hz", "predicted crossover"),
        Figure("bandwidth_hz", found.figures.bandwidth_hz, "Hz", "predicted bandwidth (−3 dB)"),
    ]
    if found.notch is not None:
        figures.append(Figure("notch_hz", found.notch.f_hz, "Hz", "notch on the resonance"))
    if resonance is not None:
        figures.append(Figure("resonance_hz", resonance, "Hz", "first resonance, measured"))
    if achieved is not None and again is not None:
        at = found.figures.crossover_hz
        h_again = complex(
            np.interp(at, again.h.f_hz, again.h.h.real), np.interp(at, again.h.f_hz, again.h.h.imag)
        )
        h_pred = complex(np.interp(at, f, predicted.real), np.interp(at, f, predicted.imag))
        figures += [
            Figure(
                "crossover_db_measured",
                20 * math.log10(abs(h_again)),
                "dB",
                "|L| there, measured again",
            ),
            Figure("crossover_deg_measured", math.degrees(np.angle(h_again)), "°", "its phase"),
            Figure(
                "prediction_error_db",
                20 * math.log10(abs(h_again) / abs(h_pred)),
                "dB",
                "measured minus predicted at the crossover",
            ),
            Figure(
                "prediction_error_deg",
                math.degrees(np.angle(h_again / h_pred)),
                "°",
                "measured minus predicted at the crossover",
            ),
        ]
        figures += [
            Figure("pm_achieved_deg", achieved.phase_margin_deg, "°", "phase margin, measured"),
            Figure("gm_achieved_db", achieved.gain_margin_db, "dB", "gain margin, measured"),
            Figure("bandwidth_achieved_hz", achieved.bandwidth_hz, "Hz", "bandwidth, measured"),
        ]
    figures += kv_figures
    notes = [
        f"{ax.name}: the {t.name} template (≥ {t.phase_margin_deg:g}°, ≥ {t.gain_margin_db:g} dB) "
        f"on the measured open loop; the gain stopped at {found.limited_by}",
    ]
    if found.notch is not None:
        notes.append(
            f"a notch on the resonance at {found.notch.f_hz:.1f} Hz (width D = "
            f"{found.notch.width:g}, −20 dB at its centre) lets the gain rise"
        )
    elif resonance is not None:
        notes.append(
            f"the resonance at {resonance:.1f} Hz does not limit the gain (as the current "
            "filters shape the loop): no new notch"
        )
    if not changes:
        notes.append("the speed loop already is what the template allows: nothing to change")
    if validate and achieved is None:
        notes.append("measured again with the new values, the loop was not stable: keep the old")
    elif achieved is not None:
        short = (
            achieved.phase_margin_deg < t.phase_margin_deg - 2.0
            or achieved.gain_margin_db < t.gain_margin_db - 1.0
        )
        notes.append(
            f"measured again on the copy: {achieved.phase_margin_deg:.1f}°, "
            f"{achieved.gain_margin_db:.1f} dB, bandwidth {achieved.bandwidth_hz:.1f} Hz"
            + (": short of the template, read the curve" if short else ": the template holds")
        )
    else:
        notes.append("apply on trial, then measure the open speed loop again to validate")
    notes += kv_notes
    series = _bode(f, loop.h.h, predicted, again)
    inputs: dict[str, Value] = {"axis": ax.name, "template": template}
    return Result(
        "autotune",
        tuple(figures),
        (*changes, *kv_changes),
        series,
        tuple(notes),
        achieved is not None or not validate,
        inputs,
    )


# on the machine itself: measured and tuned there; the new values are not tried on it
# (apply them on trial, then measure the open speed loop again)
autotune_live = partial(autotune, validate=False)


def _now_figures(now: LoopFigures | None) -> tuple[Figure, ...]:
    if now is None:
        return ()
    return (
        Figure("pm_now_deg", now.phase_margin_deg, "°", "phase margin as it is"),
        Figure("gm_now_db", now.gain_margin_db, "dB", "gain margin as it is"),
        Figure("bandwidth_now_hz", now.bandwidth_hz, "Hz", "bandwidth as it is"),
    )


def _sig(v: float) -> float:
    """Four significant digits: what a drive's parameter display shows."""
    return float(f"{v:.4g}")


def _changes(
    cfg: AxisConfig,
    axis: str,
    kp_now: float,
    tn_now_s: float,
    found: Tuning,
    resonance: float | None,
) -> tuple[Change, ...]:
    """The speed controller's new values, and the notch in the first free current filter."""
    value = cfg.raw
    out = [
        c
        for c in (
            Change(axis, "drive.speed_kp", _sig(kp_now), _sig(found.kp), "the template's gain"),
            Change(
                axis,
                "drive.speed_tn",
                round(tn_now_s * 1e6),
                round(found.tn_s * 1e6),
                "the template's integral time, µs",
            ),
        )
        if c.before != c.after
    ]
    notch = found.notch
    if notch is None or resonance is None:
        return tuple(out)
    active = int(value("drive.current_filter_active"))
    free = next((i for i in range(CURRENT_FILTERS) if not active >> i & 1), None)
    if free is None:
        return tuple(out)
    base = f"drive.current_filter_{free + 1}"
    why = f"notch on the resonance at {notch.f_hz:.1f} Hz"
    for name, after in (
        ("type", "GENERAL_2ND_ORDER"),
        ("denominator_frequency", round(notch.f_hz, 1)),
        ("denominator_damping", notch.width),
        ("numerator_frequency", round(notch.f_hz, 1)),
        ("numerator_damping", round(notch.depth, 4)),
    ):
        before = value(f"{base}.{name}")
        if before != after:
            out.append(Change(axis, f"{base}.{name}", before, after, why))
    out.append(
        Change(
            axis, "drive.current_filter_active", active, active | 1 << free, f"filter {free + 1} on"
        )
    )
    return tuple(out)


def _validate(
    m: Machine,
    axis: str,
    changes: tuple[Change, ...],
    measured: Callable[[int, str], Generator[Wait, np.ndarray, Measured]],
) -> Generator[Wait, np.ndarray, Measured]:
    """The open loop measured again with `changes` in force on this machine (a copy), its
    values as they were afterwards."""
    ax = m.axis(axis)
    before = {c.parameter: ax.cfg.raw(c.parameter) for c in changes}
    apply_overrides(m.cfg, Scope.AXIS, axis, {c.parameter: c.after for c in changes})
    m.refresh_params()
    try:
        again = yield from measured(OPEN_SPEED, axis)
    finally:
        apply_overrides(m.cfg, Scope.AXIS, axis, before)
        m.refresh_params()
    return again


def _position_loop(
    cfg: AxisConfig, axis: str, gear: int, bandwidth_hz: float, cycle_s: float
) -> tuple[tuple[Change, ...], list[Figure], list[str]]:
    """kv for a position step without overshoot on the tuned speed loop: the speed loop as a
    lag of 1/(2π·f_bw) plus the NC's cycle and a half (sampling and output), a P position loop
    around it critically damped at kv = 1/(4·T); the lag the feedforward weighting leaves,
    s = (1 − ff)·v/kv (004 §3.6)."""
    t_eq = 1.0 / (2.0 * math.pi * bandwidth_hz) + 1.5 * cycle_s
    kv_max = 1.0 / (4.0 * t_eq)
    kv_raw = int(cfg.raw("getriebe.kv", gear))
    kv = kv_raw / 100.0
    ff = cfg.eng("lr_param.ff_weight")
    v = UNIT_FEED_MM_MIN / 60.0
    lag = (1.0 - ff) * v / kv
    gi = gear - 1
    figures = [
        Figure("kv_max", kv_max, "1/s", "highest kv without overshoot on the tuned speed loop"),
        Figure("lag_1m_min_mm", lag, "mm", "lag at 1 m/min: (1 − ff_weight)·v/kv"),
    ]
    notes = [
        f"position loop: kv ≤ 1/(4·T) = {kv_max:.1f}/s with T = 1/(2π·{bandwidth_hz:.1f} Hz) + 1.5 "
        f"NC cycles; at 1 m/min the lag is s = (1 − {ff:g})·v/kv = {lag * 1000:.0f} µm "
        "(004 §3.6: s = v/kv without feedforward)"
    ]
    changes: tuple[Change, ...] = ()
    new_raw = math.floor(kv_max * 100.0)
    if kv > kv_max:
        changes = (Change(axis, f"getriebe[{gi}].kv", kv_raw, new_raw, "no overshoot"),)
        notes.append(f"kv {kv:g}/s overshoots on this speed loop: lower it to {new_raw / 100:g}/s")
    elif kv < 0.5 * kv_max:
        notes.append(
            f"kv {kv:g}/s uses half of what the speed loop allows or less: up to "
            f"{kv_max:.1f}/s, the same on every axis of a plane (the circle's kv matching)"
        )
    return changes, figures, notes


def _bode(
    f: np.ndarray, now: np.ndarray, predicted: np.ndarray, again: Measured | None
) -> tuple[Series, ...]:
    """The open loop as measured, as predicted with the new values and as measured again."""
    keep = np.unique(
        np.searchsorted(f, np.geomspace(f[0], f[-1], MAX_PLOT_POINTS)).clip(0, len(f) - 1)
    )
    fx = tuple(float(v) for v in f[keep])

    def pair(label: str, h: np.ndarray) -> tuple[Series, Series]:
        mag = 20.0 * np.log10(np.abs(h[keep]))
        phase = np.degrees(np.unwrap(np.angle(h[keep])))
        return (
            Series(f"magnitude_db@{label}", fx, tuple(float(v) for v in mag), "Hz", "dB"),
            Series(f"phase_deg@{label}", fx, tuple(float(v) for v in phase), "Hz", "°"),
        )

    out = [*pair("now", now), *pair("predicted", predicted)]
    if again is not None:
        h = np.interp(f, again.h.f_hz, again.h.h.real) + 1j * np.interp(
            f, again.h.f_hz, again.h.h.imag
        )
        out += pair("measured again", h)
    return tuple(out)
