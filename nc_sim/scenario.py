"""Scripted experiments: parameter overrides and timed actions on one machine.

The scenario is the parsed TOML as a dict (see docs/api-guide.md, `examples/`).
`run_scenario` is pure: it returns the trace columns and the event list; writing files is the
caller's business.
Scenario time 0 is the moment the machine is ready: the runner first lets the power-on
sequence run (drives boot, the PLC switches them on), as an engineer waits for a machine to
come up before the first block; events of that sequence carry negative times.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from nc_sim.commands import (
    Accepted,
    Command,
    CycleStart,
    EmergencyStop,
    Feedhold,
    GearChange,
    HliWrite,
    Home,
    Invalid,
    JogStart,
    JogStep,
    JogStop,
    Mdi,
    Move,
    PlcAck,
    PlcMode,
    PlcSignal,
    ProgramLoad,
    Reset,
    SingleBlock,
    SpindlePosition,
    SpindleRun,
)
from nc_sim.config import MachineConfig, apply_overrides
from nc_sim.errors import NcUsageError
from nc_sim.events import EVENT_LOG_LEN, Event
from nc_sim.machine.machine import Machine
from nc_sim.params import Scope, resolve
from nc_sim.params.listfile import parse_value
from nc_sim.signals import machine_signals, signal_columns
from nc_sim.sim import Simulation

POWER_ON_LIMIT_S = 60.0  # a machine not ready by then has a configuration fault
# cycles run between reads of the event log: far fewer than the events it holds
COLLECT_CYCLES = EVENT_LOG_LEN // 10


@dataclass
class ScenarioResult:
    columns: dict[str, np.ndarray]
    events: list[Event]
    machine: Machine


def _value(scope: Scope, name: str, value: Any) -> float | int | str:
    d = resolve(scope, name)
    return (
        value
        if isinstance(value, int | float) and d.is_numeric
        else parse_value(d, name, str(value))
    )


def apply_parameters(cfg: MachineConfig, params: Mapping[str, Mapping[str, Any]]) -> None:
    """Apply `[parameters.channel]` and `[parameters.<axis>]` tables (native list names)."""
    for target, table in params.items():
        scope = Scope.CHANNEL if target == "channel" else Scope.AXIS
        values = {name: _value(scope, name, v) for name, v in table.items()}
        apply_overrides(cfg, scope, target, values)


ACTIONS = (
    "mdi",
    "program",
    "cycle_start",
    "feedhold",
    "single_block",
    "hli",
    "plc",
    "jog",
    "move",
    "home",
    "spindle",
    "reset",
    "emergency_stop",
)
PROGRAM_NAME = "scenario"  # the label of a `program` action's text without `name`


def commands(action: Mapping[str, Any]) -> tuple[Command, ...]:
    """The commands a TOML action stands for, submitted in this order (docs/api-guide.md:
    scenario format); `program` is a load and a cycle start. A missing or mistyped field is an
    NcUsageError naming the action and the field."""
    kind = next((k for k in ACTIONS if k in action), None)
    if kind is None:
        raise NcUsageError(f"unknown action {dict(action)}: one of {', '.join(ACTIONS)}")
    try:
        return _commands(kind, action)
    except KeyError as e:
        raise NcUsageError(f"action {kind}: field {e.args[0]} missing") from e
    except (TypeError, ValueError) as e:
        raise NcUsageError(f"action {kind}: {e}") from e


def _flag(action: Mapping[str, Any], field: str) -> bool:
    """A `true | false` field (TOML booleans only: `"yes"` or `1` is a typo, not a value)."""
    value = action[field]
    if not isinstance(value, bool):
        raise ValueError(f"{field} must be true or false, not {value!r}")
    return value


def _text(action: Mapping[str, Any], field: str) -> str:
    value = action[field]
    if not isinstance(value, str):
        raise ValueError(f"{field} must be a string, not {value!r}")
    return value


def _commands(kind: str, action: Mapping[str, Any]) -> tuple[Command, ...]:
    if kind == "program":
        name = _text(action, "name") if "name" in action else PROGRAM_NAME
        return ProgramLoad(name, _text(action, "program")), CycleStart()
    if kind == "cycle_start":
        if not _flag(action, "cycle_start"):
            raise ValueError("cycle_start must be true (there is no cycle start off)")
        return (CycleStart(),)
    if kind == "feedhold":
        return (Feedhold(_flag(action, "feedhold")),)
    if kind == "single_block":
        return (SingleBlock(_flag(action, "single_block")),)
    return (_command(action),)


def _command(action: Mapping[str, Any]) -> Command:
    """The one command of an action that is one command."""
    if "mdi" in action:
        return Mdi(str(action["mdi"]))
    if "hli" in action:
        h = action["hli"]
        return HliWrite(str(h["unit"]), int(h["value"]), h.get("axis"))
    if "plc" in action:
        p = action["plc"]
        if "ack" in p:
            return PlcAck(None if p["ack"] == "all" else int(p["ack"]))
        if "signal" in p:
            return PlcSignal(str(p["signal"]), bool(p["on"]))
        return PlcMode(str(p["mode"]), p.get("delay_s"))
    if "jog" in action:
        j = action["jog"]
        axis = str(j["axis"])
        if j.get("stop"):
            return JogStop(axis)
        if "step" in j:
            return JogStep(axis, float(j["step"]), j.get("feed_mm_min"))
        return JogStart(axis, int(j.get("direction", 1)), j.get("feed_mm_min"))
    if "move" in action:
        mv = action["move"]
        return Move(
            str(mv["axis"]), float(mv["target"]), bool(mv.get("rapid", True)), mv.get("feed_mm_min")
        )
    if "home" in action:
        return Home(str(action["home"]))
    if "spindle" in action:
        sp = action["spindle"]
        name = str(sp.get("name", "S"))
        if "pos_deg" in sp:
            return SpindlePosition(name, float(sp["pos_deg"]), sp.get("direction"), sp.get("rpm"))
        if "gear" in sp:
            return GearChange(name, int(sp["gear"]))
        return SpindleRun(name, int(sp["m"]), sp.get("rpm"))
    if action.get("reset"):
        return Reset()
    if action.get("emergency_stop"):
        return EmergencyStop()
    raise NcUsageError(f"unknown action {dict(action)}")  # ACTIONS and this disagree


def trace_columns(m: Machine, rec: np.ndarray, t0_cycle: int) -> dict[str, np.ndarray]:
    """Named trace columns `t_s` and `<axis>.<signal>` (nc_sim.signals) from a kernel record."""
    n = rec.shape[0]
    cols: dict[str, np.ndarray] = {"t_s": (t0_cycle + 1 + np.arange(n)) * m.k.cycle_s}
    sigs = machine_signals(m.axes, m.channel_slot, m.rotary_spindle)
    data = signal_columns(sigs, rec)
    for i, s in enumerate(sigs):
        cols[s.name] = data[i]
    return cols


def run_scenario(cfg: MachineConfig, scenario: Mapping[str, Any]) -> ScenarioResult:
    """Run a scenario on a machine config (which it modifies by the parameter tables)."""
    apply_parameters(cfg, scenario.get("parameters", {}))
    sim = Simulation(cfg.cycle_s)
    m = sim.add(cfg)
    power_on(sim, m)
    t0 = sim.cycle
    duration = float(scenario.get("duration_s", 1.0))
    n_total = round(duration / cfg.cycle_s)
    actions = sorted(scenario.get("actions", []), key=lambda a: float(a.get("t_s", 0.0)))
    rec = sim.new_record(n_total)
    events: list[Event] = []  # every event: the machine's own log keeps only the newest
    cursor = m.events.first_seq
    done = 0

    def collect() -> None:
        nonlocal cursor
        read = m.events.since(cursor)
        events.extend(read.entries)
        cursor = read.cursor

    def run_to(end: int) -> None:
        nonlocal done
        while done < end:
            n = min(end - done, COLLECT_CYCLES)
            sim.run(n, rec[done : done + n])
            done += n
            collect()

    for action in actions:
        run_to(min(n_total, round(float(action.get("t_s", 0.0)) / cfg.cycle_s)))
        for cmd in commands(action):
            outcome = m.submit(cmd)  # a refusal, a bad block or program: in the event log
            if isinstance(outcome, Invalid) and outcome.code is None:  # a fault of the scenario
                raise NcUsageError(f"action {dict(action)}: {outcome.message}")
            if not isinstance(outcome, Accepted):  # a program that did not load is not started
                break
        collect()
    run_to(n_total)
    events = [replace(e, t_s=(e.cycle - t0) * cfg.cycle_s) for e in events]
    return ScenarioResult(trace_columns(m, rec, 0), events, m)


def power_on(sim: Simulation, m: Machine) -> None:
    """Run the power-on sequence until the machine is ready (NcUsageError if it never is)."""
    limit = round(POWER_ON_LIMIT_S / sim.kernel.cycle_s)
    while not m.powered:
        if sim.cycle >= limit:
            waiting = {
                ax.name: ax.missing_enables() + ax.drive.missing()
                for ax in m.axes
                if not ax.drive_follows()
            }
            raise NcUsageError(f"machine not ready after {POWER_ON_LIMIT_S:g} s: {waiting}")
        sim.run(1)
