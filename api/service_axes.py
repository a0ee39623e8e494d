"""The service-axis view: per axis and spindle, the loop's gain and the lag it should give,
the gain measured from the newest cycles, the D/A output and the dynamic limits in force
with their sources. Served on its own route (read while the HMI's Service tab is open), so
the status pushed to every viewer stays compact."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

LimitKind = Literal["parameter", "programmed", "reduced_speed", "reduced_acceleration", "tool"]


class LimitInForce(BaseModel):
    """A dynamic limit in force and where it comes from."""

    value: float = Field(description="in `unit`")
    unit: str = Field(
        description="velocity: mm/min, °/min or rpm; acceleration unit/s²; jerk unit/s³"
    )
    source: str = Field(
        description="the list name of the parameter (with the gear record's index, e.g. "
        "getriebe[0].dynamik.vb_max), F or F (path) for the programmed feed, S for the "
        "programmed spindle speed, 'jog feed', wz[i].* for the tool's limit; a jerk names "
        "acceleration / ramp time"
    )
    param_id: str | None = Field(description="the parameter's ID (P-AXIS-00212), null for F/S")
    kind: LimitKind = Field(
        description="parameter; programmed (F, S, jog feed); reduced_speed or "
        "reduced_acceleration (the PLC's HLI request selects that parameter); tool"
    )
    override_pct: float | None = Field(
        description="the override that scales this limit, %; null when none does (100 %)"
    )


class AxisService(BaseModel):
    """One axis or spindle in the service-axis view (positions, speeds, enables and status
    bits are in its AxisStatus)."""

    name: str
    gear: int = Field(description="the active gear record (1 = getriebe[0])")
    kv_per_s: float = Field(description="kv of the active gear record, 1/s")
    ff_weight: float = Field(description="velocity feedforward weight in force, 0..1")
    multi_gain: float = Field(
        description="multi_gain_z/multi_gain_n: digits for 1 m/min or 1000 °/min"
    )
    lag_max: float = Field(description="getriebe.lag_max, mm or °")
    v_cmd: float = Field(description="commanded speed, mm/s or °/s")
    lag_expected: float | None = Field(
        description="(1 − ff)·v/kv, mm or °; null without a closed position loop"
    )
    lag_expected_why_not: str | None
    k_measured_per_s: float | None = Field(
        description="k = v/lag, 1/s, averaged over 0.1 s after the speed has been constant for "
        "8/kv; null when that does not hold or |lag| is below 100 encoder increments"
    )
    k_why_not: str | None = Field(description="why k is not shown")
    da_digits: float = Field(description="manipulated variable at the D/A, digits")
    da_max_digits: float = Field(description="lr_hw.da_max, digits")
    velocity: LimitInForce
    acceleration: LimitInForce
    jerk: LimitInForce | None = Field(description="null: step-shaped, jerk not limited")
    jerk_why_none: str | None


class ServiceAxes(BaseModel):
    """The service-axis view of a machine, read in one cycle."""

    cycle: int
    axes: list[AxisService]
