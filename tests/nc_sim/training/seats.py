"""A student's seat in simulated time, fed as the service's worker feeds its monitor: chunks
of 100 recorded cycles (0.1 s) with the events logged since."""

from __future__ import annotations

from pathlib import Path

from nc_sim.commands import Command, Invalid, Mdi, Refused, Reset
from nc_sim.config import apply_overrides
from nc_sim.machine.machine import Machine
from nc_sim.params import Scope, Value
from nc_sim.sim import Simulation
from nc_sim.training.checks import CheckResult, ExerciseMonitor
from nc_sim.training.exercise import Exercise, parse_exercise
from nc_sim.training.seat import start_seat

EXERCISES = Path(__file__).resolve().parents[3] / "exercises"
CHUNK = 100  # cycles per feed: the worker's 10 Hz at 1 ms


def load(name: str) -> Exercise:
    path = EXERCISES / f"{name}.toml"
    return parse_exercise(path.read_text(encoding="utf-8"), path.name)


class Seat:
    """A student's seat: the exercise's machine, its monitor, fed in chunks."""

    def __init__(self, name: str) -> None:
        self.exercise = load(name)
        self.sim = Simulation()
        self.m: Machine = start_seat(self.sim, self.exercise)
        self.sim.run(20)  # the PLC switches the drives on
        self.monitor = ExerciseMonitor(self.exercise.checks, self.m)

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds / (CHUNK * self.sim.kernel.cycle_s))):
            rec = self.sim.new_record(CHUNK)
            first = self.sim.cycle + 1
            self.sim.run(CHUNK, rec)
            self.monitor.feed(self.m, rec, first)

    def do(self, cmd: Command) -> None:
        outcome = self.m.submit(cmd)
        assert not isinstance(outcome, Invalid | Refused), (cmd, outcome)

    def mdi(self, block: str) -> None:
        self.do(Mdi(block))

    def param(self, scope: Scope, target: str, values: dict[str, Value]) -> None:
        """Write parameters as the HMI does: into the lists, then the machine re-reads them."""
        apply_overrides(self.m.cfg, scope, target, values)
        self.m.refresh_params()

    def result(self, check_id: str) -> CheckResult:
        return next(r for r in self.monitor.results() if r.id == check_id)

    def passed(self, check_id: str) -> bool:
        r = self.result(check_id)
        return r.passed and r.first_passed_cycle is not None

    def first_passes(self) -> dict[str, float]:
        """Check id -> seconds after the start of the checks passing now, as the gateway
        records them for the score."""
        dt = self.sim.kernel.cycle_s
        start = self.monitor.start_cycle
        return {
            r.id: (r.first_passed_cycle - start) * dt
            for r in self.monitor.results()
            if r.passed and r.first_passed_cycle is not None
        }

    def recover(self, axis: str) -> None:
        """After a trip: the CNC reset (which gives the servo back)."""
        self.do(Reset())
        self.run(0.5)

    def x_back_and_forth(self, seconds: float) -> None:
        """G01 X between 50 and 100 mm at 1 m/min (16.7 mm/s: 3 s per stroke)."""
        for i in range(round(seconds / 4.0)):
            self.mdi(f"G01 X{100 if i % 2 == 0 else 50} F1000")
            self.run(4.0)
