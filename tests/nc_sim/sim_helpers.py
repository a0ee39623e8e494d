"""Helpers for kernel tests: a demo machine in simulated time."""

from __future__ import annotations

from typing import Any

import numpy as np

from nc_sim.commands import Accepted, CycleStart, Mdi, ProgramLoad
from nc_sim.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.params import Scope
from nc_sim.sim import Simulation


def make(
    axis_params: dict[str, dict[str, Any]] | None = None,
    channel: dict[str, Any] | None = None,
    settle: int = 20,
) -> tuple[Simulation, Machine, MachineConfig]:
    cfg = demo_machine()
    for name, values in (axis_params or {}).items():
        apply_overrides(cfg, Scope.AXIS, name, values)
    if channel:
        apply_overrides(cfg, Scope.CHANNEL, "", channel)
    sim = Simulation(cfg.cycle_s)
    m = sim.add(cfg)
    sim.run(settle)  # the PLC switches the drives on
    return sim, m, cfg


def record(sim: Simulation, seconds: float) -> np.ndarray:
    rec = sim.new_record(round(seconds / sim.kernel.cycle_s))
    sim.run(rec.shape[0], rec)
    return rec


def mdi(m: Machine, text: str) -> Accepted:
    """Submit an MDI block and assert that the NC accepted it: it parsed and started (or
    waits behind a running block) without a job error."""
    outcome = m.submit(Mdi(text))
    assert isinstance(outcome, Accepted), (text, outcome)
    return outcome


def run_program(
    program: str,
    seconds: float,
    axes: dict[str, dict[str, Any]] | None = None,
    channel: dict[str, Any] | None = None,
) -> tuple[Simulation, Machine, np.ndarray]:
    """Load and start `program` on a demo machine (with these parameter overrides) and record
    `seconds` of it."""
    sim, m, _cfg = make(axes, channel)
    assert isinstance(m.submit(ProgramLoad("test", program)), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    return sim, m, record(sim, seconds)


__all__ = ["L", "make", "mdi", "record", "run_program"]
