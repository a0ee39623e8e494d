"""Commissioning calculators [004 §3.4, §3.6.1, 000 §2.2.4]: the arithmetic of the manuals'
worked examples, answered as list fractions (numerator/denominator as the manual writes them)
with the decimal factor as a figure.

Fractions are kept in the manual's natural form (4096 increments per 50000·0.1 µm, not the
reduced 256/3125); only a pair that does not fit the list's UNS32 range is reduced, and if
that is not enough, approximated (with a note saying by how much).
"""

from __future__ import annotations

import math
from fractions import Fraction

from nc_sim.assist.result import Change, Figure, Result, Value
from nc_sim.config import MachineConfig
from nc_sim.errors import NcUsageError
from nc_sim.params.definitions import U32MAX
from nc_sim.units import (
    DEG_PER_REV,
    MULTI_GAIN_SPEED_DEG_MIN,
    MULTI_GAIN_SPEED_MM_MIN,
    POSITION_UNITS_PER_DEG,
    POSITION_UNITS_PER_MM,
    V_RESO_UNITS_PER_DEG,
    V_RESO_UNITS_PER_MM,
)

# P-AXIS-00207: 0 per minute, 1 per second, 2 per sampling interval
TIME_BASE_PER_MIN = {0: Fraction(1), 1: Fraction(1, 60)}
TIME_BASE_TEXT = {0: "per minute", 1: "per second", 2: "per cycle"}


def exact(x: float | int | str | Fraction) -> Fraction:
    """A decimal input as the exact fraction the engineer typed (0.1 -> 1/10, not binary)."""
    if isinstance(x, Fraction):
        return x
    return Fraction(str(x)) if isinstance(x, float) else Fraction(x)


def _positive(name: str, x: Fraction) -> Fraction:
    if x <= 0:
        raise NcUsageError(f"{name} must be positive (got {float(x):g})")
    return x


def list_fraction(num: Fraction, den: Fraction) -> tuple[int, int, str]:
    """Integers (z, n) with z/n = num/den in the manual's form: both scaled to whole numbers,
    reduced only if they exceed UNS32, approximated if even that is too large. The third
    item is a note when the pair is not exact."""
    ratio = num / den
    scale = math.lcm(num.denominator, den.denominator)  # whole numbers, the pair unreduced
    zi, ni = (num * scale).numerator, (den * scale).numerator
    if max(zi, ni) > U32MAX:
        zi, ni = ratio.numerator, ratio.denominator
    if max(zi, ni) <= U32MAX:
        return zi, ni, ""
    limit = max(1, min(U32MAX, int(U32MAX / ratio))) if ratio > 1 else U32MAX
    approx = ratio.limit_denominator(limit)
    err = float(abs(approx - ratio) / ratio)
    return (
        approx.numerator,
        approx.denominator,
        f"the exact ratio does not fit UNS32: {err:.1e} off",
    )


def _pair_changes(
    target: str, prefix: str, z_name: str, n_name: str, z: int, n: int, why: str
) -> tuple[Change, Change]:
    return (
        Change(target, prefix + z_name, "", z, why),
        Change(target, prefix + n_name, "", n, why),
    )


