"""Running an assistant by its descriptor (nc_sim/assist/registry.py): the inputs checked
against the descriptor, the defaults added, the procedure imported and run; what every
caller (the service, its workers, the command line) does the same way.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any

from nc_sim.assist.descriptor import Assistant, Kind, resolve
from nc_sim.assist.registry import assistant
from nc_sim.assist.result import ExperimentError, Result
from nc_sim.config import MachineConfig
from nc_sim.errors import NcUsageError
from nc_sim.faults import Fault
from nc_sim.params import Scope
from nc_sim.params import resolve as resolve_parameter


def _inputs(a: Assistant, values: Mapping[str, object]) -> dict[str, Any]:
    errors = a.check(values)
    if errors:
        raise ExperimentError("; ".join(errors))
    return a.with_defaults(values)


def _with_before(cfg: MachineConfig, result: Result) -> Result:
    """A calculator's changes with the value each replaces as the list shows it now (its
    default when unset): a calculator knows only what it computed."""
    changes = []
    for c in result.changes:
        scope = Scope.CHANNEL if c.target == "channel" else Scope.AXIS
        values = cfg.list_values(scope, c.target)
        before = values.get(c.parameter, resolve_parameter(scope, c.parameter).default)
        changes.append(replace(c, before=before))
    return replace(result, changes=tuple(changes))


def _live_on_copy(a: Assistant, cfg: MachineConfig, inputs: dict[str, Any]) -> Result:
    """The live procedure on a fresh copy of the machine (imported here: the kernel loads only
    where an experiment runs, never for a calculator)."""
    on_copy = resolve("nc_sim.assist.procedure:on_copy")
    start = resolve(a.live)
    result: Result = on_copy(cfg, lambda m: start(m, **inputs))
    return result


def run(
    name: str, cfg: MachineConfig, values: Mapping[str, object], faults: Sequence[Fault] = ()
) -> Result:
    """Assistant `name` with `values` on a copy of the machine `cfg` describes with the
    training `faults` in force on it (a calculator: on its parameters); ExperimentError when
    the inputs or the machine do not allow it."""
    a = assistant(name)
    inputs = _inputs(a, values)
    try:
        if "axis" in inputs:
            cfg.axis(str(inputs["axis"]))
        if a.kind is Kind.CALCULATOR:
            result: Result = resolve(a.run)(cfg, **inputs)
        else:  # the kernel loads here, where an experiment runs
            copies_with = resolve("nc_sim.assist.procedure:copies_with")
            with copies_with(faults):
                result = resolve(a.run)(cfg, **inputs) if a.run else _live_on_copy(a, cfg, inputs)
    except NcUsageError as e:
        raise ExperimentError(str(e)) from None
    return _with_before(cfg, result) if a.kind is Kind.CALCULATOR else result


def live(name: str, values: Mapping[str, object]) -> Callable[[Any], Any]:
    """The start of assistant `name` on a live machine: a function of the machine giving
    the procedure its worker paces (procedure.LiveRun); ExperimentError when it cannot run
    live. (Typed loosely: the machine's module loads the kernel, which a calculator's caller
    must not.)"""
    a = assistant(name)
    if not a.live:
        raise ExperimentError(f"{name} runs on copies only")
    inputs = _inputs(a, values)
    start = resolve(a.live)
    return lambda m: start(m, **inputs)
