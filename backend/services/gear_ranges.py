"""The gear-range preview [000 §2.8.2] for the gateway: the NC's own selection rule
(nc_sim/spindle/gears.py) on the ranges as edited, answered at once in the request without
the kernel; the machine supplies the gear table the edit is compared with.
"""

from __future__ import annotations

from api.assist import (
    AssistChange,
    GearRangeValues,
    GearSelectionRequest,
    GearSelectionResult,
    GearStep,
)
from backend.errors import Invalid
from nc_sim.config import MachineConfig
from nc_sim.spindle.gears import GearChoice, GearRange, m_of, range_table, select_gear
from nc_sim.spindle.gears import spindle_index as spindel_index


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
