"""Control of a machine: one operator at a time (the control token HEIDENHAIN calls focus).

A machine is free or held by one client of one session (a browser tab, or a script's API
token). Others request it and the holder grants or refuses; an instructor or admin takes it;
it is released on logout and after a grace period once the holder's connection is lost.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from api.auth import Role

GRACE_S = 20.0  # control outlives the holder's last connection (a reload, a blip), by default
REQUEST_S = 60.0  # an unanswered request lapses after this long
MAX_REQUEST_MESSAGE = 300  # characters a requester may write with a request


class ControlParty(BaseModel):
    """Someone who holds or asks for control: a user through one session and client."""

    user: str
    role: Role
    session: str = Field(description="public id of the session or API token")
    client: str = Field(description="the browser tab's id ('' for a script)")
    since_unix: float
    message: str = Field("", description="what a requester wrote with the request")
    lapses_unix: float | None = Field(None, description="when an unanswered request lapses")
    guest: bool = Field(False, description="a share link's guest")


class ControlState(BaseModel):
    """Who holds a machine, and who asks for it."""

    holder: ControlParty | None = Field(None, description="None: the machine is free")
    requests: list[ControlParty] = Field(default_factory=list, description="oldest first")
    connected: bool = Field(True, description="the holder watches the machine live")
    release_at_unix: float | None = Field(
        None,
        description="without a live connection (a closed tab, a script between requests) "
        "control is released then, unless the holder comes back or acts",
    )
    seq: int = Field(
        0,
        ge=0,
        description="grows with every change, across restarts of the service too: of two "
        "states (an answer, a push) the higher is the newer",
    )
    viewers: list[ControlParty] = Field(
        default_factory=list,
        description="who watches the machine live now (one per browser tab or script), "
        "share links' guests included",
    )


ControlVerb = Literal["take", "request", "cancel", "grant", "refuse", "release"]


class ControlAction(BaseModel):
    """`take` a free machine (an instructor or admin: a held one too), `request` it from its
    holder (with a `message`; observers too, to ask for the holder's attention) or `cancel`
    the request; the holder may `grant` it to a requester who may command (`session` and
    `client` name whom), `refuse` a request, or `release` it."""

    action: ControlVerb
    session: str | None = Field(None, max_length=64, description="grant or refuse: whose request")
    client: str | None = Field(None, max_length=64)
    message: str | None = Field(
        None,
        max_length=MAX_REQUEST_MESSAGE,
        description="request: a word to the holder (why, for how long), shown with the request",
    )
