"""A running simulation snapshots and restores exactly (nc_sim.sim.snapshot_bytes/restore):
the restored copy and the original, given the same later commands, record the same samples,
events and snapshots - mid program, mid gear change, mid PLC handshake, with faults."""

from __future__ import annotations

import copy
import pickle
import random

import numpy as np
import pytest

from nc_sim.commands import (
    Command,
    CycleStart,
    GearChange,
    JogStart,
    JogStop,
    Mdi,
    Move,
    PlcAck,
    PlcMode,
    ProgramLoad,
    Reset,
    SpindlePosition,
    SpindleRun,
)
from nc_sim.config import demo_machine
from nc_sim.faults import (
    Backlash,
    DriveGainWrong,
    EncoderNoise,
    Fault,
    Friction,
    MotorInverted,
    PlcSlowAck,
    Trigger,
)
from nc_sim.sim import Simulation, restore, snapshot_bytes
from tests.nc_sim.channel.randprog import random_program
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


Step = tuple[int, Command | tuple[Fault, Trigger]]
HORIZON = 4000  # cycles every scenario runs


def _script(seed: int) -> list[Step]:
    """Commands and faults at random cycles: moves, a program, the spindle (M3, M19, gear
    changes), jog, the C axis, the PLC by hand, faults armed and in force, resets."""
    rng = random.Random(seed)
    prog = random_program(
        seed,
        ("X", "Z"),
        {"X": (20.0, 80.0), "Z": (-130.0, -70.0)},
        {"X": 50.0, "Z": -100.0},
        ("S1",),
        blocks=8,
    )
    pool: list[list[Command | tuple[Fault, Trigger]]] = [
        [Mdi(f"G01 X{rng.uniform(20, 80):.3f} F{rng.choice((600, 2000, 4000))}")],
        [ProgramLoad("p", prog.text), CycleStart()],
        [SpindleRun("S", 3, rng.choice((300.0, 600.0, 1500.0)))],
        [Mdi(f"M3 S{rng.choice((200, 650, 1200))}")],
        [SpindlePosition("S", rng.uniform(0, 360))],
        [GearChange("S", rng.choice((40, 41, 42)))],
        [JogStart("Z", rng.choice((-1, 1)), 1000.0), JogStop("Z")],
        [Move("C", rng.uniform(0, 360), rapid=False, feed_mm_min=20000.0)],
        [PlcMode("manual"), PlcAck(), PlcMode("auto")],
        [(DriveGainWrong("X", rng.uniform(0.8, 1.2)), Trigger(after_s=rng.uniform(0, 1)))],
        [(EncoderNoise("Z", 0.002, rng.randrange(100)), Trigger(on_motion=True))],
        [(PlcSlowAck(rng.uniform(0.05, 0.5)), Trigger())],
        [(Friction("X", 0.5), Trigger()), (Backlash("Z", 0.05), Trigger())],
        [(MotorInverted("X"), Trigger(after_s=2.0)), Reset()],
        [Reset()],
    ]
    steps: list[Step] = []
    for group in rng.sample(pool, 7):
        at = rng.randrange(0, HORIZON - 600)
        for item in group:
            steps.append((at, item))
            at += rng.randrange(1, 400)
    return sorted(steps, key=lambda step: step[0])


def _play(sim: Simulation, steps: list[Step], end: int, rec: np.ndarray | None) -> None:
    """Run `sim` to cycle `end`, giving each step at its cycle (from the current one on)."""
    start = sim.cycle
    m = sim.machines[0]
    for at, item in steps:
        if not start <= at < end:
            continue
        if at > sim.cycle:
            part = None if rec is None else rec[sim.cycle - start : at - start]
            sim.run(at - sim.cycle, part)
        if isinstance(item, tuple):
            m.inject(*item)
        else:
            m.submit(item)
    part = None if rec is None else rec[sim.cycle - start : end - start]
    sim.run(end - sim.cycle, part)


@pytest.mark.parametrize("seed", range(8))
def test_a_snapshot_at_a_random_cycle_runs_on_exactly_as_the_original(seed: int) -> None:
    steps = _script(seed)
    at = random.Random(-seed).randrange(1, HORIZON - 500)
    sim = Simulation(0.001)
    sim.add(demo_machine())
    _play(sim, steps, at, None)
    data = snapshot_bytes(sim)
    twins = [restore(data), copy.deepcopy(sim)]
    ra = sim.new_record(HORIZON - at)
    _play(sim, steps, HORIZON, ra)
    a = sim.machines[0]
    for twin in twins:
        rb = twin.new_record(HORIZON - at)
        _play(twin, steps, HORIZON, rb)
        assert np.array_equal(ra, rb)
        b = twin.machines[0]
        assert list(a.events) == list(b.events)
        assert list(a.outcomes) == list(b.outcomes)
        assert a.snapshot() == b.snapshot()
        assert a.faults() == b.faults()
        assert pickle.dumps(a.cfg) == pickle.dumps(b.cfg)


def test_restore_refuses_what_is_not_a_simulation() -> None:
    with pytest.raises(TypeError, match="not a simulation snapshot"):
        restore(pickle.dumps([1, 2]))
