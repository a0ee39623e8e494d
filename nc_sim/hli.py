"""The HLI objects an operator or the PLC writes: the control units of the channel and of
each axis [000 §2.9, 004 §4], their names, initial values and the range of a write.

What a write sets off (replanning, enables, a spindle reset) is the machine's; here is only
which units exist and which values they take.
"""

from __future__ import annotations

from nc_sim.errors import NcUsageError

CHANNEL_UNITS = ("override", "feedhold", "reduced_acceleration")
AXIS_UNITS = (
    "override",
    "override_valid",
    "DriveOn",
    "TorquePermission",
    "ReleaseFeedhold",
    "reduced_speed",
    "reduced_speed_zone",  # in safety zone 1 (P-AXIS-00093 … 00085) [002 §2.8]
    "reduced_speed_2_zone",  # in safety zone 2 (P-AXIS-00105 … 00097)
    "spindle_stop_at_program_end",
    "spindle_reset",
)
REDUCED_SPEED_UNITS = ("reduced_speed", "reduced_speed_zone", "reduced_speed_2_zone")
OVERRIDE_MAX = 2000  # override in 0.1 %: 0 … 200 %


def channel_units() -> dict[str, int]:
    """The channel's control units at start: 100 % override, no feedhold, full acceleration."""
    return {"override": 1000, "feedhold": 0, "reduced_acceleration": 0}


def axis_units() -> dict[str, int]:
    """An axis' control units at start: 100 % override, every enable off until the PLC's
    start-up sets them (`spindle_reset` is a command, not a state: it is not kept)."""
    return {
        "override": 1000,
        "override_valid": 1,
        "DriveOn": 0,
        "TorquePermission": 0,
        "ReleaseFeedhold": 0,
        "reduced_speed": 0,
        "reduced_speed_zone": 0,
        "reduced_speed_2_zone": 0,
        "spindle_stop_at_program_end": 0,
    }


def channel_write(unit: str, value: int) -> int:
    """The value a write of a channel control unit sets (override clamped to 0 … 200 %);
    an unknown unit is misuse."""
    if unit not in CHANNEL_UNITS:
        raise NcUsageError(f"unknown channel control unit '{unit}'")
    return clamp(unit, value)


def axis_write(unit: str, value: int) -> int:
    """The value a write of an axis control unit sets (override clamped to 0 … 200 %); an
    unknown unit is misuse."""
    if unit not in AXIS_UNITS:
        raise NcUsageError(f"unknown axis control unit '{unit}'")
    return clamp(unit, value)


def clamp(unit: str, value: int) -> int:
    """An override beyond its range is taken at the nearest end; other units as written."""
    value = int(value)
    return max(0, min(value, OVERRIDE_MAX)) if unit == "override" else value
