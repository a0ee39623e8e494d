"""The single authorization point. Every command, parameter write, simulation control and
telemetry subscription asks `authorize` first.

The actor is who the authentication middleware identified (backend/authn.py: an API token or
a login session); a single-operator control lock plugs in here without changing routes.
"""

from __future__ import annotations

from dataclasses import dataclass

from api.auth import ALLOWED, Action, Role
from backend.errors import ApiError


@dataclass(frozen=True)
class Actor:
    name: str
    role: Role


def authorize(actor: Actor, action: Action, machine: str | None = None) -> None:
    """Raise 403 unless the actor's role permits the action (on the machine)."""
    if action not in ALLOWED[actor.role]:
        where = f" on {machine}" if machine else ""
        raise ApiError(
            403, {"message": f"{actor.name} ({actor.role.value}) may not {action.value}{where}"}
        )
