"""Raw (parameter-list) units <-> engineering units, in one place.

The controller's lists use internal units [004 §3.2]: position 0.1 µm or 0.0001°, velocity
µm/s or 0.001°/s, acceleration mm/s² or °/s², time µs, kv 0.01/s, weights 0.1 %.
The kernel computes in float64 mm, °, s. Each parameter names a `Quantity`; the axis kind
(linear or rotary/spindle) picks the unit text.
"""

from __future__ import annotations

import math
from enum import StrEnum

RPM_TO_DEG_S = 6.0  # 1 rpm = 360°/60 s
RAD_PER_REV = 2.0 * math.pi
RPM_TO_RAD_S = RAD_PER_REV / 60.0  # a motor's rpm in rad/s
MM_MIN_PER_MM_S = 60.0
MS_PER_S = 1000.0


def per_second(v_per_min: float) -> float:
    """A feed or speed per minute (mm/min, °/min) as per second."""
    return v_per_min / MM_MIN_PER_MM_S


def per_minute(v_per_s: float) -> float:
    """A speed per second (mm/s, °/s) as per minute (the unit of F)."""
    return v_per_s * MM_MIN_PER_MM_S


class AxisKind(StrEnum):
    """What the manuals call axis type T (translatory), R (rotary) and S (spindle)."""

    LINEAR = "T"
    ROTARY = "R"
    SPINDLE = "S"


class Quantity(StrEnum):
    """The physical meaning of a raw parameter value."""

    NONE = "none"
    POSITION = "position"  # 0.1 µm | 0.0001°
    VELOCITY = "velocity"  # µm/s | 0.001°/s
    ACCELERATION = "acceleration"  # mm/s² | °/s²
    TIME = "time"  # µs
    KV = "kv"  # 0.01/s
    PERMILLE = "permille"  # 0.1 %
    PERCENT = "percent"  # %
    RPM = "rpm"  # channel gear table, rpm
    INCREMENTS = "increments"
    CURVE_B1 = "curve_b1"  # curve coefficients, stored as given
    CURVE_B2 = "curve_b2"
    CURVE_B3 = "curve_b3"
    DA_DIGITS = "da_digits"
    # the drive and the mechanics (nc_sim/plant), referred to the motor shaft, in SI units
    TORQUE = "torque"  # Nm
    INERTIA = "inertia"  # kg·m²
    SPEED_GAIN = "speed_gain"  # Nm·s/rad: speed-loop gain, viscous friction
    FREQUENCY = "frequency"  # Hz


# factor raw -> kernel engineering unit (mm, °, s based)
_TO_ENG: dict[Quantity, float] = {
    Quantity.NONE: 1.0,
    Quantity.POSITION: 1e-4,
    Quantity.VELOCITY: 1e-3,
    Quantity.ACCELERATION: 1.0,
    Quantity.TIME: 1e-6,
    Quantity.KV: 1e-2,
    Quantity.PERMILLE: 1e-3,
    Quantity.PERCENT: 1e-2,
    Quantity.RPM: 1.0,
    Quantity.INCREMENTS: 1.0,
    Quantity.CURVE_B1: 1.0,
    Quantity.CURVE_B2: 1.0,
    Quantity.CURVE_B3: 1.0,
    Quantity.DA_DIGITS: 1.0,
    Quantity.TORQUE: 1.0,
    Quantity.INERTIA: 1.0,
    Quantity.SPEED_GAIN: 1.0,
    Quantity.FREQUENCY: 1.0,
}


def raw_unit(q: Quantity, kind: AxisKind) -> str:
    """Unit text of the raw value as the parameter list holds it."""
    linear = kind is AxisKind.LINEAR
    return {
        Quantity.NONE: "",
        Quantity.POSITION: "0.1 µm" if linear else "0.0001°",
        Quantity.VELOCITY: "µm/s" if linear else "0.001°/s",
        Quantity.ACCELERATION: "mm/s²" if linear else "°/s²",
        Quantity.TIME: "µs",
        Quantity.KV: "0.01/s",
        Quantity.PERMILLE: "0.1 %",
        Quantity.PERCENT: "%",
        Quantity.RPM: "rpm",
        Quantity.INCREMENTS: "incr.",
        Quantity.CURVE_B1: "1/s",
        Quantity.CURVE_B2: "1/°",
        Quantity.CURVE_B3: "s/°²",
        Quantity.DA_DIGITS: "digits",
        Quantity.TORQUE: "Nm",
        Quantity.INERTIA: "kg·m²",
        Quantity.SPEED_GAIN: "Nm·s/rad",
        Quantity.FREQUENCY: "Hz",
    }[q]


