"""A seat's machine for an exercise: the template, the starting values, the faults."""

from __future__ import annotations

from nc_sim.machine.machine import Machine
from nc_sim.sim import Simulation
from nc_sim.training.exercise import Exercise
from nc_sim.training.template import seat_config


def start_seat(sim: Simulation, exercise: Exercise) -> Machine:
    """Add the exercise's machine to `sim` and inject its faults (their triggers armed from
    now). The monitor (checks.ExerciseMonitor) is made once the seat is handed over."""
    m = sim.add(seat_config(exercise))
    for f in exercise.faults:
        m.inject(f.fault, f.trigger)
    return m
