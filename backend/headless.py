"""`inbetrieb sim`: run a TOML scenario as fast as possible and write trace.csv, events.jsonl."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np

from nc_sim.config import MachineConfig, demo_machine, machine_from_lists
from nc_sim.scenario import ScenarioResult, run_scenario


def load_machine(ref: str, base: Path) -> MachineConfig:
    """`demo` or a folder with `channel.lis` and `axis_<log_achs_nr>.lis` files."""
    if ref == "demo":
        return demo_machine()
    folder = (base / ref).resolve()
    channel = (folder / "channel.lis").read_text(encoding="utf-8")
    axes = {int(p.stem[5:]): p.read_text(encoding="utf-8") for p in folder.glob("axis_*.lis")}
    return machine_from_lists(folder.name, channel, axes)


def write_trace(path: Path, columns: dict[str, np.ndarray]) -> None:
    """CSV with a header row; floats with 9 significant digits (0.1 µm at 100 m)."""
    names = list(columns)
    data = np.column_stack([columns[n] for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")


def write_events(path: Path, result: ScenarioResult) -> None:
    with path.open("w", encoding="utf-8") as f:
        for e in result.events:
            rec = {
                "seq": e.seq,
                "t_s": round(e.t_s, 9),
                "axis": e.axis,
                "code": e.code,
                "error": e.error,
                "message": e.message,
                "m": e.m,
                "gear": e.gear,
                "line": e.line,
                "column": e.column,
                "signal": e.signal,
                "value": e.value,
            }
            f.write(json.dumps(rec) + "\n")


def run_file(scenario_path: Path, out_dir: Path) -> ScenarioResult:
    """Load, run and write one scenario; returns the result."""
    scenario = tomllib.loads(scenario_path.read_text(encoding="utf-8"))
    cfg = load_machine(str(scenario.get("machine", "demo")), scenario_path.parent)
    result = run_scenario(cfg, scenario)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_trace(out_dir / "trace.csv", result.columns)
    write_events(out_dir / "events.jsonl", result)
    return result
