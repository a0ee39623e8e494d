"""Seeded random operator sessions on the demo lathe: every sequence ends (issue 13).

Whatever a random operator does (jog, move, home in any order, M3/M4/M5/M19, gear buttons,
spindle jog and move), every axis ends, some time after the last command, in a state that
lasts by design (standstill, endless rotation, error) and never in a sequence that stopped
progressing; every job error on the way is one the job error table documents for it.
"""

from __future__ import annotations

import random

import pytest

from nc_sim.commands import GearChange, JogStart, JogStep, JogStop, Mdi, Move
from nc_sim.errors import Code, is_error
from nc_sim.machine.machine import Machine
from nc_sim.snapshot import AxisState
from tests.nc_sim.sim_helpers import make

S = "S1"
LASTING = {AxisState.STANDSTILL, AxisState.ENDLESS, AxisState.OPEN_LOOP, AxisState.ERROR}
EXPECTED_ERRORS = {
    Code.GEAR_NO_RANGE,  # S above 7000 rpm
    Code.GEAR_WRONG_STAGE,  # M4x outside the running S
    Code.AXIS_BUSY,  # an increment or a spindle jog while moving
    Code.SOFTWARE_LIMIT,  # a target beyond the limits once homed
}


def _act(m: Machine, rng: random.Random) -> None:
    axis = rng.choice(["X", "Z", S])
    rpm = rng.choice([rng.uniform(50, 7000), rng.uniform(0, 9000)])
    choice = rng.randrange(10)
    if choice == 0:
        m.submit(JogStep(axis, rng.uniform(-50, 50)))
    elif choice == 1:
        m.submit(Move(axis, rng.uniform(-200, 400), rng.random() < 0.5, rng.uniform(600, 6000)))
    elif choice == 2:
        m.submit(Mdi(rng.choice(["G74 X1 Z2", "G74 Z1 X2 S1", "G74 X1 Z1", "G74 S1"])))
    elif choice == 3:
        m.submit(Mdi(f"M{rng.choice([3, 4])} S{rpm:.1f}"))
    elif choice == 4:
        m.submit(Mdi("M5"))
    elif choice == 5:
        m.submit(Mdi(f"M19 S.POS={rng.uniform(0, 360):.2f}"))
    elif choice == 6:
        m.submit(GearChange("S", rng.randint(40, 45)))
    elif choice == 7:
        m.submit(Mdi(f"G01 X{rng.uniform(-5, 290):.2f} F{rng.uniform(500, 5000):.0f}"))
    else:  # a held jog key, released later by the session
        m.submit(JogStart(axis, rng.choice([-1, 1]), rng.uniform(100, 3000)))


def _session(seed: int) -> None:
    rng = random.Random(seed)
    sim, m, _ = make(channel={"plc.m_ack_timeout": 2000000})
    for _ in range(10):
        _act(m, rng)
        sim.run(round(rng.uniform(0.05, 3.0) / 0.001))
        for ax in m.axes:  # jog keys are released
            if ax.state is AxisState.JOG and rng.random() < 0.7:
                m.submit(JogStop(ax.name))
    for ax in m.axes:
        m.submit(JogStop(ax.name))
    sim.run(90_000)  # longer than any bound of the demo's sequences
    for ax in m.axes:
        assert ax.state in LASTING, (ax.name, ax.state, ax.deadline_what)
        assert ax.state is not AxisState.ERROR or ax.job_error != 0
    assert m.queued_blocks == 0
    errors = {e.code for e in m.events if is_error(e.code)}
    assert errors <= EXPECTED_ERRORS, errors


@pytest.mark.parametrize("seed", range(40))
def test_random_session_ends_every_sequence(seed: int) -> None:
    _session(seed)