def eng_unit(q: Quantity, kind: AxisKind) -> str:
    """Unit text of the kernel's engineering value."""
    linear = kind is AxisKind.LINEAR
    return {
        Quantity.POSITION: "mm" if linear else "°",
        Quantity.VELOCITY: "mm/s" if linear else "°/s",
        Quantity.ACCELERATION: "mm/s²" if linear else "°/s²",
        Quantity.TIME: "s",
        Quantity.KV: "1/s",
        Quantity.PERMILLE: "",  # a plain fraction (1 = 100 %): no unit to show
        Quantity.PERCENT: "",
    }.get(q, raw_unit(q, kind))


def to_eng(q: Quantity, raw: float) -> float:
    """Convert a raw list value to the kernel's engineering unit."""
    return raw * _TO_ENG[q]


def to_raw(q: Quantity, eng: float) -> float:
    """Convert an engineering value back to the raw list unit."""
    return eng / _TO_ENG[q]


V_TIME_BASE_S = {0: 60.0, 1: 1.0}  # P-AXIS-00207: 0 per minute, 1 per second, 2 per cycle


def v_reso_digits_per_unit_s(num: float, denom: float, time_base: int, cycle_s: float) -> float:
    """Drive output per speed (mm/s | °/s) of a speed-controlled spindle [000 §2.2.4]:
    v_reso_num (P-AXIS-00206) is output for v_reso_denom (P-AXIS-00205, µm | 0.001°) covered
    in the time base (P-AXIS-00207). Check: 32767 for 3000 rpm = 1080000000 0.001°/min."""
    per = cycle_s if time_base == 2 else V_TIME_BASE_S[time_base]
    return num / denom * 1000.0 * per


def feed_per_min(v_eng: float, kind: AxisKind) -> tuple[float, str]:
    """A feed as programmed (F, jog feed): mm/min for linear axes, °/min for rotary axes and
    spindles moved as axes."""
    return v_eng * MM_MIN_PER_MM_S, "mm/min" if kind is AxisKind.LINEAR else "°/min"


def display_velocity(v_eng: float, kind: AxisKind) -> tuple[float, str]:
    """Velocity as an engineer reads it: mm/min for linear axes, rpm for spindles, °/min else."""
    if kind is AxisKind.SPINDLE:
        return v_eng / RPM_TO_DEG_S, "rpm"
    return v_eng * MM_MIN_PER_MM_S, "mm/min" if kind is AxisKind.LINEAR else "°/min"


def display_unit(q: Quantity, kind: AxisKind) -> tuple[float, str]:
    """The HMI's one convention for a parameter's value, as (factor from the raw list value,
    unit): velocities as the NC's F word reads them (mm/min, °/min; rpm for a spindle),
    weights in %, kv in 1/s, times in s; the rest in the kernel's engineering unit."""
    if q is Quantity.VELOCITY:
        per_min = _TO_ENG[q] * MM_MIN_PER_MM_S
        if kind is AxisKind.SPINDLE:
            return _TO_ENG[q] / RPM_TO_DEG_S, "rpm"
        return per_min, "mm/min" if kind is AxisKind.LINEAR else "°/min"
    if q is Quantity.PERMILLE:
        return 0.1, "%"
    if q is Quantity.PERCENT:
        return 1.0, "%"
    return _TO_ENG[q], eng_unit(q, kind)


# exact integer scales the commissioning calculators build list fractions from [004 §3.4-3.6]
POSITION_UNITS_PER_MM = 10000  # wegaufn: 0.1 µm
POSITION_UNITS_PER_DEG = 10000  # wegaufn: 0.0001°
DEG_PER_REV = 360
V_RESO_UNITS_PER_MM = 1000  # v_reso_denom: 1 µm [P-AXIS-00205]
V_RESO_UNITS_PER_DEG = 1000  # v_reso_denom: 0.001°
MULTI_GAIN_SPEED_MM_MIN = 1000  # multi_gain: the output for 1 m/min ...
MULTI_GAIN_SPEED_DEG_MIN = 1000  # ... or 1000 °/min
