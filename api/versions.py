"""Parameter versions of a machine: named snapshots of every list, one of them the baseline
(the state at the start of commissioning), their differences and rollback."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field, StringConstraints

from api.parameters import ScopeName, Value

VERSION_NAME_CHARS = 80
VERSION_NOTE_CHARS = 1000

VersionName = Annotated[
    str,
    StringConstraints(strip_whitespace=True, min_length=1, max_length=VERSION_NAME_CHARS),
]


class VersionCreate(BaseModel):
    """Take a version: the machine's parameters as the next restart would load them (pending
    values included), under a name unique on the machine (any case)."""

    name: VersionName = Field(description="e.g. 'after kv tuning X'")
    note: str = Field("", max_length=VERSION_NOTE_CHARS, description="why, what was done")
    baseline: bool = Field(
        False, description="make it the machine's baseline (the previous one stays a version)"
    )


class VersionInfo(BaseModel):
    """One stored version, without its values."""

    id: int = Field(description="unique per service, never reused")
    machine: str
    name: str
    note: str
    created_unix: float
    created_by: str
    baseline: bool = Field(description="the machine's baseline (at most one)")
    values: int = Field(description="written values it holds (the rest are defaults)")


class RollbackRequest(BaseModel):
    """Roll back to a version: its values are written as one parameter write."""

    comment: str = Field("", max_length=200, description="added to the audit rows")


class ParamDiff(BaseModel):
    """One parameter that differs between two states (a value not written counts as the
    manual's default). `before`/`after` are list values in `unit`, as the parameter page's
    Value column; `before_eng`/`after_eng` the same in `eng_unit` (its Engineering column)."""

    scope: ScopeName
    target: str | None = Field(description="axis name, null for the channel and tool lists")
    parameter: str = Field(description="concrete list name, e.g. getriebe[0].kv")
    id: str = Field(description="the manual's parameter ID, e.g. P-AXIS-00099")
    title: str = ""
    before: Value | None = Field(description="value in the first state")
    after: Value | None = Field(description="value in the second state")
    unit: str = Field(description="unit of the list value")
    before_eng: float | None = Field(None, description="`before` in `eng_unit` (numbers)")
    after_eng: float | None = Field(None, description="`after` in `eng_unit` (numbers)")
    eng_unit: str = Field(
        "", description="the HMI's unit (as the parameter list's), e.g. 1/s for a kv in 0.01/s"
    )
    effect: str = Field(description="when a new value takes effect: now, reset or restart")


class VersionDiff(BaseModel):
    """The differences from one state to another, list by list."""

    from_: str = Field(alias="from", description="version id, 'live', 'baseline' or 'defaults'")
    to: str
    from_label: str = Field(description="what the first state is, in words")
    to_label: str
    changes: list[ParamDiff]

    model_config = {"populate_by_name": True}
