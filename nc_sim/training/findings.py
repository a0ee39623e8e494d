"""A student's finding graded: which axis carries the hidden fault, and how large it is.

The truth is what the seat's machine has: the exercise's faults of the finding's kind, each
on its axis, plus what the axis' own list already gives of the same (the demo Z's 3 µm of
backlash, `sim.mech.backlash`): the student measures the sum. Sizes are in the axis' unit
(mm | °); a linear axis' are said in µm.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from nc_sim.config import MachineConfig
from nc_sim.faults import Backlash, Fault
from nc_sim.training.checks import FindingCheck
from nc_sim.units import Quantity, eng_unit

# fault kind -> (its class, the list parameter that gives the same on a sound machine)
FINDABLE: dict[str, tuple[type[Backlash], str]] = {"backlash": (Backlash, "sim.mech.backlash")}


@dataclass(frozen=True)
class Graded:
    passed: bool
    detail: str


def truth(rule: FindingCheck, faults: Iterable[Fault], cfg: MachineConfig) -> dict[str, float]:
    """Axis -> the size of what is to be found on it (only axes that carry such a fault)."""
    cls, param = FINDABLE[rule.fault]
    out: dict[str, float] = {}
    for f in faults:
        if isinstance(f, cls):
            out[f.axis] = out.get(f.axis, 0.0) + f.width
    for axis in out:
        out[axis] += cfg.axis(axis).eng(param)
    return out


def say(size: float, unit: str) -> str:
    """A size as an engineer says it: µm on a linear axis."""
    return f"{size * 1000.0:.1f} µm" if unit == "mm" else f"{size:.4f} {unit}"


def unit_of(cfg: MachineConfig, axis: str) -> str:
    """The unit of the axis' sizes: mm or °. Raises NcUsageError for an axis it lacks."""
    return eng_unit(Quantity.POSITION, cfg.axis(axis).kind)


def grade(
    rule: FindingCheck, faults: Iterable[Fault], cfg: MachineConfig, axis: str, value: float
) -> Graded:
    """One answer: `axis` carries the fault and `value` (its unit) is within the rule's share
    of its size. A wrong answer does not give the size away. Raises NcUsageError for an axis
    the machine lacks."""
    unit = unit_of(cfg, axis)
    said = say(value, unit)
    size = truth(rule, faults, cfg).get(axis)
    if size is None:
        return Graded(False, f"the {rule.fault} to find is not on {axis}")
    off_pct = (value / size - 1.0) * 100.0
    if abs(off_pct) <= rule.within_pct:
        return Graded(
            True,
            f"{axis} has {say(size, unit)} of {rule.fault}: your {said} is {off_pct:+.0f} %"
            f" off (within {rule.within_pct:g} %)",
        )
    return Graded(
        False,
        f"{axis} is right, {said} is not: more than {rule.within_pct:g} % off what {axis} has",
    )
