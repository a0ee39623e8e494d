"""A simulation: one kernel, the machines on it, and simulated time.

`run(n)` advances every machine by exactly n cycles; the kernel returns early on events so
each machine reacts in the cycle they happen, and wakes up for its own timers (PLC).
"""

from __future__ import annotations

import numpy as np

from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.machine.config import MachineConfig
from nc_sim.machine.machine import Machine


class Simulation:
    """Machines sharing one vectorised kernel and one cycle counter."""

    def __init__(self, cycle_s: float = 0.001) -> None:
        self.kernel = Kernel(cycle_s)
        self.machines: list[Machine] = []
        self.cycle = 0

    @property
    def t_s(self) -> float:
        return self.cycle * self.kernel.cycle_s

    def add(self, cfg: MachineConfig) -> Machine:
        """Add a machine; its axes get kernel slots."""
        m = Machine(cfg, self.kernel)
        m.cycle = self.cycle
        self.machines.append(m)
        return m

    def new_record(self, n: int) -> np.ndarray:
        """A buffer for n cycles of samples of every slot (for `run(n, rec)`)."""
        return np.zeros((n, self.kernel.n, L.R_COLS))

    def run(self, n: int, rec: np.ndarray | None = None) -> None:
        """Advance all machines by n cycles, filling rec[0:n] when given."""
        done = 0
        while done < n:
            limit = n - done
            for m in self.machines:
                wake = m.next_wakeup()
                if wake is not None and wake > self.cycle:
                    limit = min(limit, wake - self.cycle)
            part = rec[done : done + limit] if rec is not None else None
            k = self.kernel.run(limit, part)
            done += k
            self.cycle += k
            for m in self.machines:
                m.on_cycle(self.cycle)

    def run_s(self, seconds: float, rec: np.ndarray | None = None) -> None:
        """Advance by a simulated duration (rounded to whole cycles)."""
        self.run(round(seconds / self.kernel.cycle_s), rec)
