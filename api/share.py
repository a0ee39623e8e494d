"""Share links: an expiring, revocable, read-only view of one machine without an account."""

from __future__ import annotations

from pydantic import BaseModel, Field

MAX_SHARE_H = 168.0  # a week


class ShareCreate(BaseModel):
    """A new share link to the machine."""

    hours: float = Field(24.0, ge=0.05, le=MAX_SHARE_H, description="how long it is valid, h")
    label: str = Field("", max_length=60, description="for whom, e.g. 'Bosch service'")


class ShareLink(BaseModel):
    """A share link (its secret is shown once, when it is made)."""

    id: str
    machine: str
    label: str
    created_unix: float
    created_by: str
    expires_unix: float
    revoked_unix: float | None
    revoked_by: str
    uses: int = Field(description="times it was opened")
    active: bool = Field(description="neither expired nor revoked")
    guest: str = Field(description="the login its guests act as (the audit names it)")
    watching: int = Field(0, description="its guests watching the machine live now")


class ShareCreated(BaseModel):
    link: ShareLink
    url: str = Field(description="the link to pass on: anyone with it may watch until it ends")
