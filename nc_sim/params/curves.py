"""A spindle's acceleration curves must accelerate [000 §2.8.4, P-AXIS-00202].

The manual gives the coefficients b1..b3 the whole REAL64 range, and n_grenz, a_konst, a_min
their own ranges; each value can be in range while the curve they make is meaningless: with
b2 = 1e308 the hyperbola gives no acceleration above n_grenz, a polynomial with a_konst = 0
none at standstill. A spindle on such a curve could never reach its speed. So a list is
checked as a whole: every curve in use (typ 1-3) must give a finite acceleration of at least
one list unit (1 °/s², `A_LEAST`) at every speed from standstill to its gear's vb_max
(P-AXIS-00212), as the kernel applies it (floored at a_min, capped by a_max P-AXIS-00008).
"""

from __future__ import annotations

from collections.abc import Mapping

from nc_sim.accel_curve import A_LEAST, CurveParams
from nc_sim.params.registry import Registry, Scope
from nc_sim.units import RPM_TO_DEG_S, to_eng

GEARS = 6
CURVE_NAMES = ("n_grenz", "a_konst", "b1", "b2", "b3", "a_min", "a_max", "n1", "n2")
KINDS = {1: "hyperbola", 2: "polynomial", 3: "asynchronous"}
Values = Mapping[str, float | int | str]  # one axis list, list units


def list_eng(values: Values, reg: Registry, name: str) -> float:
    """An axis list entry in engineering units (its default when the list leaves it out)."""
    found = reg.lookup(Scope.AXIS, name)
    assert found is not None, name
    d = found[0]
    raw = values.get(name, d.default)
    return to_eng(d.quantity, float(raw))


def curve_of(values: Values, reg: Registry, gear_index: int) -> CurveParams:
    """The curve of getriebe[gear_index] in an axis list (defaults where unset)."""
    pre = f"getriebe[{gear_index}].beschl_kennlinie."
    typ = int(list_eng(values, reg, pre + "typ"))
    n_limit, a_konst, b1, b2, b3, a_min, a_max3, n1, n2 = (
        list_eng(values, reg, pre + n) for n in CURVE_NAMES
    )
    a_cap = list_eng(values, reg, f"getriebe[{gear_index}].dynamik.a_max")
    return CurveParams(typ, n_limit, a_konst, b1, b2, b3, a_min, a_max3, n1, n2, a_cap)


def curve_problems(values: Values, reg: Registry) -> list[tuple[str, str]]:
    """(parameter name, message) for every curve in use that does not accelerate somewhere
    between standstill and vb_max; the name is the curve's `typ` entry."""
    problems: list[tuple[str, str]] = []
    for g in range(GEARS):
        name = f"getriebe[{g}].beschl_kennlinie.typ"
        if name not in values or int(float(str(values[name]))) == 0:
            continue
        curve = curve_of(values, reg, g)
        vb_max = list_eng(values, reg, f"getriebe[{g}].dynamik.vb_max")
        dead = curve.dead_speed(0.0, vb_max)
        if dead is None:
            continue
        problems.append(
            (
                name,
                f"getriebe[{g}].beschl_kennlinie: the {KINDS.get(curve.typ, 'acceleration')} "
                f"curve gives a = {curve.accel(dead):g} °/s² at {dead / RPM_TO_DEG_S:g} rpm; "
                f"it must accelerate (a ≥ {A_LEAST:g} °/s²) at every speed up to vb_max "
                f"{vb_max / RPM_TO_DEG_S:g} rpm (P-AXIS-00202)",
            )
        )
    return problems
