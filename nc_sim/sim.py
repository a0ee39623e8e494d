"""A simulation: one kernel, the machines on it, and simulated time.

`run(n)` advances every machine by exactly n cycles; the kernel returns early on events so
each machine reacts in the cycle they happen, and wakes up for its own timers (PLC).

A simulation is plain data at every cycle boundary (arrays, dataclasses, and for callbacks
bound methods or `functools.partial` of them, never a lambda or closure): `snapshot_bytes`
and `restore` save and restore it exactly, and `copy.deepcopy` gives an independent twin.
"""

from __future__ import annotations

import pickle

import numpy as np

from nc_sim.config import MachineConfig
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
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


def snapshot_bytes(sim: Simulation) -> bytes:
    """The whole simulation as it stands (machines, kernel, faults, pending handshakes), as
    a pickle of our own objects: restore it with `restore`, and only ever load what this
    function wrote (unpickling runs code named in the data)."""
    return pickle.dumps(sim, protocol=pickle.HIGHEST_PROTOCOL)


def restore(data: bytes) -> Simulation:
    """The simulation `snapshot_bytes` saved, to run on exactly as the original would.
    Only for our own snapshots (see `snapshot_bytes`)."""
    sim = pickle.loads(data)  # our own snapshot, never outside data
    if not isinstance(sim, Simulation):
        raise TypeError(f"not a simulation snapshot: {type(sim).__name__}")
    return sim
