"""The acceleration-curve assistant [000 §2.8.4]: run a spindle gear up to its top speed in
simulated time, derive a(n) from the recorded actual speed and fit the curve to it.

Pure: it builds its own machine from the configuration it is given (a copy: the caller's is
left as it was), so the service can preview it and the command line run it headless.
"""

from __future__ import annotations

import copy

import numpy as np

from nc_sim.accel_curve import CURVE_ASYNC
from nc_sim.assist.curve_fit import (
    CURVE,
    binned,
    curve_changes,
    curve_figures,
    curve_series,
    fit_curve,
    measured_accel,
)
from nc_sim.assist.result import Figure, Result
from nc_sim.commands import Accepted, SpindleRun
from nc_sim.config import MachineConfig, apply_overrides
from nc_sim.errors import NcUsageError
from nc_sim.kernel import layout as L
from nc_sim.params import Scope
from nc_sim.scenario import power_on
from nc_sim.sim import Simulation
from nc_sim.units import RPM_TO_DEG_S

RUN_UP_LIMIT_S = 300.0  # a run-up still short of its speed by then: the curve barely accelerates
SETTLE_TAUS = (
    5.0  # the loop's time constants (1/kv) before the actual acceleration is the command's
)
BINS = 60


def curve_run_up(
    cfg: MachineConfig,
    axis: str,
    gear: int,
    typ: int,
    *,
    speed_rpm: float | None = None,
    n_limit_deg_s: float | None = None,
) -> Result:
    """Run the spindle `axis` up with M3 in `gear` (1-6) to `speed_rpm` (default: the gear's vb_max)
    and fit a curve of type `typ` to the measured a(n) by least squares."""
    spindle = axis
    cfg = copy.deepcopy(cfg)
    ax = cfg.axis(spindle)
    if not ax.is_spindle:
        raise NcUsageError(f"{spindle} is not a spindle")
    if not 1 <= gear <= 6:
        raise NcUsageError(f"gear must be 1 to 6, not {gear}")
    apply_overrides(cfg, Scope.AXIS, spindle, {"kenngr.getriebe_stufe": gear})
    top_deg_s = ax.eng("getriebe.dynamik.vb_max", gear)
    target_deg_s = top_deg_s if speed_rpm is None else speed_rpm * RPM_TO_DEG_S
    if not 0 < target_deg_s <= top_deg_s * (1 + 1e-9):
        raise NcUsageError(
            "speed must be above 0 and at most the gear's vb_max "
            f"({top_deg_s / RPM_TO_DEG_S:g} rpm)"
        )
    kv = ax.eng("getriebe.kv", gear)
    a_min = ax.eng("getriebe.beschl_kennlinie.a_min", gear)
    sim = Simulation(cfg.cycle_s)
    m = sim.add(cfg)
    power_on(sim, m)
    s = m.axis(spindle).slot
    outcome = m.submit(SpindleRun(spindle, 3, target_deg_s / RPM_TO_DEG_S))
    if not isinstance(outcome, Accepted):
        raise NcUsageError(f"M3 refused: {outcome}")
    chunk = round(1.0 / cfg.cycle_s)
    recs: list[np.ndarray] = []
    while True:
        rec = sim.new_record(chunk)
        sim.run(chunk, rec)
        recs.append(rec[:, s].copy())
        col = recs[-1]
        if np.any(col[:, L.R_JOB_ERROR] != 0):
            raise NcUsageError(
                f"the run-up stopped with job error {int(col[:, L.R_JOB_ERROR].max())}"
            )
        if col[-1, L.R_V_CMD] >= target_deg_s * (1 - 1e-9):
            break
        if len(recs) * chunk * cfg.cycle_s > RUN_UP_LIMIT_S:
            raise NcUsageError(f"not at {target_deg_s:g} °/s after {RUN_UP_LIMIT_S:g} s")
    data = np.concatenate(recs)
    v_act, v_cmd = data[:, L.R_V_ACT], data[:, L.R_V_CMD]
    n, a = measured_accel(v_act, data[:, L.R_OPEN_LOOP], cfg.cycle_s)
    start = int(np.argmax(v_cmd > 0.0)) + round(SETTLE_TAUS / kv / cfg.cycle_s)
    reached = int(np.argmax(v_cmd >= target_deg_s * (1 - 1e-9)))
    keep = np.zeros(len(n), dtype=bool)
    keep[start:reached] = True
    keep &= np.isfinite(a) & (a > a_min)
    if np.count_nonzero(keep) < BINS:
        raise NcUsageError("too few samples of the run-up to fit: raise the speed")
    bn, ba = binned(n[keep], a[keep], BINS)
    curve = fit_curve(typ, bn, ba, n_limit_deg_s=n_limit_deg_s, a_min=a_min)
    model = np.array([curve.accel(float(x)) for x in bn])
    before = {
        f"getriebe[{gear - 1}].{CURVE}{k}": ax.raw(f"getriebe.{CURVE}{k}", gear)
        for k in ("typ", "n_grenz", "a_konst", "b1", "b2", "b3", "a_max", "n1", "n2")
    }
    span = f"{bn.min():.0f}-{bn.max():.0f} °/s"
    notes = [f"measured from {span} in gear {gear}; a_min {a_min:g} °/s² kept"]
    if typ != CURVE_ASYNC and curve.n_limit <= bn.min():
        notes.append("no constant range measured: a_konst is the curve's value at n_limit")
    return Result(
        "curve-run-up",
        figures=(
            *curve_figures(curve),
            Figure(
                "max_error",
                float(np.max(np.abs(model - ba) / ba)),
                "",
                "largest relative error of the fit",
            ),
            Figure("run_up_s", float(reached * cfg.cycle_s), "s", "time to the speed"),
        ),
        changes=curve_changes(
            curve, spindle, gear, before, f"type {typ} fitted to the run-up over {span}"
        ),
        series=curve_series(curve, bn, ba),
        notes=tuple(notes),
        inputs={
            "spindle": spindle,
            "gear": gear,
            "typ": typ,
            "speed_rpm": target_deg_s / RPM_TO_DEG_S,
        },
    )


__all__ = ["curve_run_up"]
