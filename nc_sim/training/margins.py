"""The speed-loop check of a tuning exercise: the margins and bandwidth the axis' speed loop
has now, on the plant it really drives.

The grader knows what the student can only measure: the drive cascade and mechanics with the
training faults in force (nc_sim/axis/plant.py's `drive_model`). From it and the drive's
parameters as they stand it computes the open loop exactly (`DriveModel.speed_open_loop`) and
reads margins, crossover and bandwidth on its Nyquist curve as the autotune does
(nc_sim/plant/tuning.py). The bandwidth is judged against the best the same template allows
on that plant: the autotune's search (gain, integral time, one notch on the resonance) run on
the exact loop with the drive's low-pass filters, so a student who only lowers the gain keeps
the margins and still falls short.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from nc_sim.axis.plant import cascade, drive_model
from nc_sim.plant.model import DriveModel
from nc_sim.plant.tuning import TEMPLATES, LoopFigures, loop_figures, tune

if TYPE_CHECKING:
    from nc_sim.events import Event
    from nc_sim.machine.machine import Machine

F_MIN_HZ = 1.0
POINTS = 1500  # log-spaced frequencies up to the drive's Nyquist frequency
KP_REF_CROSSOVER_HZ = 50.0


def open_loop_figures(model: DriveModel) -> LoopFigures | None:
    """Margins, crossover and bandwidth of the model's speed loop (None: not stable)."""
    f = _grid(model)
    return loop_figures(f, model.speed_open_loop(f))


def best_bandwidth_hz(model: DriveModel, template: int) -> float:
    """The highest closed-loop bandwidth template `template` allows on the model's plant:
    the autotune's search on the exact loop, with the drive's low-pass filters and room for
    one notch on the resonance (0 when nothing keeps the template)."""
    bare = _bare(model)
    f = _grid(model)
    resonance = model.anti_resonance_hz * math.sqrt(model.inertia_ratio) if model.two_mass else None
    # the search spans KP_RANGE about a gain of the plant's own scale (a 50 Hz crossover on
    # its whole inertia), not the student's gain: the best must not depend on what they set
    kp_ref = model.total_inertia * 2.0 * math.pi * KP_REF_CROSSOVER_HZ
    best = tune(
        f, bare.speed_open_loop(f), model.sampling_s, TEMPLATES[template], kp_ref, resonance
    )
    return best.figures.bandwidth_hz if best is not None else 0.0


def _bare(model: DriveModel) -> DriveModel:
    """The plant the best is searched on: no controller, only the low-pass filters."""
    lowpass = tuple(f for f in model.filters if f.numerator_hz <= 0.0)
    return replace(model, kp=1.0, tn_s=0.0, filters=lowpass)


def _grid(model: DriveModel) -> np.ndarray:
    return np.geomspace(F_MIN_HZ, 0.49 / model.sampling_s, POINTS)


class MarginsEvaluator:
    """Judged at every feed on the drive model as it stands; the figures are computed again
    only when the model changed (a parameter, a fault, a gear), the best bandwidth only when
    the plant did."""

    def __init__(self, axis: str, template: int, bandwidth_pct: float, m: Machine) -> None:
        """The check of checks.MarginsCheck (its fields: this module does not import it)."""
        self.ax = m.axis(axis)
        self.cycle_s = m.k.cycle_s
        self.template_id = template
        self.template = TEMPLATES[template]
        self.bandwidth_pct = bandwidth_pct
        self.passed = False
        self.first_passed_cycle: int | None = None
        self.detail = "not evaluated yet"
        self._model: DriveModel | None = None
        self._plant: DriveModel | None = None
        self._best_hz = 0.0

    def feed(self, rows: np.ndarray, first_cycle: int, events: list[Event], now: int) -> None:
        ax = self.ax
        if not cascade(ax.cfg):
            self.passed = False
            self.detail = f"{ax.name} runs the ideal drive (sim.plant): no speed loop to judge"
            return
        model = drive_model(ax.cfg, self.cycle_s, ax.plant, ax.gear)
        if model == self._model:
            return
        self._model = model
        fig = open_loop_figures(model)
        t = self.template
        name = f"the {t.name} template ({t.phase_margin_deg:g}°, {t.gain_margin_db:g} dB)"
        if fig is None:
            self._set(False, now, f"{ax.name}'s speed loop is not stable: it keeps no margin")
            return
        said = (
            f"phase margin {fig.phase_margin_deg:.1f}°, gain margin {fig.gain_margin_db:.1f} dB"
            f", bandwidth {fig.bandwidth_hz:.1f} Hz"
        )
        short = []
        if fig.phase_margin_deg < t.phase_margin_deg:
            short.append("phase margin")
        if fig.gain_margin_db < t.gain_margin_db:
            short.append("gain margin")
        kept = f"short of {name} in {' and '.join(short)}" if short else f"keeps {name}"
        if self.bandwidth_pct <= 0.0:
            self._set(not short, now, f"{said}: {kept}")
            return
        plant = _bare(model)
        if plant != self._plant:
            self._plant = plant
            self._best_hz = best_bandwidth_hz(model, self.template_id)
        share = fig.bandwidth_hz / self._best_hz * 100.0 if self._best_hz > 0.0 else 0.0
        self._set(
            not short and share >= self.bandwidth_pct,
            now,
            f"{said}: {kept}; {share:.0f} % of the best bandwidth it allows"
            f" ({self._best_hz:.1f} Hz; {self.bandwidth_pct:g} % wanted)",
        )

    def _set(self, passed: bool, now: int, detail: str) -> None:
        self.passed = passed
        if passed and self.first_passed_cycle is None:
            self.first_passed_cycle = now
        self.detail = detail
