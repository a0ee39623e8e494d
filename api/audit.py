"""The audit trail: who did what to which machine, when, and with what outcome."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field

AuditKind = Literal[
    "login",
    "login_failed",
    "logout",
    "command",
    "assist",
    "parameter",
    "version",
    "control",
    "simulation",
    "machine",
    "trace",
    "recording",
    "program",
    "user",
    "token",
    "report",
    "training",  # classes, seats, faults, hints, broadcasts, freezing, snapshots
]


class AuditRecord(BaseModel):
    """One row of the append-only, hash-chained audit trail."""

    seq: int = Field(description="1, 2, 3, ... without gaps")
    time_unix: float
    actor: str = Field(description="user name; for a failed login the name that was tried")
    session: str = Field(description="public id of the session or API token ('' for none)")
    address: str = Field(description="the client's address (logins)")
    machine: str = Field(description="machine id, '' for service-wide rows")
    kind: AuditKind
    action: str = Field(description="what was done, in words")
    detail: dict[str, Any] = Field(description="the request as data (a command, a change)")
    outcome: str = Field(description="'ok', or why it was refused")
    hash: str = Field(description="SHA-256 over the row before's hash and this row")
    request_id: str = Field(
        description="the request that made it, as the service's log and the answer's "
        "X-Request-ID name it ('' for rows of earlier versions and of the service itself)"
    )


class AuditPage(BaseModel):
    """Rows matching a filter, newest first, and how many match in all."""

    rows: list[AuditRecord]
    total: int


class AuditVerification(BaseModel):
    """Whether every row still hashes to its chain."""

    ok: bool
    rows: int = Field(description="rows checked")
    first_bad_seq: int | None = Field(None, description="the first row that was changed or lost")
    message: str
