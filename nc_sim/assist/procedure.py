"""An experiment as a procedure: it drives a machine it does not own, one wait at a time.

A procedure is a generator over a powered machine. It submits its commands and yields a
`Wait` for as many cycles as it wants to see next; whoever steps the machine sends back the
kernel records of exactly those cycles, and the procedure returns its `Result` at the end.
So one procedure runs either way, with the same cycles and the same answer:

- `on_copy`: a fresh machine from a configuration, stepped in simulated time as fast as the
  kernel goes (the preview; the command line);
- `LiveRun`: the machine a worker paces in real time, the worker stepping no further than
  the wait asks before it hands the records over (nc_sim stays free of clocks and threads).
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from nc_sim.assist.result import ExperimentError, Result
from nc_sim.config import MachineConfig
from nc_sim.errors import NcUsageError
from nc_sim.faults import Fault
from nc_sim.machine.machine import Machine
from nc_sim.scenario import power_on
from nc_sim.sim import Simulation


@dataclass(frozen=True)
class Wait:
    """Step `cycles` more cycles and send their kernel records back (cycles × slots × cols).
    `phase` says what the machine does meanwhile; `planned_s` is the whole run's expected
    length in simulated seconds as far as the procedure knows it now (progress)."""

    cycles: int
    phase: str
    planned_s: float


Procedure = Generator[Wait, np.ndarray, Result]
Start = Callable[[Machine], Procedure]
T = TypeVar("T")  # what a procedure answers: a Result, or a part of one (a loop gain's step)


# the faults in force on the machine a copy is made of (an experiment function builds its
# copies from the configuration alone: what the plant hides comes this way, see copies_with)
_copy_faults: ContextVar[tuple[Fault, ...]] = ContextVar("copy_faults", default=())


@contextmanager
def copies_with(faults: Iterable[Fault]) -> Iterator[None]:
    """Every copy made within carries `faults`: a copy of a machine behaves as the machine
    does, its training faults included (a preview that ignored them would tell a student
    the opposite of the machine)."""
    token = _copy_faults.set(tuple(faults))
    try:
        yield
    finally:
        _copy_faults.reset(token)


def on_copy(cfg: MachineConfig, start: Callable[[Machine], Generator[Wait, np.ndarray, T]]) -> T:
    """Run the procedure `start` makes on a fresh machine built from `cfg`, powered on as a
    scenario is, with the faults of `copies_with` in force; the machine the configuration
    came from does not move."""
    sim = Simulation(cfg.cycle_s)
    m = sim.add(cfg)
    try:
        power_on(sim, m)
    except NcUsageError as e:
        raise ExperimentError(str(e)) from None
    for fault in _copy_faults.get():
        m.inject(fault)
    return step_through(sim, start(m))


def step_through(sim: Simulation, proc: Generator[Wait, np.ndarray, T]) -> T:
    """Run a procedure on a machine of `sim` as it is (its faults in force), stepping `sim`
    in simulated time as far as each wait asks."""
    try:
        wait = next(proc)
        while True:
            rec = sim.new_record(max(1, wait.cycles))
            sim.run(rec.shape[0], rec)
            wait = proc.send(rec)
    except StopIteration as done:
        result: T = done.value
        return result


class LiveRun:
    """A procedure on a machine someone else steps: `want` cycles at most before the next
    `feed` of their records. `result` once it has ended, `error` when it ended in one."""

    def __init__(self, m: Machine, start: Start, cycle_s: float) -> None:
        self.cycle_s = cycle_s
        self.proc = start(m)
        self.result: Result | None = None
        self.error: str | None = None
        self.fed_cycles = 0
        self._chunks: list[np.ndarray] = []
        self._have = 0
        self.wait: Wait | None = None
        self._advance(None)  # up to its first wait: its commands go out now

    @property
    def done(self) -> bool:
        return self.result is not None or self.error is not None

    def want(self) -> int:
        """Cycles the machine may step before the procedure must see them (0 once done)."""
        return 0 if self.wait is None else max(1, self.wait.cycles) - self._have

    def feed(self, rows: np.ndarray) -> None:
        """The records of the cycles just stepped (no more than `want`)."""
        if self.wait is None:
            return
        self._chunks.append(rows.copy())  # the rows are a ring's: they are overwritten later
        self._have += rows.shape[0]
        self.fed_cycles += rows.shape[0]
        if self._have >= max(1, self.wait.cycles):
            rec = np.concatenate(self._chunks) if len(self._chunks) > 1 else self._chunks[0]
            self._chunks, self._have = [], 0
            self._advance(rec)

    def cancel(self, why: str) -> None:
        """End it now (the caller stops the motion it started)."""
        if not self.done:
            self.proc.close()
            self.wait, self.error = None, why

    def progress(self) -> tuple[str, float, float]:
        """(phase, elapsed simulated s, planned simulated s)."""
        phase = "done" if self.wait is None else self.wait.phase
        planned = self.wait.planned_s if self.wait is not None else self.fed_cycles * self.cycle_s
        return phase, self.fed_cycles * self.cycle_s, planned

    def _advance(self, rec: np.ndarray | None) -> None:
        try:
            self.wait = next(self.proc) if rec is None else self.proc.send(rec)
        except StopIteration as done:
            self.wait, self.result = None, done.value
        except ExperimentError as e:
            self.wait, self.error = None, str(e)
