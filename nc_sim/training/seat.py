"""A seat's machine for an exercise: the template, the starting values, the faults."""

from __future__ import annotations

from collections import defaultdict

from nc_sim.machine.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.machine.machine import Machine
from nc_sim.params import Scope, Value
from nc_sim.sim import Simulation
from nc_sim.training.exercise import Exercise


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


def start_seat(sim: Simulation, exercise: Exercise) -> Machine:
    """Add the exercise's machine to `sim` and inject its faults (their triggers armed from
    now). The monitor (checks.ExerciseMonitor) is made once the seat is handed over."""
    m = sim.add(seat_config(exercise))
    for f in exercise.faults:
        m.inject(f.fault, f.trigger)
    return m
