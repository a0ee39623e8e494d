"""What the drive's own parameters make of a step: the linear model a drive engineer has at
hand (the cascade of nc_sim/plant/model.py on a rigid mass of the inertia the drive is told,
p0341 · p0342, no friction, no backlash), stepped exactly as the kernel steps it.

The measured step differs from it by what the drive does not know: the coupling's resonance,
friction, backlash. That difference is what the engineer reads.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from nc_sim.plant import layout as PL
from nc_sim.plant.model import DriveModel


@dataclass(frozen=True)
class StepFigures:
    """Rise time (10 % to 90 %), overshoot (% of the step), settling time (into ±band of the
    step for good), each None where the response never gets there."""

    rise_s: float | None
    overshoot_pct: float
    settling_s: float | None


def step_figures(t: np.ndarray, y: np.ndarray, step: float, band: float = 0.02) -> StepFigures:
    """The figures of response `y` (from 0 at t[0]) to a step of `step`."""
    r = y / step
    above10 = np.flatnonzero(r >= 0.1)
    above90 = np.flatnonzero(r >= 0.9)
    rise = float(t[above90[0]] - t[above10[0]]) if len(above10) and len(above90) else None
    overshoot = max(0.0, float(np.max(r)) - 1.0) * 100.0
    overshoot = 0.0 if overshoot < 1e-6 else overshoot  # round-off of a response that creeps in
    outside = np.flatnonzero(np.abs(r - 1.0) > band)
    if len(outside) == 0:
        settling: float | None = 0.0
    elif outside[-1] + 1 < len(t):
        settling = float(t[outside[-1] + 1] - t[0])
    else:
        settling = None
    return StepFigures(rise, overshoot, settling)


def nominal(model: DriveModel) -> DriveModel:
    """The drive's view of its axis: rigid, no friction, no backlash."""
    return replace(
        model,
        anti_resonance_hz=0.0,
        coulomb=0.0,
        breakaway=0.0,
        viscous=0.0,
        backlash=0.0,
    )


class _SpeedLoop:
    """The drive's PI speed loop on the linear part, one drive step at a time, from rest."""

    def __init__(self, model: DriveModel) -> None:
        self.model = model
        self.ad, self.bd = model.discrete()
        self.x = np.zeros(self.ad.shape[0])
        self.t_late = 0.0
        self.integral = 0.0
        self.inv_tn = 1.0 / model.tn_s if model.tn_s > 0.0 else 0.0

    def step(self, w_ref: float) -> None:
        m = self.model
        e = w_ref - self.x[PL.X_WM]
        self.integral += e * m.sampling_s
        t = min(max(m.kp * (e + self.inv_tn * self.integral), -m.torque_limit), m.torque_limit)
        self.x = self.ad @ self.x + self.bd[:, PL.U_TORQUE] * self.t_late
        self.t_late = t


def speed_step(model: DriveModel, step_rad_s: float, seconds: float) -> np.ndarray:
    """Motor speed (rad/s) per drive step after a speed setpoint step, from rest."""
    loop = _SpeedLoop(model)
    out = np.zeros(round(seconds / model.sampling_s))
    for k in range(len(out)):
        out[k] = loop.x[PL.X_WM]
        loop.step(step_rad_s)
    return out


def position_step(
    model: DriveModel, kv: float, cycle_s: float, step: float, seconds: float
) -> np.ndarray:
    """Load position (mm | °) per NC cycle after a position step, from rest: the NC's P
    controller at its cycle on the speed loop at the drive's steps (no feedforward)."""
    loop = _SpeedLoop(model)
    alpha = (
        1.0 - float(np.exp(-model.sampling_s / model.speed_filter_s))
        if model.speed_filter_s > 0.0
        else 1.0
    )
    pos = 0.0
    w_ref = 0.0
    out = np.zeros(round(seconds / cycle_s))
    for c in range(len(out)):
        out[c] = pos
        w_set = kv * (step - pos) / model.unit_per_rad
        for _ in range(model.substeps):
            w_ref += (w_set - w_ref) * alpha
            loop.step(w_ref)
            pos += loop.x[PL.X_TRAVEL] * model.unit_per_rad
            loop.x[PL.X_TRAVEL] = 0.0
    return out
