"""The commissioning calculators [004 §3.4, §3.6.1, 000 §2.2.4, §2.8.4] and the gear-range
preview [000 §2.8.2] for the gateway: pure arithmetic (nc_sim/assist/calculators.py,
curve_fit.py, nc_sim/spindle/gears.py), answered at once in the request. None of them loads the
kernel (the assistants' process is for experiments); the machine only supplies the values the
proposal replaces ("before") and what the engineer did not type (the curve's a_min, the
cycle time, the gear table).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pydantic import BaseModel

from api.assist import (
    AssistChange,
    AssistResult,
    CurveFitRequest,
    GearRangeValues,
    GearSelectionRequest,
    GearSelectionResult,
    GearStep,
    MultiGainCalcRequest,
    ResolutionRequest,
    SpeedScalingRequest,
)
from backend.errors import Invalid
from nc_sim.assist.calculators import multi_gain, resolution, speed_scaling
from nc_sim.assist.curve_fit import curve_fit
from nc_sim.assist.result import Change, Result
from nc_sim.config import MachineConfig
from nc_sim.errors import NcUsageError
from nc_sim.params import Scope, Value, resolve
from nc_sim.spindle.gears import GearChoice, GearRange, m_of, range_table, select_gear
from nc_sim.spindle.gears import spindle_index as spindel_index


def _resolution(cfg: MachineConfig, r: ResolutionRequest) -> Result:
    return resolution(
        r.increments_per_rev,
        pitch_mm=r.pitch_mm,
        rotary=r.rotary,
        gear_ratio=r.gear_ratio,
        target=r.axis,
        gear=r.gear,
    )


def _multi_gain(cfg: MachineConfig, r: MultiGainCalcRequest) -> Result:
    return multi_gain(
        digits_per_rpm=r.digits_per_rpm,
        full_scale_digits=r.full_scale_digits,
        full_scale_rpm=r.full_scale_rpm,
        speed_weighting_rpm=r.speed_weighting_rpm,
        speed_weighting_m_per_min=r.speed_weighting_m_per_min,
        pitch_mm=r.pitch_mm,
        gear_ratio=r.gear_ratio,
        target=r.axis,
        gear=r.gear,
    )


def _speed_scaling(cfg: MachineConfig, r: SpeedScalingRequest) -> Result:
    if not cfg.axis(r.axis).is_spindle:
        raise NcUsageError(f"axis: {r.axis} is not a spindle (v_reso scales a spindle's speed)")
    cycle_ms = r.cycle_ms
    if r.time_base == 2 and cycle_ms is None:
        cycle_ms = cfg.cycle_s * 1000.0  # the machine's own cycle (P-CHAN cycle_time)
    return speed_scaling(
        r.increments,
        r.speed_rpm,
        time_base=r.time_base,
        cycle_ms=cycle_ms,
        gear_ratio=r.gear_ratio,
        target=r.axis,
    )


def _curve_fit(cfg: MachineConfig, r: CurveFitRequest) -> Result:
    ax = cfg.axis(r.axis)
    if not ax.is_spindle:
        raise NcUsageError(f"axis: {r.axis} is not a spindle (the curve is a spindle gear's)")
    return curve_fit(
        r.typ,
        [(p.n_deg_s, p.a_deg_s2) for p in r.points],
        n_limit_deg_s=r.n_limit_deg_s,
        a_min=r.a_min,
        target=r.axis,
        gear=r.gear,
    )


CALCULATORS: dict[str, Callable[[MachineConfig, Any], Result]] = {
    "resolution": _resolution,
    "multi-gain-calc": _multi_gain,
    "speed-scaling": _speed_scaling,
    "curve-fit": _curve_fit,
}


def _current(cfg: MachineConfig, change: Change) -> Value:
    """The value the change replaces, as the parameter list shows it (default when unset)."""
    scope = Scope.CHANNEL if change.target == "channel" else Scope.AXIS
    values = cfg.list_values(scope, change.target)
    return values.get(change.parameter, resolve(scope, change.parameter).default)


def calculate(cfg: MachineConfig, name: str, req: BaseModel) -> AssistResult:
    """Calculator `name` on the request's inputs, its changes with the machine's values
    before; 422 with the calculator's reason when the inputs do not fit together."""
    try:
        cfg.axis(str(getattr(req, "axis", "")))
        result = CALCULATORS[name](cfg, req)
        changes = [
            AssistChange(
                target=c.target,
                parameter=c.parameter,
                before=_current(cfg, c),
                after=c.after,
                why=c.why,
            )
            for c in result.changes
        ]
    except NcUsageError as e:
        raise Invalid(str(e)) from None  # the route names the calculator
    answer = AssistResult.model_validate(result.as_json())
    return answer.model_copy(update={"changes": changes})


def _step(choice: GearChoice, rpm: float, current: int) -> GearStep:
    if choice.gear is None:
        assert choice.error is not None
        return GearStep(
            speed_rpm=rpm,
            gear=None,
            m=None,
            change=False,
            error=f"{choice.error.name} ({int(choice.error)})",
            detail=choice.detail,
        )
    return GearStep(
        speed_rpm=rpm, gear=choice.gear, m=m_of(choice.gear), change=choice.gear != current
    )


def gear_selection(cfg: MachineConfig, req: GearSelectionRequest) -> GearSelectionResult:
    """The main spindle's gear table (as edited, else the machine's) and the stage the NC's
    rule (nc_sim/spindle/gears.py `select_gear`, no M40-M45 programmed) selects for each S in
    turn from `current_gear`; the edited ranges as changes against the machine's."""
    name = cfg.main_spindle
    i = spindel_index(cfg, name) if name else None
    if name is None or i is None:
        raise Invalid("the machine has no main spindle (main_spindle_ax_nr)")
    own = range_table(cfg, i)
    ranges = (
        [GearRange(float(r.min_rpm), float(r.max_rpm)) for r in req.ranges]
        if req.ranges is not None
        else own
    )
    pre = f"spindel[{i}]"
    enabled = bool(cfg.channel_raw("main_spindle_gear_change"))
    automatic = (
        bool(cfg.channel_raw(f"{pre}.autom_range")) if req.automatic is None else req.automatic
    )
    way = int(cfg.channel_raw(f"{pre}.range_way")) if req.range_way is None else req.range_way
    start = req.current_gear or int(cfg.axis(name).raw("kenngr.getriebe_stufe"))
    current, steps = start, []
    for s in req.speeds_rpm:
        # without gear change (P-CHAN-00052 off) S runs in the stage the spindle is in
        choice = (
            select_gear(ranges, current, s, automatic, way, None)
            if enabled
            else GearChoice(current)
        )
        steps.append(_step(choice, s, current))
        current = choice.gear or current
    changes = [
        AssistChange(
            target="channel",
            parameter=f"{pre}.range_table[{j}].{key}",
            before=int(getattr(old, attr)),
            after=int(getattr(new, attr)),
            why=f"M{m_of(j + 1)} (gear {j + 1}, getriebe[{j}]) {key}",
        )
        for j, (old, new) in enumerate(zip(own, ranges, strict=True))
        for key, attr in (("min_speed", "min_rpm"), ("max_speed", "max_rpm"))
        if getattr(old, attr) != getattr(new, attr)
    ]
    return GearSelectionResult(
        spindle=name,
        spindle_index=i,
        gear_change=enabled,
        automatic=automatic,
        range_way=way,
        current_gear=start,
        ranges=[GearRangeValues(min_rpm=int(r.min_rpm), max_rpm=int(r.max_rpm)) for r in ranges],
        steps=steps,
        changes=changes,
    )
