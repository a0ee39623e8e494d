"""A machine's share links: make one (valid for hours you choose), list, revoke."""

from __future__ import annotations

from collections import Counter
from typing import Annotated

from fastapi import APIRouter, Path, Request

from api.auth import Action
from api.share import ShareCreate, ShareCreated, ShareLink
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import CREATED, Forbidden, NotFound, responses
from backend.services.audit_log import Entry

router = APIRouter(prefix="/api/machines", tags=["share links"])
LinkId = Annotated[str, Path(pattern=r"^[0-9a-f]{12}$")]


def _watching(services: ServicesDep, mid: str) -> dict[str, int]:
    return Counter(s.actor.name for s in services.hub.subscribers if s.machine.id == mid)


@router.post(
    "/{mid}/share",
    status_code=CREATED,
    dependencies=[permit(Action.SHARE)],
    responses=responses(Forbidden, NotFound),
)
def share(
    req: ShareCreate, machine: MachineDep, services: ServicesDep, actor: ActorDep, request: Request
) -> ShareCreated:
    """A read-only link to the machine for someone without an account: its live view,
    history and traces, until it expires (`hours`) or is revoked. The link is shown once."""
    link, token = services.shares.create(machine.id, req.hours, req.label.strip(), actor.name)
    what = f"shared the machine by link {link.id} ({link.label or 'no label'}) for {req.hours:g} h"
    services.audit.record_later(Entry(actor.name, actor.session, "machine", what, machine.id))
    return ShareCreated(link=link, url=f"{request.base_url}share/{token}")


@router.get("/{mid}/share", dependencies=[permit(Action.SHARE)], responses=responses(NotFound))
def links(machine: MachineDep, services: ServicesDep) -> list[ShareLink]:
    """The machine's share links, newest first, with their guests watching now."""
    return services.shares.of(machine.id, _watching(services, machine.id))


@router.delete(
    "/{mid}/share/{lid}",
    dependencies=[permit(Action.SHARE)],
    responses=responses(Forbidden, NotFound),
)
def revoke(lid: LinkId, machine: MachineDep, services: ServicesDep, actor: ActorDep) -> ShareLink:
    """End a share link now: its guests are logged out within seconds."""
    link = services.shares.revoke(machine.id, lid, actor.name)
    services.sessions.poke()
    what = f"revoked share link {lid} ({link.label or 'no label'})"
    services.audit.record_later(Entry(actor.name, actor.session, "machine", what, machine.id))
    return link
