"""An exercise's machine as configured, without the kernel (the gateway checks an uploaded
exercise against it): the template with the starting values, and whether every axis the
faults and checks name is there."""

from __future__ import annotations

from collections import defaultdict

from nc_sim.machine.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.params import Scope, Value
from nc_sim.training.exercise import Exercise, ExerciseError


def seat_config(exercise: Exercise) -> MachineConfig:
    """The exercise's machine template with its starting values written into the lists.
    Raises ParamListError for a value out of range, NcUsageError for an unknown axis."""
    cfg = demo_machine()  # the one template (exercise.MACHINES)
    lists: dict[tuple[Scope, str], dict[str, Value]] = defaultdict(dict)
    for v in exercise.start:
        lists[(v.scope, v.target)][v.name] = v.value
    for (scope, target), values in lists.items():
        apply_overrides(cfg, scope, target, values)
    return cfg


def check_fits(exercise: Exercise, source: str) -> None:
    """Raise ExerciseError naming the first fault or check whose axis the exercise's machine
    lacks (a main spindle's rotary-axis name, e.g. C, counts), ParamListError for a starting
    value out of range."""
    cfg = seat_config(exercise)
    names = {a.name for a in cfg.axes}
    rotary = str(cfg.channel_raw("default_ax_name_of_spindle") or "").strip().upper()
    if rotary:
        names.add(rotary)
    named = [
        (f"faults[{i}].axis", getattr(f.fault, "axis", None)) for i, f in enumerate(exercise.faults)
    ]
    named += [
        (f"checks[{i}].axis", getattr(c.rule, "axis", None)) for i, c in enumerate(exercise.checks)
    ]
    for key, axis in named:
        if axis is not None and axis not in names:
            raise ExerciseError(
                source, key, axis, f"an axis of the machine: {', '.join(sorted(names))}"
            )
