"""`inbetrieb sim` as a user runs it: the console script on a scenario file."""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from nc_sim.errors import Code

ROOT = Path(__file__).resolve().parents[2]


def run_cli(scenario: Path, out: Path) -> subprocess.CompletedProcess[str]:
    exe = shutil.which("inbetrieb", path=str(Path(sys.executable).parent))
    assert exe, "the console script is installed with the package"
    # the script's own folder comes first on sys.path: point it at this checkout's packages
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [exe, "sim", str(scenario), "--out", str(out)],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_spindle_override_scenario(tmp_path: Path) -> None:
    # the manual's example: M3 S1000, override 50 % -> 500 rpm [000 §2.4.1]
    res = run_cli(ROOT / "examples" / "spindle_override.toml", tmp_path)
    assert res.returncode == 0, res.stderr
    rows = list(csv.DictReader((tmp_path / "trace.csv").read_text().splitlines()))
    assert len(rows) == 6000
    for col in (
        "speed_cmd_rpm",
        "speed_act_rpm",
        "pos_cmd_deg",
        "pos_act_deg",
        "lag_deg",
        "accel_cmd_deg_s2",
        "speed_reached",
        "stopped",
        "gear",
        "state",
        "job_error",
    ):
        assert f"S1.{col}" in rows[0]
    for col in ("pos_cmd_mm", "pos_act_mm", "lag_mm", "vel_cmd_mm_min", "vel_act_mm_min"):
        assert f"X.{col}" in rows[0]
    at = {round(float(r["t_s"]), 3): r for r in rows}
    assert float(at[2.9]["S1.speed_cmd_rpm"]) == pytest.approx(1000.0)
    assert float(at[2.9]["S1.lag_deg"]) == pytest.approx(600.0, rel=0.01)  # v/(kv·0.01)
    assert at[2.9]["S1.speed_reached"] == "1"
    assert float(at[5.9]["S1.speed_cmd_rpm"]) == pytest.approx(500.0)
    events = [json.loads(line) for line in (tmp_path / "events.jsonl").read_text().splitlines()]
    assert not [e for e in events if e["error"]]
    assert {"t_s", "axis", "code", "message"} <= set(events[0])


def guide_scenario() -> str:
    """The scenario example of the API guide (docs/api-guide.md), as printed there (the first
    toml block after "Scenario format")."""
    text = (ROOT / "docs" / "api-guide.md").read_text(encoding="utf-8")
    after = text[text.index("Scenario format (TOML):") :]
    start = after.index("```toml\n") + len("```toml\n")
    return after[start : after.index("```", start)]


def test_the_guides_scenario_runs_as_written(tmp_path: Path) -> None:
    """`t_s = 0.0, mdi = "M3 S1000"` on a fresh demo: time 0 is the moment the machine is
    ready, so the block is accepted; override 50 % at 1.5 s gives 500 rpm [000 §2.4.1]."""
    scenario = tmp_path / "guide.toml"
    scenario.write_text(guide_scenario(), encoding="utf-8")
    res = run_cli(scenario, tmp_path / "out")
    assert res.returncode == 0, res.stderr
    lines = (tmp_path / "out" / "events.jsonl").read_text().splitlines()
    events = [json.loads(line) for line in lines]
    assert not [e for e in events if e["error"]]  # no 90001/90007 at t = 0
    started = [e for e in events if e["code"] == Code.EV_M_START]  # the M3 begins at time 0
    assert started and started[0]["t_s"] == pytest.approx(0.0)
    rows = list(csv.DictReader((tmp_path / "out" / "trace.csv").read_text().splitlines()))
    assert float(rows[0]["t_s"]) == pytest.approx(0.001)
    assert float(rows[0]["S1.speed_cmd_rpm"]) > 0.0  # accelerating from the first cycle
    assert float(rows[-1]["S1.speed_cmd_rpm"]) == pytest.approx(500.0)


def test_plc_fault_scenario_ends_in_a_timeout_error(tmp_path: Path) -> None:
    res = run_cli(ROOT / "examples" / "plc_fault.toml", tmp_path)
    assert res.returncode == 0, res.stderr
    events = [json.loads(line) for line in (tmp_path / "events.jsonl").read_text().splitlines()]
    errors = [e for e in events if e["error"]]
    assert [e["code"] for e in errors] == [90004]
    assert errors[0]["t_s"] == pytest.approx(1.1)  # output at 0.1 s + 1 s timeout


