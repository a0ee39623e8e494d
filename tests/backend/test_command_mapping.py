"""The API and the scenario runner map onto the same nc_sim commands (one dispatcher).

Each pair below is one operator action written as an API command and as a TOML scenario
action: both become the same frozen command, so `Machine.submit` gives both the same outcome.
"""

from __future__ import annotations

from typing import Any

import pytest
from pydantic import TypeAdapter

from api.commands import Command as ApiCommand
from api.commands import EmergencyStopCommand
from backend.services.commands import to_nc
from nc_sim.commands import Accepted, Refused
from nc_sim.config import demo_machine
from nc_sim.errors import Code, NcUsageError
from nc_sim.scenario import commands, run_scenario
from nc_sim.snapshot import AxisState
from tests.nc_sim.sim_helpers import make

PAIRS: list[tuple[dict[str, Any], dict[str, Any]]] = [
    ({"type": "mdi", "block": "M3 S1000"}, {"mdi": "M3 S1000"}),
    ({"type": "spindle", "m": 4, "speed_rpm": 500}, {"spindle": {"m": 4, "rpm": 500}}),
    (
        {"type": "spindle_position", "spindle": "S1", "position_deg": 90, "direction": -1},
        {"spindle": {"name": "S1", "pos_deg": 90, "direction": -1}},
    ),
    ({"type": "gear", "m": 41}, {"spindle": {"gear": 41}}),
    ({"type": "home", "axis": "X"}, {"home": "X"}),
    (
        {"type": "jog", "axis": "Z", "action": "start", "direction": -1, "feed_mm_min": 600},
        {"jog": {"axis": "Z", "direction": -1, "feed_mm_min": 600}},
    ),
    ({"type": "jog", "axis": "Z", "action": "stop"}, {"jog": {"axis": "Z", "stop": True}}),
    (
        {"type": "jog", "axis": "X", "action": "step", "direction": -1, "distance": 2.5},
        {"jog": {"axis": "X", "step": -2.5}},
    ),
    (
        {"type": "move", "axis": "X", "target": 60, "rapid": False, "feed_mm_min": 1000},
        {"move": {"axis": "X", "target": 60, "rapid": False, "feed_mm_min": 1000}},
    ),
    (
        {"type": "override", "axis": "X", "percent": 50},
        {"hli": {"unit": "override", "value": 500, "axis": "X"}},
    ),
    (
        {"type": "hli", "unit": "DriveOn", "value": 0, "axis": "X"},
        {"hli": {"unit": "DriveOn", "value": 0, "axis": "X"}},
    ),
    ({"type": "plc_mode", "mode": "manual"}, {"plc": {"mode": "manual"}}),
    ({"type": "plc_ack", "m": 8}, {"plc": {"ack": 8}}),
    ({"type": "plc_ack"}, {"plc": {"ack": "all"}}),
    (
        {"type": "plc_signal", "signal": "ROTMOD_Q", "on": False},
        {"plc": {"signal": "ROTMOD_Q", "on": False}},
    ),
    ({"type": "reset"}, {"reset": True}),
    ({"type": "cycle_start"}, {"cycle_start": True}),
    ({"type": "feedhold", "on": True}, {"feedhold": True}),
    ({"type": "feedhold", "on": False}, {"feedhold": False}),
    ({"type": "single_block", "on": True}, {"single_block": True}),
]

API: TypeAdapter[ApiCommand] = TypeAdapter(ApiCommand)


@pytest.mark.parametrize(("api", "action"), PAIRS, ids=lambda v: str(v.get("type", "")))
def test_the_api_and_a_scenario_action_are_the_same_command(
    api: dict[str, Any], action: dict[str, Any]
) -> None:
    cmd = to_nc(API.validate_python(api))
    assert commands(action) == (cmd,)
    _, m1, _ = make()
    _, m2, _ = make()
    assert m1.submit(cmd) == m2.submit(commands(action)[0])  # one dispatcher: one outcome


def test_the_emergency_stop_route_and_a_scenario_action_are_the_same_command() -> None:
    assert commands({"emergency_stop": True}) == (to_nc(EmergencyStopCommand()),)


def test_a_program_action_is_the_api_program_load_then_cycle_start() -> None:
    text = "G00 X10\nM30"
    load = to_nc(API.validate_python({"type": "program_load", "name": "p1", "text": text}))
    start = to_nc(API.validate_python({"type": "cycle_start"}))
    assert commands({"program": text, "name": "p1"}) == (load, start)


def test_a_refused_block_is_the_same_refusal_through_either_way_in() -> None:
    api = to_nc(API.validate_python({"type": "mdi", "block": "M3 S20000"}))
    _, m, _ = make()
    out = m.submit(api)
    assert isinstance(out, Refused) and out.code == Code.GEAR_NO_RANGE
    _, m2, _ = make()
    assert m2.submit(*commands({"mdi": "M3 S20000"})) == out
    assert isinstance(m2.submit(*commands({"mdi": "M3 S1000"})), Accepted)


def test_a_scenario_records_a_refusal_as_an_event_and_runs_on() -> None:
    actions = [{"t_s": 0.1, "mdi": "M3 S20000"}, {"t_s": 0.2, "mdi": "M3 S1000"}]
    res = run_scenario(demo_machine(), {"duration_s": 0.5, "actions": actions})
    refused = [e for e in res.events if e.code == Code.GEAR_NO_RANGE]
    assert len(refused) == 1 and refused[0].t_s == pytest.approx(0.1)
    assert res.machine.axis("S1").state is AxisState.ENDLESS  # the next block still ran


def test_a_scenario_naming_no_axis_is_a_fault_of_the_scenario() -> None:
    """Misuse in a scenario file stops the run with the message (a typo, not a machine
    condition to record)."""
    with pytest.raises(NcUsageError, match="no axis or spindle 'Q'"):
        run_scenario(demo_machine(), {"duration_s": 0.1, "actions": [{"home": "Q"}]})
