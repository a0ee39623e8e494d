"""An exercise tried on a copy before a class meets it: its seat's machine built as a seat is
(the starting values, the faults with the first seat's own numbers), run for a while with
nobody at it, its checks judged as a seat's worker judges them. A check that passes on the
untouched machine gives its points away; a job error nobody caused shows what the student
meets first."""

from __future__ import annotations

from dataclasses import dataclass

from nc_sim.config import MachineConfig
from nc_sim.errors import is_error
from nc_sim.training.checks import CheckResult, ExerciseMonitor
from nc_sim.training.exercise import Exercise
from nc_sim.training.template import seat_config

CHUNK = 100  # cycles per feed of the monitor: as a worker's 10 Hz at 1 ms
MAX_DRY_S = 120.0


@dataclass(frozen=True)
class DryRun:
    """What the untouched seat did in `seconds` of simulated time."""

    seconds: float
    checks: tuple[CheckResult, ...]  # the judged checks, in the exercise's order
    job_errors: tuple[tuple[int, str, float], ...]  # (code, message, t_s), oldest first
    start_cycle: int  # the checks' start (their first passes count from it)
    cycle_s: float


def dry_run(exercise: Exercise, seconds: float, template: MachineConfig | None = None) -> DryRun:
    """Run a seat of `exercise` (as given: pass a seat's, numbers drawn) untouched for
    `seconds` (at most MAX_DRY_S) of simulated time on `template` (changed in place) or the
    demo lathe. Raises ValueError for a check naming an axis the machine lacks."""
    from nc_sim.sim import Simulation  # the kernel: here, not when the gateway imports DryRun

    sim = Simulation()
    m = sim.add(seat_config(exercise, template))
    for f in exercise.faults:
        m.inject(f.fault, f.trigger)
    cursor = m.events.cursor
    sim.run(20)  # the PLC switches the drives on, as before a seat is handed over
    monitor = ExerciseMonitor(exercise.checks, m)
    chunks = max(1, round(min(seconds, MAX_DRY_S) / (CHUNK * sim.kernel.cycle_s)))
    for _ in range(chunks):
        rec = sim.new_record(CHUNK)
        first = sim.cycle + 1
        sim.run(CHUNK, rec)
        monitor.feed(m, rec, first)
    events = m.events.since(cursor).entries
    errors = tuple((e.code, e.message, e.t_s) for e in events if is_error(e.code))
    ran = chunks * CHUNK * sim.kernel.cycle_s
    return DryRun(ran, tuple(monitor.results()), errors, monitor.start_cycle, sim.kernel.cycle_s)