def resolution(
    increments_per_rev: int,
    *,
    pitch_mm: float | None = None,
    rotary: bool = False,
    gear_ratio: float = 1.0,
    target: str = "X",
    gear: int = 1,
) -> Result:
    """wegaufz/wegaufn [004 §3.4]: encoder increments per motor revolution over the distance
    one motor revolution moves the axis (pitch / i in 0.1 µm, or 360° / i in 0.0001°).
    `gear_ratio` i = motor revolutions per revolution of the spindle or screw.
    Checks: 4096 per 5 mm -> 4096/50000; i = 10 -> 4096/5000; 65536 rotary -> 65536/3600000."""
    incr = _positive("increments per revolution", exact(increments_per_rev))
    i = _positive("gear ratio", exact(gear_ratio))
    if rotary == (pitch_mm is not None):
        raise NcUsageError("give either a spindle pitch (mm per revolution) or rotary, not both")
    if pitch_mm is not None:
        per_rev = _positive("pitch", exact(pitch_mm)) * POSITION_UNITS_PER_MM
        unit, per = "incr/0.1 µm", f"{float(exact(pitch_mm)):g} mm"
    else:
        per_rev = Fraction(DEG_PER_REV * POSITION_UNITS_PER_DEG)
        unit, per = "incr/0.0001°", "360°"
    z, n, note = list_fraction(incr, per_rev / i)
    why = f"{incr} increments per motor revolution, {per} per output revolution, i = {i}"
    prefix = f"getriebe[{gear - 1}]."
    return Result(
        "resolution",
        figures=(
            Figure("resolution", z / n, unit, "wegaufz / wegaufn"),
            Figure("distance_per_motor_rev", float(per_rev / i), unit.split("/")[1], ""),
        ),
        changes=_pair_changes(target, prefix, "wegaufz", "wegaufn", z, n, why),
        notes=(note,) if note else (),
        inputs=_inputs(
            increments_per_rev=increments_per_rev,
            pitch_mm=pitch_mm,
            rotary=int(rotary),
            gear_ratio=gear_ratio,
            target=target,
            gear=gear,
        ),
    )


def multi_gain(
    *,
    digits_per_rpm: float | Fraction | None = None,
    full_scale_digits: int | None = None,
    full_scale_rpm: float | None = None,
    speed_weighting_rpm: float | None = None,
    speed_weighting_m_per_min: float | None = None,
    pitch_mm: float | None = None,
    gear_ratio: float = 1.0,
    target: str = "X",
    gear: int = 1,
) -> Result:
    """multi_gain_z/multi_gain_n by calculation [004 §3.6.1]: the command value for 1 m/min
    (translatory, `pitch_mm` per output revolution) or 1000 °/min (rotary, no pitch).

    The manual's procedure: (1) the factor f between motor rpm and the command value, from
    exactly one of: `digits_per_rpm` (Lightbus: 1048576·32/(4000·60)), the D/A full scale
    (`full_scale_digits` at `full_scale_rpm`, terminal: 32767 at 9000 rpm), a SERCOS rotary
    speed weighting (`speed_weighting_rpm`, 1e-4 rpm per digit) or a SERCOS translatory one
    (`speed_weighting_m_per_min`, 1e-4 m/min per digit, the axis's own speed); (2) the motor
    speed n for 1 m/min or 1000 °/min with the gear i; (3) multi_gain = f·n.
    Checks: terminal 10.1134, with i = 5 50.5668, SERCOS rotary 10000000/360, translatory
    10000/1, Lightbus (5 mm) 27962.02."""
    sources = [
        digits_per_rpm is not None,
        full_scale_digits is not None or full_scale_rpm is not None,
        speed_weighting_rpm is not None,
        speed_weighting_m_per_min is not None,
    ]
    if sum(sources) != 1:
        raise NcUsageError(
            "give exactly one drive scaling: digits per rpm, the D/A full scale "
            "(digits and rpm), or a SERCOS speed weighting (rpm or m/min)"
        )
    i = _positive("gear ratio", exact(gear_ratio))
    rotary = pitch_mm is None
    if rotary:
        speed, per_rev = Fraction(MULTI_GAIN_SPEED_DEG_MIN), Fraction(DEG_PER_REV)
        speed_text = "1000 °/min"
    else:
        speed, per_rev = Fraction(MULTI_GAIN_SPEED_MM_MIN), _positive("pitch", exact(pitch_mm or 0))
        speed_text = "1 m/min"
    motor_rpm = speed * i / per_rev  # step 2
    if speed_weighting_m_per_min is not None:
        if rotary:
            raise NcUsageError("a translatory speed weighting needs the pitch (mm per revolution)")
        weight = _positive("speed weighting", exact(speed_weighting_m_per_min))
        f = Fraction(MULTI_GAIN_SPEED_MM_MIN, 1000) / weight / motor_rpm  # 1 m/min in weights
        source = f"SERCOS translatory weighting {float(weight):g} m/min"
    elif speed_weighting_rpm is not None:
        f = 1 / _positive("speed weighting", exact(speed_weighting_rpm))
        source = f"SERCOS rotary weighting {float(exact(speed_weighting_rpm)):g} rpm"
    elif digits_per_rpm is not None:
        f = _positive("digits per rpm", exact(digits_per_rpm))
        source = f"{float(f):.4f} digits per rpm"
    else:
        if full_scale_digits is None or full_scale_rpm is None:
            raise NcUsageError("the D/A full scale needs both digits and rpm")
        f = _positive("full-scale digits", exact(full_scale_digits)) / _positive(
            "full-scale speed", exact(full_scale_rpm)
        )
        source = f"{full_scale_digits} digits at {float(exact(full_scale_rpm)):g} rpm"
    if speed_weighting_m_per_min is not None:
        num, den = Fraction(MULTI_GAIN_SPEED_MM_MIN, 1000), exact(speed_weighting_m_per_min)
    else:
        num, den = f * speed * i, per_rev  # step 3, over the distance per revolution as
        # the manual writes it (10000000/360, not 250000/9)
    z, n, note = list_fraction(num, den)
    why = f"{source}; {float(motor_rpm):.4f} motor rpm for {speed_text} (i = {i})"
    prefix = f"getriebe[{gear - 1}]."
    return Result(
        "multi-gain-calc",
        figures=(
            Figure("f", float(f), "digits/rpm", "command value per motor rpm"),
            Figure("n_motor_rpm", float(motor_rpm), "rpm", f"motor speed for {speed_text}"),
            Figure("multi_gain", z / n, "", f"command value for {speed_text}"),
        ),
        changes=_pair_changes(target, prefix, "multi_gain_z", "multi_gain_n", z, n, why),
        notes=(note,) if note else (),
        inputs=_inputs(
            digits_per_rpm=None if digits_per_rpm is None else float(exact(digits_per_rpm)),
            full_scale_digits=full_scale_digits,
            full_scale_rpm=full_scale_rpm,
            speed_weighting_rpm=speed_weighting_rpm,
            speed_weighting_m_per_min=speed_weighting_m_per_min,
            pitch_mm=pitch_mm,
            gear_ratio=gear_ratio,
            target=target,
            gear=gear,
        ),
    )


