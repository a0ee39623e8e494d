"""`inbetrieb assist NAME [--machine demo|DIR] [--set TARGET.PARAM=VALUE ...] [options] [--json]`:
the commissioning assistants (nc_sim/assist) headless, in simulated time.

The options are made from each assistant's descriptor (nc_sim/assist/registry.py): one per
input (`--feed-mm-min`, or the short name the descriptor gives, `--feed`), with its range and
unit in the help; the inputs are checked as the service checks them.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path

from nc_sim.assist.descriptor import (
    Assistant,
    AxisChoice,
    Choice,
    Flag,
    Input,
    Number,
    NumberList,
    Table,
)
from nc_sim.assist.registry import ASSISTANTS, assistant
from nc_sim.assist.result import Result
from nc_sim.assist.run import run as run_assistant
from nc_sim.config import MachineConfig
from nc_sim.errors import NcUsageError
from nc_sim.params import ParamListError
from nc_sim.params.listfile import ParamError
from nc_sim.units import AxisKind


class UsageError(Exception):
    """A bad option: printed as `inbetrieb assist NAME: ...`, exit code 2."""


def _machine(args: argparse.Namespace) -> MachineConfig:
    """The machine of --machine with the --set overrides (TARGET.PARAM=VALUE, TARGET an axis
    name or `channel`), as `inbetrieb sim` builds it from a scenario."""
    from backend.headless import load_machine
    from nc_sim.scenario import apply_parameters

    cfg = load_machine(args.machine, Path.cwd())
    tables: dict[str, dict[str, str]] = {}
    for item in args.set:
        target, dot, rest = item.partition(".")
        name, eq, value = rest.partition("=")
        if not (dot and eq and target and name):
            raise UsageError(
                f"--set {item!r}: expected TARGET.PARAM=VALUE (e.g. X.getriebe[0].kv=300)"
            )
        tables.setdefault(target, {})[name] = value
    apply_parameters(cfg, tables)
    return cfg


def _option(i: Input) -> str:
    return "--" + (i.cli or i.name.replace("_", "-"))


def _numbers(i: NumberList) -> Callable[[str], list[float]]:
    def parse(text: str) -> list[float]:
        try:
            return [float(k) for k in text.split(",") if k.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{i.name} must be numbers ({i.item.unit}) separated by commas, not {text!r}"
            ) from None

    return parse


def _rows(i: Table) -> Callable[[str], list[dict[str, float]]]:
    names = [c.name for c in i.columns]
    units = ":".join(c.unit for c in i.columns)

    def parse(text: str) -> list[dict[str, float]]:
        try:
            rows = [p.split(":") for p in text.split(",") if p.strip()]
            return [dict(zip(names, map(float, r), strict=True)) for r in rows]
        except ValueError:
            pairs = ":".join(n.split("_")[0] for n in names)
            raise argparse.ArgumentTypeError(
                f"{i.name} must be {pairs} pairs ({units}) separated by commas, not {text!r}"
            ) from None

    return parse


def _add(p: argparse.ArgumentParser, i: Input) -> None:
    """The option of one input, with its range and unit in the help."""
    option, dest = _option(i), i.name
    match i:
        case Number():
            kind: Callable[[str], object] = int if i.integer else float
            p.add_argument(option, dest=dest, type=kind, help=f"{i.text} ({i.range_text()})")
        case Choice():
            meaning = ", ".join(f"{o} {t}" for o, t in i.options)
            choices = [o for o, _ in i.options]
            p.add_argument(option, dest=dest, type=int, choices=choices, help=meaning)
        case Flag():
            p.add_argument(option, dest=dest, action="store_true", default=None, help=i.text)
        case AxisChoice():
            p.add_argument(option, dest=dest, help=f"{i.text} (default: the machine's first)")
        case NumberList():
            p.add_argument(option, dest=dest, type=_numbers(i), help=i.text)
        case Table():
            p.add_argument(option, dest=dest, type=_rows(i), help=i.text)


def _inputs(a: Assistant, args: argparse.Namespace, cfg: MachineConfig) -> dict[str, object]:
    """The options given; an axis not given is the machine's first of the kinds it takes."""
    values = {i.name: getattr(args, i.name) for i in a.inputs}
    values = {k: v for k, v in values.items() if v is not None}
    for i in a.inputs:
        if isinstance(i, AxisChoice) and i.name not in values:
            kinds = {"linear": AxisKind.LINEAR, "rotary": AxisKind.ROTARY}
            wanted = {kinds.get(k, AxisKind.SPINDLE) for k in i.kinds}
            first = next((x.name for x in cfg.axes if x.kind in wanted), None)
            if first is None:
                raise UsageError(f"{_option(i)}: the machine has no {' or '.join(i.kinds)}")
            values[i.name] = first
    return values


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p_assist = sub.add_parser("assist", help="run a commissioning assistant headless")
    names = p_assist.add_subparsers(dest="assistant", required=True)
    for a in ASSISTANTS:
        p = names.add_parser(a.name, help=f"{a.title} ({a.section})", description=a.text)
        p.add_argument(
            "--machine", default="demo", help="demo, or a folder with channel.lis and axis_<n>.lis"
        )
        p.add_argument(
            "--set",
            action="append",
            default=[],
            metavar="TARGET.PARAM=VALUE",
            help="parameter override (repeat)",
        )
        p.add_argument("--json", action="store_true", help="print the result as JSON")
        for i in a.inputs:
            _add(p, i)


def _summary(result: Result) -> str:
    lines = [f"{result.assistant}: {'ok' if result.ok else 'NOT OK'}"]
    lines += [f"  {f.name} = {f.value:.6g} {f.unit}".rstrip() for f in result.figures]
    lines += [f"  {c.target} {c.parameter} = {c.after}" for c in result.changes]
    lines += [f"  note: {n}" for n in result.notes]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run the chosen assistant; a bad option or input is a message on stderr and exit 2."""
    a = assistant(args.assistant)
    try:
        cfg = _machine(args)
        result = run_assistant(a.name, cfg, _inputs(a, args, cfg))
    except (UsageError, NcUsageError, ParamListError, ParamError, OSError, ValueError) as e:
        print(f"inbetrieb assist {args.assistant}: {e}", file=sys.stderr)
        return 2
    print(json.dumps(result.as_json(), indent=1) if args.json else _summary(result))
    return 0
