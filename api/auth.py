"""Who may do what. Roles and actions are part of the contract so the UI can show them."""

from __future__ import annotations

from enum import StrEnum

from pydantic import BaseModel, Field


class Role(StrEnum):
    """Roles of a user of the HMI."""

    OBSERVER = "observer"  # watches status and telemetry
    OPERATOR = "operator"  # commands the machine, edits parameters
    INSTRUCTOR = "instructor"  # also creates, deletes and paces machines for a class
    ADMIN = "admin"  # everything, and users and the service


class Action(StrEnum):
    """What a request does, as the single authorization point sees it."""

    OBSERVE = "observe"
    COMMAND = "command"
    CONFIGURE = "configure"  # parameter writes and imports
    SIMULATE = "simulate"  # run, pause, step, fast
    ADMINISTER = "administer"  # create, restart, delete machines


ALLOWED: dict[Role, frozenset[Action]] = {
    Role.OBSERVER: frozenset({Action.OBSERVE}),
    Role.OPERATOR: frozenset({Action.OBSERVE, Action.COMMAND, Action.CONFIGURE}),
    Role.INSTRUCTOR: frozenset(Action),
    Role.ADMIN: frozenset(Action),
}

SESSION_COOKIE = "inbetrieb_session"  # HttpOnly: the session, never readable by scripts
CSRF_COOKIE = "inbetrieb_csrf"  # readable by the page, which echoes it in CSRF_HEADER
CSRF_HEADER = "X-CSRF-Token"


class LoginRequest(BaseModel):
    """A name and password for `POST /api/auth/login`."""

    name: str = Field(min_length=1, max_length=64, description="user name")
    password: str = Field(min_length=1, max_length=256)


class Me(BaseModel):
    """Who the request's session or token belongs to."""

    name: str
    role: Role