def speed_scaling(
    increments: int,
    speed_rpm: float,
    *,
    time_base: int = 0,
    cycle_ms: float | None = None,
    gear_ratio: float = 1.0,
    linear_mm_per_rev: float | None = None,
    target: str = "S1",
) -> Result:
    """v_reso_num/v_reso_denom of a speed-controlled spindle [000 §2.2.4]: the output
    `increments` turns the motor at `speed_rpm`; the denominator is the distance the axis
    covers meanwhile in the time base (P-AXIS-00207: 0 minute, 1 second, 2 cycle) in 0.001°
    (or 1 µm with `linear_mm_per_rev`). Checks: 32767 for 3000 rpm -> 32767/1080000000 per
    minute; 1 for 1 rpm -> 1/360000."""
    incr = _positive("increments", exact(increments))
    rpm = _positive("speed", exact(speed_rpm))
    i = _positive("gear ratio", exact(gear_ratio))
    if time_base == 2:
        if cycle_ms is None:
            raise NcUsageError("time base 2 (per cycle) needs the cycle time in ms")
        per_min = _positive("cycle time", exact(cycle_ms)) / 60000
    elif time_base in TIME_BASE_PER_MIN:
        per_min = TIME_BASE_PER_MIN[time_base]
    else:
        raise NcUsageError(
            f"time base must be 0 (minute), 1 (second) or 2 (cycle), not {time_base}"
        )
    if linear_mm_per_rev is None:
        per_rev = Fraction(DEG_PER_REV * V_RESO_UNITS_PER_DEG)
        unit = "0.001°"
    else:
        per_rev = _positive("distance per revolution", exact(linear_mm_per_rev))
        per_rev *= V_RESO_UNITS_PER_MM
        unit = "µm"
    distance = rpm / i * per_rev * per_min
    z, n, note = list_fraction(incr, distance)
    why = (
        f"{incr} increments turn the motor at {float(rpm):g} rpm (i = {i}): "
        f"{float(distance):g} {unit} {TIME_BASE_TEXT[time_base]}"
    )
    return Result(
        "speed-scaling",
        figures=(
            Figure("v_reso", z / n, f"incr/{unit}", "v_reso_num / v_reso_denom"),
            Figure("distance_per_time_base", float(distance), unit, TIME_BASE_TEXT[time_base]),
        ),
        changes=(
            *_pair_changes(target, "antr.", "v_reso_num", "v_reso_denom", z, n, why),
            Change(target, "antr.v_time_base", "", time_base, TIME_BASE_TEXT[time_base]),
        ),
        notes=(note,) if note else (),
        inputs=_inputs(
            increments=increments,
            speed_rpm=speed_rpm,
            time_base=time_base,
            cycle_ms=cycle_ms,
            gear_ratio=gear_ratio,
            linear_mm_per_rev=linear_mm_per_rev,
            target=target,
        ),
    )


