"""Step responses of an axis' speed loop and position loop, small and from rest, beside what
the drive's own parameters expect (nc_sim/plant/linear.py: the cascade on the rigid inertia
p0341 · p0342, no friction): rise time (10-90 %), overshoot, settling time (±2 %).

- speed loop: a speed setpoint step at the drive with the NC's position loop open (the NC
  follows meanwhile, as in speed control); afterwards the axis is moved back to where it was;
- position loop: a step of the position command as the NC's controller sees it (the axis
  goes back by itself when the step ends).
"""

from __future__ import annotations

import numpy as np

from nc_sim.assist.drive_axis import drive_axis
from nc_sim.assist.procedure import Procedure, Wait, on_copy
from nc_sim.assist.result import ExperimentError, Figure, Result, Series
from nc_sim.commands import Accepted, Move
from nc_sim.config import MachineConfig
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.plant import layout as PL
from nc_sim.plant.linear import nominal, position_step, speed_step, step_figures
from nc_sim.plant.model import DriveModel
from nc_sim.snapshot import AxisState
from nc_sim.units import RPM_TO_RAD_S

SPEED, POSITION = 1, 2
LEAD_S = 0.05  # at rest before the step: the baseline
MAX_PLOT_POINTS = 1500


def step_response_experiment(
    cfg: MachineConfig,
    axis: str,
    loop: int = SPEED,
    speed_rpm: float = 50.0,
    position_mm: float = 0.05,
    duration_s: float = 0.5,
) -> Result:
    """`step_response` on a fresh copy of the machine `cfg` describes."""
    return on_copy(cfg, lambda m: step_response(m, axis, loop, speed_rpm, position_mm, duration_s))


def step_response(
    m: Machine,
    axis: str,
    loop: int = SPEED,
    speed_rpm: float = 50.0,
    position_mm: float = 0.05,
    duration_s: float = 0.5,
) -> Procedure:
    """A step of `speed_rpm` (the speed loop) or `position_mm` (the position loop) on `axis`
    at rest, recorded for `duration_s`."""
    ax, model = drive_axis(m, axis, "a step of its drive")
    if ax.state is not AxisState.STANDSTILL:
        raise ExperimentError(f"{ax.name} must stand still for a step ({ax.state.name})")
    k = m.k
    cycle_s = k.cycle_s
    steps = model.substeps
    speed = loop != POSITION
    lead = round(LEAD_S / cycle_s)
    cycles = lead + round(duration_s / cycle_s)
    if speed:
        step = speed_rpm * RPM_TO_RAD_S
        exc = np.zeros(cycles * steps)
        exc[lead * steps :] = step
        point = PL.INJECT_SPEED_OPEN
    else:
        step = position_mm
        exc = np.zeros(cycles * steps)
        exc[lead * steps :] = step
        point = PL.INJECT_POSITION
    p0 = float(k.st[ax.slot, L.S_P_CMD])
    what = "speed" if speed else "position"
    try:
        k.start_probe(ax.slot, exc, point)
        yield Wait(cycles, f"{ax.name}: a {what} step", cycles * cycle_s + 0.5)
        trace = k.probe_trace().copy()
    finally:
        if k.probe[PL.PR_SLOT] == ax.slot:
            k.stop_probe()
    if speed:  # back to where it stood
        out = m.submit(Move(ax.name, p0, rapid=False, feed_mm_min=1000.0))
        if isinstance(out, Accepted):
            while ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
                yield Wait(20, f"{ax.name} goes back to {p0:g}", cycles * cycle_s + 0.5)
    kv = float(k.pr[ax.slot, L.P_KV])
    return _analyse(ax.name, speed, step, trace, steps, lead, model, kv, cycle_s, duration_s)


def _thin(t: np.ndarray, y: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...]]:
    every = max(1, len(t) // MAX_PLOT_POINTS)
    return tuple(float(v) for v in t[::every]), tuple(float(v) for v in y[::every])


def _analyse(
    name: str,
    speed: bool,
    step: float,
    trace: np.ndarray,
    steps: int,
    lead: int,
    model: DriveModel,
    kv: float,
    cycle_s: float,
    duration_s: float,
) -> Result:
    drive = nominal(model)
    if speed:
        w = trace[:, PL.D_W_MOTOR]
        base = float(np.mean(w[: lead * steps]))
        y = w[lead * steps :] - base
        dt = model.sampling_s
        expected = speed_step(drive, step, len(y) * dt)
        scale, unit, label = 1.0 / RPM_TO_RAD_S, "rpm", "motor speed"
    else:
        p = trace[::steps, PL.D_P_ACT]
        base = float(np.mean(p[:lead]))
        y = p[lead:] - base
        dt = cycle_s
        expected = position_step(drive, kv, cycle_s, step, len(y) * dt)
        scale, unit, label = 1.0, "mm", "position"
    t = np.arange(len(y)) * dt
    got = step_figures(t, y, step)
    want = step_figures(t, expected, step)
    figures: list[Figure] = []
    for key, text, a, b, fig_unit in (
        ("rise_ms", "rise time 10-90 %", got.rise_s, want.rise_s, "ms"),
        ("overshoot_pct", "overshoot", got.overshoot_pct, want.overshoot_pct, "%"),
        ("settling_ms", "settling into ±2 %", got.settling_s, want.settling_s, "ms"),
    ):
        factor = 1000.0 if fig_unit == "ms" else 1.0
        if a is not None:
            figures.append(Figure(key, a * factor, fig_unit, f"{text}, measured"))
        if b is not None:
            figures.append(Figure(f"{key}_expected", b * factor, fig_unit, f"{text}, linear model"))
    notes = [
        f"{name}: a {'speed' if speed else 'position'} step of {step * scale:g} {unit} from rest; "
        "expected: the drive's own parameters on a rigid axis (p0341 · p0342, no friction)"
    ]
    if got.settling_s is None:
        notes.append(f"not settled within {duration_s:g} s: a longer duration, or the loop rings")
    if want.overshoot_pct + 5.0 < got.overshoot_pct:
        notes.append(
            "more overshoot than the parameters expect: the mechanics (a resonance, backlash) "
            "take part; measure the frequency response"
        )
    series = (
        Series(label, *_thin(t, y * scale), "s", unit),
        Series(f"{label} (linear model)", *_thin(t, expected * scale), "s", unit),
    )
    inputs: dict[str, float | int | str] = {"axis": name, "loop": SPEED if speed else POSITION}
    return Result("step-response", tuple(figures), (), series, tuple(notes), inputs=inputs)
