"""An exercise's machine as configured, without the kernel (the gateway checks an exercise
against it): the template with the starting values, and whether every axis, spindle and gear
stage the faults and checks name is there."""

from __future__ import annotations

import copy
from collections import defaultdict

from nc_sim.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.faults import GearRatioWrong
from nc_sim.params import Scope, Value
from nc_sim.spindle.gears import range_table, spindle_index
from nc_sim.training.checks import SpeedReachedCheck
from nc_sim.training.exercise import Exercise, ExerciseError


def seat_config(exercise: Exercise, template: MachineConfig | None = None) -> MachineConfig:
    """The exercise's machine with its starting values written into the lists: `template`
    (changed in place: pass a fresh one) or the demo lathe (exercise.MACHINES). Raises
    ParamListError for a value out of range, NcUsageError for an unknown axis."""
    cfg = template if template is not None else demo_machine()
    lists: dict[tuple[Scope, str], dict[str, Value]] = defaultdict(dict)
    for v in exercise.start:
        lists[(v.scope, v.target)][v.name] = v.value
    for (scope, target), values in lists.items():
        apply_overrides(cfg, scope, target, values)
    return cfg


def check_fits(exercise: Exercise, source: str, template: MachineConfig | None = None) -> None:
    """Raise ExerciseError naming the first fault or check whose axis, spindle or gear stage
    the exercise's machine (`template`, changed in place, or the demo lathe) lacks (a main
    spindle's rotary-axis name, e.g. C, counts as the spindle); ParamListError for a starting
    value out of range, NcUsageError for a starting value of an axis the machine lacks.
    Starting values varied per seat are checked at both ends of their range."""
    if any(v.section == "start" for v in exercise.vary):
        for variant in exercise.extremes():
            seat_config(variant, copy.deepcopy(template) if template is not None else None)
    cfg = seat_config(exercise, template)
    spindles = {a.name for a in cfg.axes if a.is_spindle}
    names = {a.name for a in cfg.axes}
    rotary = str(cfg.channel_raw("default_ax_name_of_spindle") or "").strip().upper()
    main = cfg.main_spindle
    if rotary and main is not None:
        names.add(rotary)
    # (key, axis, needs a spindle, gear stage)
    named: list[tuple[str, str | None, bool, int | None]] = [
        (
            f"faults[{i}]",
            getattr(f.fault, "axis", None),
            isinstance(f.fault, GearRatioWrong),
            getattr(f.fault, "gear", None),
        )
        for i, f in enumerate(exercise.faults)
    ]
    named += [
        (
            f"checks[{i}]",
            getattr(c.rule, "axis", None),
            isinstance(c.rule, SpeedReachedCheck),
            getattr(c.rule, "gear", None),
        )
        for i, c in enumerate(exercise.checks)
    ]
    for key, axis, spindle, gear in named:
        if axis is not None and axis not in names:
            raise ExerciseError(
                source, f"{key}.axis", axis, f"an axis of the machine: {', '.join(sorted(names))}"
            )
        name = main if axis is not None and axis == rotary else axis
        if spindle and name not in spindles:
            raise ExerciseError(
                source,
                f"{key}.axis",
                axis,
                f"a spindle of the machine: {', '.join(sorted(spindles)) or 'none'}",
            )
        if gear is not None and gear not in gear_stages(cfg, name if name is not None else main):
            stages = ", ".join(str(g) for g in sorted(gear_stages(cfg, name or main)))
            raise ExerciseError(
                source,
                f"{key}.gear",
                gear,
                f"a gear stage of {name or main or 'the spindle'}: {stages}",
            )


def gear_stages(cfg: MachineConfig, axis: str | None) -> set[int]:
    """The gear stages an axis can run in: 1, and for the main spindle with gear change
    (main_spindle_gear_change) every stage whose range_table[g-1] has a max_speed
    [000 §2.8.2]."""
    stages = {1}
    if axis is None or axis != cfg.main_spindle or not cfg.channel_raw("main_spindle_gear_change"):
        return stages
    i = spindle_index(cfg, axis)
    if i is None:
        return stages
    return stages | {g for g, r in enumerate(range_table(cfg, i), start=1) if r.used}
