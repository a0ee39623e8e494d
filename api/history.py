"""A machine's history: one timeline of its job errors, events, commands and their outcomes,
parameter and control changes, power-ons, service starts and stops, and notes, kept in the
store across restarts."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from api.audit import AuditKind

MAX_NOTE = 2000  # characters of a note

LogKind = Literal[
    "job_error",  # the NC raised a job error
    "cleared",  # a reset cleared the job errors in force
    "event",  # an information event of the NC
    "power",  # the machine was powered on (built, restarted, rebuilt, restored)
    "service",  # the service started or stopped
    "note",  # a logbook entry somebody wrote
    "acknowledged",  # somebody acknowledged the job errors in force (the banner's ×)
]
HistoryKind = AuditKind | LogKind
Severity = Literal["error", "warning", "info"]


class HistoryEntry(BaseModel):
    """One entry of a machine's history."""

    id: str = Field(
        description="'h<n>' for the machine log's rows, 'a<seq>' for the audit trail's "
        "(commands, parameters, control, ...)"
    )
    time_unix: float = Field(description="wall clock, Unix time")
    sim_t_s: float | None = Field(
        None, description="the machine's simulated time then (s; from 0 at each power-on)"
    )
    epoch: int | None = Field(
        None,
        description="the machine's build then (each power-on counts one up, across restarts "
        "of the service too)",
    )
    kind: HistoryKind
    severity: Severity
    actor: str = Field(description="who did it; '' for the NC itself")
    text: str = Field(description="what happened, in words")
    outcome: str = Field("", description="a command's outcome: 'ok', or why it failed")
    code: int | None = Field(None, description="job error or event number")
    axis: str = Field("", description="axis or spindle, '' for the channel")
    trace: str | None = Field(None, description="the trace saved with it (flight recorder)")
    cause: str | None = Field(
        None, description="a job error: the command whose block raised it, and who sent it"
    )


class HistoryPage(BaseModel):
    """Entries matching a filter, newest first, and how many match in all."""

    rows: list[HistoryEntry]
    total: int


class NoteCreate(BaseModel):
    """A logbook entry for the machine's history (e.g. 'replaced the encoder cable of X')."""

    text: str = Field(min_length=1, max_length=MAX_NOTE)
