"""Sequences that must progress or end in a job error: jog, homing order, PLC waits, gear
rule, spindle jog and move, automatic homing on M5, watchdogs and bounds (issue 13)."""

from __future__ import annotations

import pytest

from nc_sim.errors import Code
from nc_sim.machine.axis import AxisState
from nc_sim.machine.machine import Machine
from nc_sim.sim import Simulation
from tests.nc_sim.sim_helpers import L, make, record

S = "S1"
RPM = 6.0  # °/s per rpm


def codes(m: Machine) -> list[int]:
    return [e.code for e in m.events]


def home_x(sim: Simulation, m: Machine) -> None:
    assert m.home("X") is None
    record(sim, 10.0)
    assert m.axis("X").homed and m.axis("X").state is AxisState.STANDSTILL


# --- item 8: a jog renewed at the software limit -----------------------------------------------
@pytest.mark.parametrize("release", ["jog_stop", "reset"])
def test_jog_renewed_at_the_software_limit_then_released_stands_still(release: str) -> None:
    sim, m, cfg = make()
    x = m.axis("X")
    home_x(sim, m)
    swe_pos = cfg.axis("X").eng("kenngr.swe_pos")
    assert m.jog_start("X", 1) is None
    record(sim, 20.0)
    assert m.k.st[x.slot, L.S_P_CMD] == swe_pos and x.state is AxisState.STANDSTILL
    # the HMI renews the held key's lease: a jog towards the limit the axis stands at
    assert m.jog_start("X", 1) is None
    record(sim, 0.05)
    if release == "jog_stop":
        m.jog_stop("X")
    else:
        m.reset()
    record(sim, 0.05)
    assert x.state is AxisState.STANDSTILL
    assert m.jog_step("X", -1.0) is None  # increments are accepted again
    record(sim, 2.0)
    assert m.k.st[x.slot, L.S_P_CMD] == pytest.approx(swe_pos - 1.0)
    assert Code.AXIS_BUSY not in codes(m)


# --- item 9: timed out means gone --------------------------------------------------------------
def test_a_late_acknowledgement_after_the_timeout_acknowledges_nothing() -> None:
    sim, m, cfg = make(channel={"plc.m_ack_timeout": 300000})
    m.plc_mode("manual")
    assert m.mdi("M8").ok
    record(sim, 0.1)
    assert [p.m for p in m.plc.pending] == [8]
    record(sim, cfg.channel_eng("plc.m_ack_timeout"))
    assert Code.PLC_ACK_TIMEOUT in codes(m)
    assert m.plc.pending == [] and m.queued_blocks == 0  # no longer pending anywhere
    assert m.plc_acknowledge(8) == 0
    assert m.plc_acknowledge(None) == 0
    assert Code.EV_M_ACK not in codes(m)
