"""Scenario actions of the NC channel: `program`, `cycle_start`, `feedhold`, `single_block`
(docs/api-guide.md: scenario format), their validation and a bad program's line and column."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from nc_sim.commands import CycleStart, Feedhold, ProgramLoad, SingleBlock
from nc_sim.config import demo_machine
from nc_sim.errors import Code, NcUsageError
from nc_sim.scenario import PROGRAM_NAME, commands, run_scenario

TWO_MOVES = "G00 X10\nG01 Z-95 F600\nM30\n"  # the demo stands at X50 Z-100


@pytest.mark.parametrize(
    ("action", "expected"),
    [
        ({"program": TWO_MOVES}, (ProgramLoad(PROGRAM_NAME, TWO_MOVES), CycleStart())),
        (
            {"program": TWO_MOVES, "name": "face_z"},
            (ProgramLoad("face_z", TWO_MOVES), CycleStart()),
        ),
        ({"cycle_start": True}, (CycleStart(),)),
        ({"feedhold": True}, (Feedhold(True),)),
        ({"feedhold": False}, (Feedhold(False),)),
        ({"single_block": True}, (SingleBlock(True),)),
        ({"single_block": False}, (SingleBlock(False),)),
    ],
    ids=["program", "program_named", "cycle_start", "hold_on", "hold_off", "sb_on", "sb_off"],
)
def test_each_channel_action_is_its_commands(
    action: dict[str, Any], expected: tuple[object, ...]
) -> None:
    assert commands({"t_s": 0.5, **action}) == expected


@pytest.mark.parametrize(
    ("action", "message"),
    [
        ({"program": 5}, "action program: program must be a string, not 5"),
        ({"program": "M30", "name": 3}, "action program: name must be a string, not 3"),
        ({"feedhold": "yes"}, "action feedhold: feedhold must be true or false, not 'yes'"),
        ({"single_block": 1}, "action single_block: single_block must be true or false, not 1"),
        ({"cycle_start": False}, "action cycle_start: cycle_start must be true"),
        ({"hli": {"value": 1}}, "action hli: field unit missing"),
        ({"program_text": "M30"}, "unknown action"),
    ],
)
def test_a_bad_action_names_the_action_and_the_field(action: dict[str, Any], message: str) -> None:
    with pytest.raises(NcUsageError) as err:
        commands(action)
    assert str(err.value).startswith(message)


def test_a_bad_program_is_recorded_with_its_line_and_column_and_not_started() -> None:
    """A program error is the machine's answer, not a fault of the scenario file: the run goes
    on, the job error names the line and column (the F missing before G01 on line 2, at the
    G01 word in column 5), and no cycle start follows a program that did not load."""
    actions = [{"t_s": 0.1, "program": "G00 X10\nN20 G01 X20\nM30\n", "name": "no_feed"}]
    res = run_scenario(demo_machine(), {"duration_s": 0.3, "actions": actions})
    errors = [e for e in res.events if e.error]
    assert [(e.code, e.line, e.column) for e in errors] == [(Code.FEED_MISSING, 2, 5)]
    assert errors[0].t_s == pytest.approx(0.1)
    assert "no_feed" in errors[0].message
    assert not [e for e in res.events if e.code == Code.EV_PROGRAM_START]
    assert res.machine.channel.progress.program is None


def test_a_program_that_loads_is_kept_by_the_channel() -> None:
    actions = [{"t_s": 0.1, "program": TWO_MOVES, "name": "two_moves"}]
    res = run_scenario(demo_machine(), {"duration_s": 0.2, "actions": actions})
    loaded = res.machine.channel.progress.program
    assert loaded is not None and (loaded.name, loaded.text) == ("two_moves", TWO_MOVES)
    assert [e.t_s for e in res.events if e.code == Code.EV_PROGRAM_LOADED] == [pytest.approx(0.1)]


def test_a_program_action_runs_the_program_to_its_end() -> None:
    """G00 X10, then G01 Z-95 at 600 mm/min: 5 mm take 0.5 s plus the ramps; after 3 s both
    axes stand at the programmed end and the program has ended without a job error."""
    actions = [{"t_s": 0.1, "program": TWO_MOVES}]
    res = run_scenario(demo_machine(), {"duration_s": 3.0, "actions": actions})
    assert not [e for e in res.events if e.error]
    assert len([e for e in res.events if e.code == Code.EV_PROGRAM_END]) == 1
    assert res.columns["X.pos_cmd_mm"][-1] == pytest.approx(10.0, abs=1e-6)
    assert res.columns["Z.pos_cmd_mm"][-1] == pytest.approx(-95.0, abs=1e-6)
    # the G01 block: Z never faster than its feed
    z_speed = np.abs(np.asarray(res.columns["Z.vel_cmd_mm_min"]))
    assert z_speed.max() <= 600.0 * (1 + 1e-9)


def test_a_scenario_expresses_the_door_the_gear_change_sync_and_the_stop_at_m30() -> None:
    """What the manuals' audit added, in a scenario's own words: the PLC's reduced speed on a
    program's path [002 §2.8], m_synch of the gear change [000 §2.8.2] and the HLI unit
    spindle_stop_at_program_end."""
    scenario = {
        "duration_s": 12.0,
        "parameters": {
            "channel": {"m_synch[42]": "MVS_SVS"},
            "Z": {"getriebe[0].vb_max_red": 25000},  # 25 mm/s, in µm/s
        },
        "actions": [
            {"t_s": 0.0, "hli": {"axis": "Z", "unit": "reduced_speed", "value": 1}},
            {"t_s": 0.0, "hli": {"axis": "S1", "unit": "spindle_stop_at_program_end", "value": 1}},
            {"t_s": 0.1, "program": "M3 S650\nS950 G01 Z-50 F6000\nM30\n"},
        ],
    }
    res = run_scenario(demo_machine(), scenario)
    assert not [e for e in res.events if e.error]
    z_speed = np.abs(np.asarray(res.columns["Z.vel_cmd_mm_min"]))
    assert z_speed.max() == pytest.approx(1500.0)  # 25 mm/s, not F6000
    gear = np.asarray(res.columns["S1.gear"])
    in_m41 = int(np.argmax(gear == 2))
    in_m42 = in_m41 + int(np.argmax(gear[in_m41:] == 3))
    assert int(np.argmax(z_speed > 0)) > in_m42  # the block waited for its gear change
    assert res.columns["Z.pos_cmd_mm"][-1] == pytest.approx(-50.0)
    assert res.columns["S1.speed_cmd_rpm"][-1] == 0.0  # M30 stopped it


def test_a_scenario_sets_a_safety_zone_and_its_signal() -> None:
    # zone 1 of X from 40 to 60 mm (0.1 µm) at 10 mm/s (µm/s) [002 §2.8]: a move into it
    scenario = {
        "duration_s": 4.0,
        "parameters": {
            "X": {
                "kenngr.red_speed_zone_neg": 400000,
                "kenngr.red_speed_zone_pos": 600000,
                "getriebe[0].vb_max_red_zone": 10000,
            }
        },
        "actions": [
            {"t_s": 0.0, "hli": {"axis": "X", "unit": "reduced_speed_zone", "value": 1}},
            {"t_s": 0.1, "mdi": "G01 X70 F3000"},  # from X50, inside the zone
        ],
    }
    res = run_scenario(demo_machine(), scenario)
    x_speed = np.abs(np.asarray(res.columns["X.vel_cmd_mm_min"]))
    assert x_speed.max() == pytest.approx(600.0)  # 10 mm/s, not F3000
