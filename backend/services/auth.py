"""Who is acting, and the one check of the authorization matrix (api/auth.py ALLOWED).

The actor is who the authentication middleware identified (backend/authn.py: an API token or
a login session). Routes declare their action with `backend.deps.permit`, which asks
`authorize` and, for the actions only a control holder may do, the machine's control.
"""

from __future__ import annotations

from dataclasses import dataclass

from api.auth import ACTION_WORDS, ALLOWED, Action, Me, Role, lowest_role
from backend.errors import Forbidden, not_found


@dataclass(frozen=True)
class Actor:
    """A user acting through one login session or API token (`session`, a public id), from
    one client (a browser tab's id, '' for scripts). `seat` is the one machine a class's
    student may see (None: every machine)."""

    name: str
    role: Role
    session: str
    client: str = ""
    seat: str | None = None
    guest: bool = False  # through a share link: watching `seat` only (OBSERVE)
    watches: str | None = None  # a student's: the machine their instructor presents (OBSERVE)

    def sees(self, machine: str) -> bool:
        """Whether this actor may know the machine exists (a student: only their seat's, and
        the machine their instructor presents)."""
        return self.seat is None or machine in (self.seat, self.watches)

    @property
    def me(self) -> Me:
        return Me(
            name=self.name,
            role=self.role,
            session=self.session,
            actions=[Action.OBSERVE] if self.guest else sorted(ALLOWED[self.role]),
            guest=self.guest,
            watches=self.watches,
        )


def authorize(actor: Actor, action: Action, machine: str | None = None) -> None:
    """Raise 403 unless the actor's role permits the action (on the machine); 404 for a
    machine a student may not see (as if it did not exist)."""
    if machine is not None and not actor.sees(machine):
        raise not_found(f"machine '{machine}'")
    if actor.guest and action is not Action.OBSERVE:
        raise Forbidden(f"a share link only watches: it may not {ACTION_WORDS[action]}")
    watched = machine is not None and machine == actor.watches and machine != actor.seat
    if watched and action is not Action.OBSERVE:
        raise Forbidden(
            f"your instructor presents {machine}: you watch it, you may not "
            f"{ACTION_WORDS[action]} there"
        )
    if action not in ALLOWED[actor.role]:
        where = f" on {machine}" if machine else ""
        need = lowest_role(action).value
        raise Forbidden(
            f"{actor.name} ({actor.role.value}) may not {ACTION_WORDS[action]}{where}:"
            f" that takes the role {need} or above"
        )
