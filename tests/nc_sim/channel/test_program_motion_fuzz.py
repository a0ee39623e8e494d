"""Seeded random programs run on the demo lathe: invariants of the path, in simulated time.

Every program either ends at its last programmed point (the generator tracks it on its own,
without the interpreter) or stops with a job error in the event log; no NaN anywhere; no
axis' commanded velocity or acceleration above its limits (vb_max, a_max)."""

from __future__ import annotations

import numpy as np
import pytest

from nc_sim.commands import Accepted, CycleStart, ProgramLoad
from nc_sim.snapshot import ChannelState
from tests.nc_sim.channel.randprog import random_program
from tests.nc_sim.sim_helpers import L, make

BOUNDS = {"X": (20.0, 80.0), "Z": (-130.0, -70.0)}
START = {"X": 50.0, "Z": -100.0}  # where the demo lathe stands


@pytest.mark.parametrize("seed", range(12))
def test_a_random_program_ends_at_its_last_point_within_the_axis_limits(seed: int) -> None:
    gen = random_program(seed, ("X", "Z"), BOUNDS, START, ("S1",), blocks=12)
    sim, m, cfg = make()
    assert isinstance(m.submit(ProgramLoad(f"fuzz{seed}", gen.text)), Accepted), gen.text
    assert isinstance(m.submit(CycleStart()), Accepted)
    axes = [m.axis("X"), m.axis("Z")]
    v_max = {a.name: cfg.axis(a.name).eng("getriebe.dynamik.vb_max") for a in axes}
    a_max = {a.name: cfg.axis(a.name).eng("getriebe.dynamik.a_max") for a in axes}
    errors_before = m.events.cursor
    for _ in range(300):  # at most 300 s of simulated time
        rec = sim.new_record(1000)
        sim.run(1000, rec)
        assert not np.isnan(rec).any()
        for ax in axes:
            assert np.abs(rec[:, ax.slot, L.R_V_CMD]).max() <= v_max[ax.name] * (1 + 1e-9)
            assert np.abs(rec[:, ax.slot, L.R_A_CMD]).max() <= a_max[ax.name] * (1 + 1e-6)
        if m.channel.state is not ChannelState.RUNNING:
            break
    state = m.channel.state
    errors = [e for e in m.events.since(errors_before).entries if e.error]
    if state is ChannelState.ERROR:
        assert errors, "a program stopped in error logs its job error"
        return
    assert state is ChannelState.READY, (state, gen.text)
    for ax in axes:
        assert m.k.st[ax.slot, L.S_P_CMD] == pytest.approx(gen.end[ax.name], abs=2e-3)
