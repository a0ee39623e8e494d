"""`inbetrieb assist NAME [--machine demo|DIR] [--set TARGET.PARAM=VALUE ...] [options] [--json]`:
the commissioning assistants (nc_sim/assist) headless, in simulated time.

`ASSISTANTS` maps each name to (argument setup, run): a new assistant registers itself there
and gets the shared options (--machine, --set, --json) for free.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

from nc_sim.assist.calculators import multi_gain, resolution, speed_scaling
from nc_sim.assist.curve_fit import curve_fit
from nc_sim.assist.experiments import multi_gain_experiment, sign_check_experiment
from nc_sim.assist.loop_gain import loop_gain
from nc_sim.assist.result import Result
from nc_sim.assist.run_up import curve_run_up
from nc_sim.config import MachineConfig
from nc_sim.errors import NcUsageError
from nc_sim.params import ParamListError
from nc_sim.params.listfile import ParamError

Setup = Callable[[argparse.ArgumentParser], None]
Run = Callable[[argparse.Namespace, Callable[[], MachineConfig]], Result]


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


def _fraction(text: str) -> Fraction:
    """A number or a quotient of numbers: 139.81, 1048576*32/(4000*60) is not allowed, but
    33554432/240 is."""
    try:
        return Fraction(text)
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"not a number or fraction: {text!r}") from None


def _points(text: str) -> list[tuple[float, float]]:
    try:
        pairs = [p.split(":") for p in text.split(",") if p.strip()]
        return [(float(n), float(a)) for n, a in pairs]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"points must be n:a pairs (°/s:°/s²) separated by commas, not {text!r}"
        ) from None


def _setup_resolution(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--increments", type=int, required=True, help="encoder increments per motor revolution"
    )
    way = p.add_mutually_exclusive_group(required=True)
    way.add_argument("--pitch", type=float, help="spindle pitch, mm per revolution (linear axis)")
    way.add_argument(
        "--rotary", action="store_true", help="rotary axis or spindle: 360° per revolution"
    )
    p.add_argument(
        "--gear-ratio", type=float, default=1.0, help="i: motor revolutions per output revolution"
    )
    p.add_argument("--axis", default="X")
    p.add_argument("--gear", type=int, default=1)


def _run_resolution(args: argparse.Namespace, _machine: Callable[[], MachineConfig]) -> Result:
    return resolution(
        args.increments,
        pitch_mm=args.pitch,
        rotary=args.rotary,
        gear_ratio=args.gear_ratio,
        target=args.axis,
        gear=args.gear,
    )


def _setup_multi_gain_calc(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--digits-per-rpm", type=_fraction, help="f: command value per motor rpm (a/b allowed)"
    )
    p.add_argument("--full-scale-digits", type=int, help="D/A value at full scale (32767 at 10 V)")
    p.add_argument("--full-scale-rpm", type=float, help="motor speed at full scale")
    p.add_argument(
        "--weighting-rpm", type=float, help="SERCOS rotary speed weighting, rpm per digit"
    )
    p.add_argument(
        "--weighting-m-per-min", type=float, help="SERCOS translatory weighting, m/min per digit"
    )
    p.add_argument(
        "--pitch", type=float, help="mm per output revolution (linear axis; none: rotary)"
    )
    p.add_argument(
        "--gear-ratio", type=float, default=1.0, help="i: motor revolutions per output revolution"
    )
    p.add_argument("--axis", default="X")
    p.add_argument("--gear", type=int, default=1)


def _run_multi_gain_calc(args: argparse.Namespace, _machine: Callable[[], MachineConfig]) -> Result:
    return multi_gain(
        digits_per_rpm=args.digits_per_rpm,
        full_scale_digits=args.full_scale_digits,
        full_scale_rpm=args.full_scale_rpm,
        speed_weighting_rpm=args.weighting_rpm,
        speed_weighting_m_per_min=args.weighting_m_per_min,
        pitch_mm=args.pitch,
        gear_ratio=args.gear_ratio,
        target=args.axis,
        gear=args.gear,
    )


def _setup_speed_scaling(p: argparse.ArgumentParser) -> None:
    p.add_argument("--increments", type=int, required=True, help="value output to the drive")
    p.add_argument("--rpm", type=float, required=True, help="motor speed at that value")
    p.add_argument(
        "--time-base", type=int, default=0, choices=(0, 1, 2), help="0 minute, 1 second, 2 cycle"
    )
    p.add_argument("--cycle-ms", type=float, help="cycle time for time base 2")
    p.add_argument(
        "--gear-ratio", type=float, default=1.0, help="i: motor revolutions per spindle revolution"
    )
    p.add_argument("--spindle", default="S1")


def _run_speed_scaling(args: argparse.Namespace, _machine: Callable[[], MachineConfig]) -> Result:
    return speed_scaling(
        args.increments,
        args.rpm,
        time_base=args.time_base,
        cycle_ms=args.cycle_ms,
        gear_ratio=args.gear_ratio,
        target=args.spindle,
    )


def _setup_curve_fit(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--type",
        type=int,
        required=True,
        choices=(1, 2, 3),
        help="1 hyperbola, 2 polynomial, 3 asynchronous",
    )
    p.add_argument("--points", type=_points, required=True, help="n:a,n:a,... in °/s and °/s²")
    p.add_argument(
        "--n-limit", type=float, help="limit speed °/s (default: the first point, or searched)"
    )
    p.add_argument("--a-min", type=float, default=0.0, help="the curve's floor, °/s²")
    p.add_argument("--spindle", default="S1")
    p.add_argument("--gear", type=int, default=1)


def _run_curve_fit(args: argparse.Namespace, _machine: Callable[[], MachineConfig]) -> Result:
    return curve_fit(
        args.type,
        args.points,
        n_limit_deg_s=args.n_limit,
        a_min=args.a_min,
        target=args.spindle,
        gear=args.gear,
    )


def _setup_curve_run_up(p: argparse.ArgumentParser) -> None:
    p.add_argument("--spindle", default="S1")
    p.add_argument("--gear", type=int, required=True, help="gear stage 1-6")
    p.add_argument("--type", type=int, default=2, choices=(1, 2, 3), help="curve type to fit")
    p.add_argument("--rpm", type=float, help="top speed of the run-up (default the gear's vb_max)")
    p.add_argument("--n-limit", type=float, help="limit speed °/s (default: searched)")


def _run_curve_run_up(args: argparse.Namespace, machine: Callable[[], MachineConfig]) -> Result:
    return curve_run_up(
        machine(),
        args.spindle,
        args.gear,
        args.type,
        speed_rpm=args.rpm,
        n_limit_deg_s=args.n_limit,
    )


def _setup_multi_gain(p: argparse.ArgumentParser) -> None:
    p.add_argument("--axis", required=True, help="axis or spindle name (X, S1)")
    speed = p.add_mutually_exclusive_group(required=True)
    speed.add_argument("--feed", type=float, help="axis feed, mm/min (°/min for a rotary axis)")
    speed.add_argument("--speed", type=float, help="spindle speed, rpm (position-controlled)")
    p.add_argument("--window", type=float, default=1.0, help="averaged over, s (default 1)")


def _run_multi_gain(args: argparse.Namespace, machine: Callable[[], MachineConfig]) -> Result:
    return multi_gain_experiment(
        machine(), args.axis, feed_mm_min=args.feed, speed_rpm=args.speed, window_s=args.window
    )


def _setup_sign_check(p: argparse.ArgumentParser) -> None:
    p.add_argument("--axis", required=True, help="axis name (X)")
    p.add_argument("--distance", type=float, default=1.0, help="mm or ° (default 1)")
    p.add_argument("--feed", type=float, default=100.0, help="mm/min (default 100)")
    p.add_argument(
        "--observed",
        type=int,
        choices=(1, -1),
        help="the way the machine moved as you saw it: 1 as commanded, -1 the other way "
        "(default: the simulated plant's)",
    )


def _run_sign_check(args: argparse.Namespace, machine: Callable[[], MachineConfig]) -> Result:
    return sign_check_experiment(machine(), args.axis, args.distance, args.feed, args.observed)


def _kvs(text: str) -> list[float]:
    try:
        return [float(k) for k in text.split(",") if k.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"kv values must be numbers (1/s) separated by commas, not {text!r}"
        ) from None


def _setup_loop_gain(p: argparse.ArgumentParser) -> None:
    p.add_argument("--axis", required=True, help="axis name (X)")
    p.add_argument(
        "--kv", type=_kvs, help="kv values to try, 1/s: 10,20,40 (default 0.5x to 3x the axis' kv)"
    )
    p.add_argument(
        "--overshoot-pct", type=float, default=5.0, help="target: step overshoot, %% (default 5)"
    )
    p.add_argument(
        "--settle-ms", type=float, default=200.0, help="target: step settling, ms (default 200)"
    )
    p.add_argument("--step", type=float, help="G00 step, mm or ° (default 20 exact-stop windows)")
    p.add_argument("--feed", type=float, help="G01 ramp feed, mm/min (default 5 %% of rapid)")
    p.add_argument("--direction", type=int, default=1, choices=(1, -1))


def _run_loop_gain(args: argparse.Namespace, machine: Callable[[], MachineConfig]) -> Result:
    return loop_gain(
        machine(),
        args.axis,
        args.kv,
        args.overshoot_pct,
        args.settle_ms,
        step=args.step,
        feed_mm_min=args.feed,
        direction=args.direction,
    )


ASSISTANTS: dict[str, tuple[Setup, Run]] = {
    "multi-gain": (_setup_multi_gain, _run_multi_gain),
    "sign-check": (_setup_sign_check, _run_sign_check),
    "loop-gain": (_setup_loop_gain, _run_loop_gain),
    "resolution": (_setup_resolution, _run_resolution),
    "multi-gain-calc": (_setup_multi_gain_calc, _run_multi_gain_calc),
    "speed-scaling": (_setup_speed_scaling, _run_speed_scaling),
    "curve-fit": (_setup_curve_fit, _run_curve_fit),
    "curve-run-up": (_setup_curve_run_up, _run_curve_run_up),
}


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p_assist = sub.add_parser("assist", help="run a commissioning assistant headless")
    names = p_assist.add_subparsers(dest="assistant", required=True)
    for name, (setup, _run) in ASSISTANTS.items():
        p = names.add_parser(name)
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
        setup(p)


def _summary(result: Result) -> str:
    lines = [f"{result.assistant}: {'ok' if result.ok else 'NOT OK'}"]
    lines += [f"  {f.name} = {f.value:.6g} {f.unit}".rstrip() for f in result.figures]
    lines += [f"  {c.target} {c.parameter} = {c.after}" for c in result.changes]
    lines += [f"  note: {n}" for n in result.notes]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run the chosen assistant; a bad option or input is a message on stderr and exit 2."""
    _setup, assistant = ASSISTANTS[args.assistant]
    try:
        result = assistant(args, lambda: _machine(args))
    except (UsageError, NcUsageError, ParamListError, ParamError, OSError, ValueError) as e:
        print(f"inbetrieb assist {args.assistant}: {e}", file=sys.stderr)
        return 2
    print(json.dumps(result.as_json(), indent=1) if args.json else _summary(result))
    return 0
