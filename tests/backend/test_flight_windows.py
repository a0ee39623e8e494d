"""A machine's worker copies each job error's window as it steps (backend/workers/flight.py),
in simulated time and with nobody reading its ring: whole, however far the machine runs on
before anyone looks, and the same as a twin simulation's own record of those cycles."""

from __future__ import annotations

import numpy as np
import pytest

from backend.workers.flight import FlightWindow, main_signals
from backend.workers.host import MachineHost
from backend.workers.protocol import AddMachine
from backend.workers.ring import R_COLS, RING_CYCLES
from nc_sim.commands import Command, EmergencyStop, Mdi, Reset
from nc_sim.config import demo_machine
from nc_sim.errors import Code
from nc_sim.signals import CHANNEL, signal_rows
from nc_sim.sim import Simulation

RUN_ON = 3 * RING_CYCLES  # past the window's end before anyone looks: the ring lapped thrice


class _Twins:
    """The worker's machine (windows of 8 s before and 2 s after each job error) and a twin
    simulation of the same machine that records every cycle."""

    def __init__(self) -> None:
        self.host = MachineHost(AddMachine("m", "m", demo_machine(), 1, flight_s=(8.0, 2.0)), None)
        self.twin = Simulation(0.001)
        self.twin_machine = self.twin.add(demo_machine())
        self.record = np.zeros((60_000, self.twin.kernel.n, R_COLS))  # row c - 1: cycle c

    def run(self, cycles: int) -> None:
        self.host.advance(cycles)
        at = self.twin.cycle
        self.twin.run(cycles, self.record[at : at + cycles])

    def submit(self, cmd: Command) -> None:
        self.host.machine.submit(cmd)
        self.twin_machine.submit(cmd)

    def stop_again(self) -> None:
        """A reset, and 10 cycles later another emergency stop."""
        self.submit(Reset())
        self.run(10)
        self.submit(EmergencyStop())

    def twin_samples(self, w: FlightWindow) -> np.ndarray:
        """The twin's record of the window's cycles, its signals in its order."""
        n = w.data.shape[1]
        rows: np.ndarray = signal_rows(w.signals, self.record, np.arange(n) + w.first_cycle - 1)
        return rows


def test_a_window_is_whole_however_far_the_machine_runs_on_errors_within_it_share_it() -> None:
    """X moving at F200 from cycle 1000; an emergency stop at 9000, a reset and another at
    10510 (within its 2 s after); then 49 152 cycles in one go. One window of cycles
    1000..11000 comes out, both errors in it, every cycle of the main signals as the twin
    recorded it (the channel's state aside: a record carries it as it stood when the kernel
    call began, so it follows the stepping's stretches)."""
    t = _Twins()
    t.run(1000)
    t.submit(Mdi("G01 X150 F200"))
    t.run(8000)
    t.submit(EmergencyStop())
    t.run(1500)
    t.stop_again()
    t.run(RUN_ON)
    [w] = t.host.flights()
    assert (w.trigger.cycle, w.trigger.code) == (9000, Code.EMERGENCY_STOP)
    assert [(e.cycle, e.code) for e in w.errors] == [(9000, 90005), (10510, 90005)]
    assert all(1000 <= e.cycle <= 11000 for e in w.events) and w.errors[1] in w.events
    assert w.first_cycle == 1000 and w.data.shape == (len(w.signals), 10_001)
    assert [s.name for s in w.signals] == [s.name for s in main_signals(t.host.signals)]
    kept = [k for k, s in enumerate(w.signals) if s.name != f"{CHANNEL}.state"]
    assert np.array_equal(w.data[kept], t.twin_samples(w)[kept])
    x_cmd = w.data[[s.name for s in w.signals].index("X.pos_cmd_mm")]
    assert x_cmd[6000] - x_cmd[5000] == pytest.approx(200 / 60, abs=1e-9)  # 1 s at F200 (mm)
    assert t.host.flights() == []  # pushed once


def test_a_window_starts_at_the_first_cycle_and_an_error_after_its_end_opens_another() -> None:
    """An emergency stop at cycle 3000 (less than 8 s into the machine's life): its window
    starts at cycle 1. A reset and another stop at 6000, after that window's end (5000):
    a window of its own, cycles 1..8000."""
    t = _Twins()
    t.run(3000)
    t.submit(EmergencyStop())
    t.run(2990)
    t.stop_again()
    t.run(RUN_ON)
    first, second = t.host.flights()
    assert (first.first_cycle, first.data.shape[1]) == (1, 5000)
    assert [e.cycle for e in first.errors] == [3000]
    assert (second.first_cycle, second.data.shape[1]) == (1, 8000)
    assert [e.cycle for e in second.errors] == [6000]
