"""Parameters: registry entries, values of a machine, writes and their audit trail."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field, StrictFloat, StrictInt, StrictStr

from api.common import STORE_INT_MAX

ScopeName = Literal["axis", "channel", "tool"]
Value = float | int | str


class ParameterDef(BaseModel):
    """A registry entry as the manuals define it."""

    id: str
    name: str = Field(description="list name with [i]/[j] placeholders")
    scope: ScopeName
    dtype: str
    quantity: str
    default: float | str
    min: float | str | None = Field(description="number, or the list name that bounds it")
    max: float | str | None
    effect: Literal["now", "reset", "restart"]
    per_gear: bool
    title: str
    source: str
    without_effect: str = Field(
        "", description="why the simulation accepts it without effect (empty: it acts)"
    )


class ParameterValue(BaseModel):
    """One concrete parameter of one list of a machine."""

    scope: ScopeName
    target: str | None = Field(description="axis name, null for the channel and tool lists")
    name: str = Field(description="concrete list name, e.g. getriebe[2].kv")
    id: str
    value: Value = Field(description="value in force")
    default: Value
    set: bool = Field(description="written in the list (not a default)")
    unit: str = Field(description="unit of the value in the list")
    effect: Literal["now", "reset", "restart"]
    gear: int | None = Field(None, description="gear stage 1..6 of a getriebe[i] entry")
    pending: Value | None = Field(None, description="written, takes effect at reset/restart")
    title: str = Field("", description="what the manual says it is")
    without_effect: str = Field(
        "", description="why the simulation accepts it without effect (empty: it acts)"
    )
    min: float | None = Field(None, description="lower bound in list units, as the list stands")
    max: float | None = Field(None, description="upper bound in list units, as the list stands")
    eng_factor: float | None = Field(
        None,
        description="list value × eng_factor = the value in the HMI's unit `eng_unit` "
        "(numeric entries; nc_sim.units.display_unit: velocities mm/min, °/min or rpm, "
        "weights %, kv 1/s)",
    )
    eng_unit: str = Field("", description="the HMI's unit, e.g. 1/s for a kv in 0.01/s")
    version: int = Field(
        0,
        description="changes with every write (0: never written here); send it back as "
        "`base_version` so a write over someone else's newer value is refused",
    )


class ParameterChange(BaseModel):
    scope: ScopeName
    target: str | None = Field(None, description="axis name; null for channel and tool")
    name: str = Field(min_length=1, max_length=120)
    # strict: `true` is not 1.0 and "2000" stays text (parsed as the list format would)
    value: StrictFloat | StrictInt | StrictStr
    base_version: int | None = Field(
        None,
        ge=0,
        le=STORE_INT_MAX,
        description="the version the edit was based on: refused (409, both values) "
        "when the parameter was written since; null: no check (a script's deliberate write)",
    )


class ParameterWrite(BaseModel):
    """One or many values, checked together: all are applied or none."""

    changes: list[ParameterChange] = Field(min_length=1, max_length=5000)
    comment: str = Field("", max_length=200)


class AppliedChange(BaseModel):
    scope: ScopeName
    target: str | None
    name: str
    old: Value | None
    new: Value
    effect: Literal["now", "reset", "restart"]
    pending: bool = Field(description="stored, waits for reset/restart")
    version: int = Field(
        description="the value's version after this write (as `ParameterValue.version`): a "
        "reset or restart taking the value in leaves it, a later write changes it",
    )


class ParameterWriteResult(BaseModel):
    changes: list[AppliedChange]


class AuditEntry(BaseModel):
    """One accepted parameter change as stored in the audit trail."""

    seq: int
    time_unix: float
    machine: str
    actor: str
    scope: ScopeName
    target: str | None
    name: str
    old: Value | None
    new: Value
    effect: Literal["now", "reset", "restart"]
    comment: str
