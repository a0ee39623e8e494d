"""Control of a machine: who holds it; take, request, grant, refuse, release."""

from __future__ import annotations

from fastapi import APIRouter

from api.auth import Action
from api.control import ControlAction, ControlState
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import Conflict, Forbidden, NotFound, responses
from backend.services.audit_log import Entry

router = APIRouter(prefix="/api/machines", tags=["control"])


@router.get("/{mid}/control", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound))
def control_state(machine: MachineDep) -> ControlState:
    """Who holds the machine and who asks for it (also pushed with the status)."""
    return machine.control.state()


@router.post(
    "/{mid}/control",
    dependencies=[permit(Action.ASK)],  # observers ask; the rest needs CONTROL (`act`)
    responses=responses(
        Forbidden,
        NotFound,
        why={
            Conflict: "nothing to request (the machine is free, or yours); a student's seat is "
            "frozen by the instructor",
        },
    ),
)
def control(
    req: ControlAction, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> ControlState:
    """Take a free machine (an instructor or admin: a held one too), request it from its
    holder with a message (observers too: to be heard; they are never granted it) or withdraw
    the request; the holder grants or refuses a request, or releases it.
    A new holder's jogs are their own: the old holder's stop."""
    attempt = Entry(actor.name, actor.session, "control", req.action, machine.id, req.model_dump())
    with services.audit.refusals(attempt):  # a refused attempt is recorded too
        return services.control.act(actor, machine, req)
