"""Checks of an axis list as a whole, beyond each value's range: relations between entries
that the manuals state (the modulo range is one revolution here; the G201 shares of manual and
path mode together are at most the axis' limits)."""

from __future__ import annotations

from nc_sim.params.curves import GEARS, Values, list_eng
from nc_sim.params.registry import Registry


def modulo_problems(values: Values, reg: Registry) -> list[tuple[str, str]]:
    """(parameter name, message) for a gear record whose modulo range
    (modulou P-AXIS-00127 … moduloo P-AXIS-00126) is not one revolution: the simulated rotary
    axes and spindles turn 360° per modulo cycle (their encoder's zero mark comes once in it)."""
    problems: list[tuple[str, str]] = []
    for g in range(GEARS):
        hi_name, lo_name = f"getriebe[{g}].moduloo", f"getriebe[{g}].modulou"
        if hi_name not in values and lo_name not in values:
            continue
        lo, hi = list_eng(values, reg, lo_name), list_eng(values, reg, hi_name)
        if abs(hi - lo - 360.0) > 1e-9:
            problems.append(
                (
                    hi_name,
                    f"{hi_name} {hi:g}° − {lo_name} {lo:g}° = {hi - lo:g}°: the modulo range "
                    "(P-AXIS-00127 … P-AXIS-00126) must span one revolution, 360°",
                )
            )
    return problems


_SHARES = (
    ("handbetrieb.ipo.hb_proz_a_max", "handbetrieb.ipo.ipo_proz_a_max", "P-AXIS-00008"),
    ("handbetrieb.ipo.hb_proz_v_max", "handbetrieb.ipo.ipo_proz_v_max", "P-AXIS-00212"),
)


def share_problems(values: Values, reg: Registry) -> list[tuple[str, str]]:
    """(parameter name, message) when G201's manual and path shares of an axis limit add up to
    more than 100 %: together they would exceed the limit they split [002 §2.6.2]."""
    problems: list[tuple[str, str]] = []
    for manual, path, limit in _SHARES:
        if manual not in values and path not in values:
            continue
        total = list_eng(values, reg, manual) + list_eng(values, reg, path)
        if total > 1.0 + 1e-9:
            problems.append(
                (
                    manual,
                    f"{manual} + {path} = {total * 100:g} %: G201 splits {limit} between manual "
                    "and path mode, together at most 100 %",
                )
            )
    return problems