def _inputs(**values: Value | None) -> dict[str, Value]:
    return {k: v for k, v in values.items() if v is not None}


# --- as the assistants' registry runs them (nc_sim/assist/registry.py): the machine's
# configuration, then the inputs by their API names


def resolution_of(
    cfg: MachineConfig,
    axis: str,
    gear: int,
    increments_per_rev: int,
    pitch_mm: float | None,
    rotary: bool,
    gear_ratio: float,
) -> Result:
    """`resolution` for `axis` of the machine."""
    return resolution(
        increments_per_rev,
        pitch_mm=pitch_mm,
        rotary=rotary,
        gear_ratio=gear_ratio,
        target=cfg.axis(axis).name,
        gear=gear,
    )


def multi_gain_of(
    cfg: MachineConfig,
    axis: str,
    gear: int,
    digits_per_rpm: float | None,
    full_scale_digits: int | None,
    full_scale_rpm: float | None,
    speed_weighting_rpm: float | None,
    speed_weighting_m_per_min: float | None,
    pitch_mm: float | None,
    gear_ratio: float,
) -> Result:
    """`multi_gain` for `axis` of the machine."""
    return multi_gain(
        digits_per_rpm=digits_per_rpm,
        full_scale_digits=full_scale_digits,
        full_scale_rpm=full_scale_rpm,
        speed_weighting_rpm=speed_weighting_rpm,
        speed_weighting_m_per_min=speed_weighting_m_per_min,
        pitch_mm=pitch_mm,
        gear_ratio=gear_ratio,
        target=cfg.axis(axis).name,
        gear=gear,
    )


def speed_scaling_of(
    cfg: MachineConfig,
    axis: str,
    increments: int,
    speed_rpm: float,
    time_base: int,
    cycle_ms: float | None,
    gear_ratio: float,
) -> Result:
    """`speed_scaling` for the spindle `axis`; time base 2 without `cycle_ms` takes the
    machine's own cycle (P-CHAN cycle_time)."""
    if not cfg.axis(axis).is_spindle:
        raise NcUsageError(f"axis: {axis} is not a spindle (v_reso scales a spindle's speed)")
    if time_base == 2 and cycle_ms is None:
        cycle_ms = cfg.cycle_s * 1000.0
    return speed_scaling(
        increments,
        speed_rpm,
        time_base=time_base,
        cycle_ms=cycle_ms,
        gear_ratio=gear_ratio,
        target=axis,
    )


__all__ = [
    "exact",
    "list_fraction",
    "multi_gain",
    "multi_gain_of",
    "resolution",
    "resolution_of",
    "speed_scaling",
    "speed_scaling_of",
]
