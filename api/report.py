"""The commissioning report: stored assistant runs and the sign-off."""

from __future__ import annotations

from pydantic import BaseModel, Field

from api.assist import AssistResult


class AssistRunInfo(BaseModel):
    """One stored assistant run, without its result (for lists)."""

    id: int
    machine: str
    assistant: str = Field(description="e.g. multi-gain, sign-check")
    user: str = Field(description="who ran it")
    time_unix: float
    live: bool = Field(description="run on the live machine (false: on a copy)")
    ok: bool
    axis: str = Field(description="the axis or spindle it ran on ('' when none)")
    summary: str = Field(description="the main figures in words, e.g. 'k = 8.75 1/s, f = 2.29'")
    measurement: int | str | None = Field(
        None,
        description="what it measured, for an assistant that measures several things (its "
        "`measurement` input, e.g. the frequency response's); null otherwise",
    )


class AssistRun(AssistRunInfo):
    """A stored run with everything the assistant answered."""

    result: AssistResult


class SignOffRequest(BaseModel):
    """Who signs the commissioning of a machine off."""

    name: str = Field(min_length=1, max_length=100, description="the signatory's full name")
    role: str = Field(
        "", max_length=100, description="the signatory's function, e.g. commissioning engineer"
    )
    remark: str = Field("", max_length=2000, description="conditions, open points")


class SignOff(BaseModel):
    """A recorded sign-off of a machine's commissioning."""

    id: int
    machine: str
    name: str
    role: str
    remark: str
    user: str = Field(description="the account that recorded it")
    time_unix: float
