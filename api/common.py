"""Shared models: job errors and events, refusals."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field


def unit(symbol: str) -> dict[str, Any]:
    """`json_schema_extra=` naming the unit of a field whose name does not (its schema's
    `x-unit`: refusals name it, e.g. "must be at most 100 mm")."""
    return {"x-unit": symbol}


# SQLite's integers are signed 64-bit: a larger number meant for the store (a row's number,
# a version) is refused as out of range, never passed on to overflow there
STORE_INT_MAX = 2**63 - 1


class JobErrorModel(BaseModel):
    """One job error or event of a machine, numbered as the manuals number them."""

    model_config = ConfigDict(allow_inf_nan=False)

    cycle: int = Field(description="cycle in which it happened")
    t_s: float = Field(description="simulated time, s")
    axis: str = Field(description="axis or spindle, empty for the channel")
    code: int = Field(description="job error (≥ 60000) or event number")
    message: str = Field(description="in the operator's words (for people: never parse it)")
    error: bool = Field(description="true for a job error, false for an information event")
    seq: int | None = Field(
        None,
        description="sequence number in the machine's event log (from 0 per power-on, "
        "increasing by one); null only in traces saved before events were numbered",
    )
    m: int | None = Field(
        None,
        description="the M function it concerns: M function output, acknowledgement and "
        "start, in position after M19 (m = 19), M5 stop done; null for none",
    )
    gear: int | None = Field(
        None,
        description="the gear stage 1..6 (M40..M45) it concerns: gear change started, gear "
        "changed, M40-M45 output of a gear change; null for none",
    )
    line: int | None = Field(
        None, description="program line (from 1) it concerns: a program error, a block"
    )
    column: int | None = Field(None, description="column (from 1) of a program error")
    signal: str | None = Field(
        None,
        max_length=16,
        description="the PLC interface signal (ROTMOD, ROTMOD_Q, SPMOD, SPMOD_Q) or HLI unit "
        "(feedhold, DriveOn, override, ...) it concerns: signal set/reset events and HLI "
        "writes; null for none",
    )
    value: float | None = Field(
        None,
        description="the value it concerns: the position reached (in position, mm | °), the "
        "value written (an HLI unit, a signal 0/1), the seq of the job error that dropped an "
        "MDI block; null for none",
    )
    block: int | None = Field(
        None,
        description="the MDI block it concerns (the block_id its command's answer gave): block "
        "done, block dropped by a job error; null for none",
    )


class ParameterProblem(BaseModel):
    """A rejected parameter value: which parameter, its range and unit, and why."""

    parameter: str = Field(description="list name, e.g. getriebe[0].kv")
    id: str | None = Field(None, description="manual ID, e.g. P-AXIS-00099")
    target: str | None = Field(None, description="axis name, or null for the channel list")
    message: str
    line: int | None = Field(None, description="line of an imported list")
    min: float | None = None
    max: float | None = None
    unit: str | None = None


class StaleValue(BaseModel):
    """A parameter someone else wrote after the edit began: both values, nothing written."""

    parameter: str
    target: str | None
    yours: float | int | str = Field(description="the value this write asked for")
    current: float | int | str | None = Field(description="the value in force (None: default)")
    base_version: int = Field(description="the version the edit was based on")
    version: int = Field(description="the parameter's version now")
    by: str = Field(description="who wrote the current value")
    time_unix: float | None


class Refusal(BaseModel):
    """Why a request was not carried out (HTTP 4xx body under `detail`)."""

    message: str
    code: int | None = Field(None, description="job error number when the NC refused it")
    line: int | None = Field(None, description="1-based line of a bad NC program")
    column: int | None = Field(None, description="1-based column of a bad NC block or program")
    error: JobErrorModel | None = None
    serial: int | None = Field(
        None, description="the machine's number of the refused command (commands only)"
    )
    problems: list[ParameterProblem] = Field(
        default_factory=list, description="rejected parameter values (nothing was applied)"
    )
    stale: list[StaleValue] = Field(
        default_factory=list, description="parameters written by someone else meanwhile"
    )


class ValidationIssue(BaseModel):
    """One way a request does not match the schema (FastAPI's request validation)."""

    loc: list[str | int] = Field(description="where: body, query, path, then field names")
    msg: str
    type: str = Field(description="pydantic error type, e.g. missing, literal_error")
    input: Any = Field(None, description="the offending input; long inputs are cut and end in '…'")
    text: str = Field(
        description="the issue as a sentence: the field's meaning, the rule and its unit "
        "(what a UI shows)"
    )


class ErrorBody(BaseModel):
    """HTTP body of every error answer: a refusal, or the request's schema violations."""

    detail: Refusal | list[ValidationIssue]