def test_bad_parameter_in_a_scenario_is_a_clear_error(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('duration_s = 0.1\n[parameters.X]\n"getriebe[0].kv" = 0\n')
    res = run_cli(bad, tmp_path / "out")
    assert res.returncode == 2
    assert "getriebe[0].kv = 0 is out of range 1" in res.stderr
    assert not (tmp_path / "out" / "trace.csv").exists()


def test_spindle_sequences_scenario_exposes_the_spindle_signals(tmp_path: Path) -> None:
    res = run_cli(ROOT / "examples" / "gear_change_m19.toml", tmp_path)
    assert res.returncode == 0, res.stderr
    rows = list(csv.DictReader((tmp_path / "trace.csv").read_text().splitlines()))
    for col in (
        "speed_monitoring_active",
        "speed_monitoring_invalid",
        "open_loop",
        "override_pct",
        "homed",
        "in_position",
    ):
        assert f"S1.{col}" in rows[0]
    at = {round(float(r["t_s"]), 3): r for r in rows}
    assert at[3.9]["S1.gear"] == "2" and float(at[3.9]["S1.speed_cmd_rpm"]) == 650.0
    assert at[7.9]["S1.gear"] == "3" and float(at[7.9]["S1.speed_cmd_rpm"]) == 950.0
    assert at[7.9]["S1.speed_monitoring_active"] == "1"
    assert at[11.9]["S1.in_position"] == "1" and at[11.9]["S1.homed"] == "1"
    assert abs((float(at[11.9]["S1.pos_act_deg"]) - 90.0 + 180) % 360 - 180) <= 0.1
    events = [json.loads(line) for line in (tmp_path / "events.jsonl").read_text().splitlines()]
    assert not [e for e in events if e["error"]]
    # the facts are fields: gear stage 2 is M41, 3 is M42; M19 done is in position, m 19
    assert [e["seq"] for e in events] == list(
        range(events[0]["seq"], len(events) + events[0]["seq"])
    )
    changed = [e for e in events if e["code"] == Code.EV_GEAR_CHANGED]
    assert [(e["axis"], e["gear"]) for e in changed] == [("S1", 2), ("S1", 3)]
    assert [e["message"] for e in changed] == ["S1 gear M42 -> M41", "S1 gear M41 -> M42"]
    m41 = [e for e in events if e["code"] == Code.EV_M_OUTPUT and e["m"] == 41]
    assert m41 and all(e["gear"] == 2 for e in m41)
    assert all(e["message"].startswith("M41 output") for e in m41)
    # in position after M19 (m 19), then after S[G74] homing (no M function)
    in_position = [e for e in events if e["code"] == Code.EV_IN_POSITION]
    assert [(e["axis"], e["m"]) for e in in_position] == [("S1", 19), ("S1", None)]
    assert in_position[0]["value"] == pytest.approx(90.0)  # where it stopped, °
    assert in_position[0]["message"] == "S1 at 90° (M19)"


def test_a_program_action_reaches_the_channel_with_line_and_column(tmp_path: Path) -> None:
    """`program = \"\"\"...\"\"\"` through the console script. The G18 arc on line 3 starts at
    X10 Z0 with its centre at X0 Z0 (I-10): start radius 10, but its end X0 Z12 lies 12 from the
    centre, so the load fails at the I word (column 12); events.jsonl names line and column and
    the run goes on to its next action."""
    scenario = tmp_path / "program.toml"
    scenario.write_text(
        'duration_s = 0.2\n[[actions]]\nt_s = 0.05\nname = "bad_arc"\nprogram = """\n'
        "G18 G00 X10 Z0\n(line 2: the arc starts at X10 Z0, centre Z0 X0)\n"
        'G03 X0 Z12 I-10 F100\nM30\n"""\n'
        "[[actions]]\nt_s = 0.1\nfeedhold = true\n",
        encoding="utf-8",
    )
    res = run_cli(scenario, tmp_path / "out")
    assert res.returncode == 0, res.stderr
    lines = (tmp_path / "out" / "events.jsonl").read_text().splitlines()
    events = [json.loads(line) for line in lines]
    errors = [e for e in events if e["error"]]
    assert [(e["code"], e["line"], e["column"]) for e in errors] == [(Code.ARC_GEOMETRY, 3, 12)]
    assert errors[0]["t_s"] == pytest.approx(0.05)
    # the next action ran: a channel HLI write at its time, the unit and value as fields
    hli = [e for e in events if e["code"] == Code.EV_HLI and e["axis"] == ""]
    assert [(e["t_s"], e["signal"], e["value"]) for e in hli] == [
        (pytest.approx(0.1), "feedhold", 1)
    ]
    assert hli[0]["message"] == "channel feedhold = 1"


def test_a_mistyped_channel_action_stops_the_run_naming_it(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('duration_s = 0.1\n[[actions]]\nsingle_block = "on"\n', encoding="utf-8")
    res = run_cli(bad, tmp_path / "out")
    assert res.returncode == 2
    assert "action single_block: single_block must be true or false, not 'on'" in res.stderr


CHANGEOVER = """duration_s = 1.0
[[actions]]
t_s = 0.0
plc = { mode = "manual" }
[[actions]]
t_s = 0.1
mdi = "#CAX"
[[actions]]
t_s = 0.5
plc = { signal = "ROTMOD_Q", on = true }
"""


def test_a_changeover_to_c_keeps_the_trace_columns_and_records_the_mode(tmp_path: Path) -> None:
    """#CAX with a manual PLC: S1 is in no mode from the activation until the scenario sets
    ROTMOD_Q at 0.5 s, then the rotary axis C. The columns keep the configured name S1 (no
    `C.*`), the same header as a run in which S1 stays the spindle."""
    (tmp_path / "cax.toml").write_text(CHANGEOVER, encoding="utf-8")
    (tmp_path / "idle.toml").write_text("duration_s = 0.1\n", encoding="utf-8")
    for name in ("cax", "idle"):
        res = run_cli(tmp_path / f"{name}.toml", tmp_path / name)
        assert res.returncode == 0, res.stderr
    header = (tmp_path / "cax" / "trace.csv").read_text().splitlines()[0].split(",")
    assert header == (tmp_path / "idle" / "trace.csv").read_text().splitlines()[0].split(",")
    assert "S1.rotary_mode" in header and not [c for c in header if c.startswith("C.")]
    for col in ("mvpos", "mvneg", "ready"):
        assert f"S1.{col}" in header and f"X.{col}" in header
    rows = list(csv.DictReader((tmp_path / "cax" / "trace.csv").read_text().splitlines()))
    at = {round(float(r["t_s"]), 3): r for r in rows}
    assert at[0.05]["S1.rotary_mode"] == "0" and at[0.45]["S1.rotary_mode"] == "0"
    assert at[0.6]["S1.rotary_mode"] == "1" and at[0.999]["S1.rotary_mode"] == "1"
    assert at[0.6]["S1.ready"] == "1" and at[0.6]["S1.mvpos"] == at[0.6]["S1.mvneg"] == "0"
