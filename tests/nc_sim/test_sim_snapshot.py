"""A running simulation snapshots and restores exactly (nc_sim.sim.snapshot_bytes/restore):
the restored copy and the original, given the same later commands, record the same samples,
events and snapshots - mid program, mid gear change, mid PLC handshake, with faults."""

from __future__ import annotations

import copy

import numpy as np

from nc_sim.commands import Mdi
from nc_sim.faults import DriveGainWrong, Trigger
from nc_sim.sim import Simulation, restore, snapshot_bytes
from tests.nc_sim.sim_helpers import make, mdi


def _same_future(a: Simulation, b: Simulation, cycles: int) -> None:
    ra, rb = a.new_record(cycles), b.new_record(cycles)
    a.run(cycles, ra)
    b.run(cycles, rb)
    assert np.array_equal(ra, rb)
    ma, mb = a.machines[0], b.machines[0]
    assert list(ma.events) == list(mb.events)
    assert ma.snapshot() == mb.snapshot()
    assert ma.faults() == mb.faults()


def test_a_simulation_restored_mid_move_with_a_fault_armed_runs_on_identically() -> None:
    sim, m, _ = make()
    mdi(m, "G01 X80 F3000")
    m.inject(DriveGainWrong("X", 1.3), Trigger(after_s=0.2))
    sim.run(77)
    copy_ = restore(snapshot_bytes(sim))
    _same_future(sim, copy_, 600)


def test_a_deep_copy_is_a_machine_of_its_own() -> None:
    """Stored callbacks are bound methods: the copy's parts call the copy, not the original."""
    sim, m, _ = make()
    twin = copy.deepcopy(sim)
    twin.machines[0].submit(Mdi("G01 X80 F3000"))
    twin.run(300)
    assert twin.machines[0].cycle == 320 and m.cycle == 20
    assert twin.machines[0].handshake.now() == 320
    assert m.axis("X").state.name == "STANDSTILL"
