"""Parameters: the registry, a machine's values, validated writes, import/export, audit."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import PlainTextResponse, Response

from api.auth import Action
from api.parameters import (
    AuditEntry,
    ParameterDef,
    ParameterValue,
    ParameterWrite,
    ParameterWriteResult,
    ScopeName,
)
from backend.bodies import (
    CHANGES_BODY_BYTES,
    LIST_BODY_BYTES,
    read_text,
    text_answer,
    text_body,
)
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import (
    WORKER_GONE,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    TooLarge,
    Why,
    responses,
)
from backend.services import parameters as params
from backend.services.audit_log import Entry
from nc_sim.params import Scope, registry

router = APIRouter(prefix="/api", tags=["parameters"])

ScopeQ = Annotated[ScopeName, Query(description="axis, channel or tool list")]
TargetQ = Annotated[str | None, Query(description="axis name for the axis list")]
_STALE: Why = {Conflict: "written by someone else since it was read: both values, nothing applied"}
_REJECTED: Why = {
    Invalid: "rejected values: parameter, range, unit (nothing applied)"
} | WORKER_GONE


@router.get("/parameters", dependencies=[permit(Action.OBSERVE)])
def definitions() -> list[ParameterDef]:
    """Every parameter the simulated NC knows: ID, list name, type, range, default, effect."""
    return [
        ParameterDef(
            id=d.id,
            name=d.name,
            scope=d.scope.value,
            dtype=d.dtype.value,
            quantity=d.quantity.value,
            default=d.default,
            min=d.lo,
            max=d.hi,
            effect=d.effect.value,
            per_gear=d.per_gear,
            title=d.title,
            source=d.source,
            without_effect=d.without_effect,
        )
        for d in registry()
    ]


@router.get(
    "/machines/{mid}/parameters",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound, Invalid),
)
def values(
    machine: MachineDep,
    services: ServicesDep,
    actor: ActorDep,
    scope: ScopeQ = "axis",
    target: TargetQ = None,
) -> list[ParameterValue]:
    """Values of one list (every gear record for getriebe[i]), with pending values and
    versions. A class's student does not get the simulated plant's sim.* values."""
    plant = not params.plant_hidden(actor)
    return params.read(machine, services.store, Scope(scope), target, plant)


@router.patch(
    "/machines/{mid}/parameters",
    dependencies=[permit(Action.CONFIGURE)],
    responses=responses(Forbidden, NotFound, TooLarge, why=_STALE | _REJECTED),
    max_body_size=CHANGES_BODY_BYTES,
)
def write(
    req: ParameterWrite, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> ParameterWriteResult:
    """Write one or many values (only while holding control of the machine): all are checked
    first, then stored, audited and applied. A value based on an older version than the
    parameter's is refused with both values (409): nobody overwrites another's change unseen."""
    names = ", ".join(c.name for c in req.changes[:5]) + (" …" if len(req.changes) > 5 else "")
    # rows recorded before (control taken by this very request) first: the trail keeps the
    # order things happened in, and a value's version is its row's place in it
    services.audit.flush()
    attempt = Entry(actor.name, actor.session, "parameter", f"write {names}", machine.id)
    with services.audit.refusals(attempt):
        return params.write(actor, machine, services.store, req.changes, req.comment)


@router.get(
    "/machines/{mid}/parameters/export",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=text_answer("text/plain", "the list") | responses(NotFound, Invalid),
)
def export(
    machine: MachineDep, actor: ActorDep, scope: ScopeQ = "axis", target: TargetQ = None
) -> PlainTextResponse:
    """The list in the native format, as a restart would load it (without the simulated
    plant's sim.* for a class's student)."""
    plant = not params.plant_hidden(actor)
    return PlainTextResponse(params.export_list(machine, Scope(scope), target, plant))


@router.post(
    "/machines/{mid}/parameters/import",
    dependencies=[permit(Action.CONFIGURE)],
    responses=responses(Forbidden, NotFound, TooLarge, why=_REJECTED),
    openapi_extra=text_body("text/plain", LIST_BODY_BYTES, "a list in the native format"),
    max_body_size=LIST_BODY_BYTES,
)
async def import_list(
    request: Request,
    machine: MachineDep,
    services: ServicesDep,
    actor: ActorDep,
    scope: ScopeQ = "axis",
    target: TargetQ = None,
) -> ParameterWriteResult:
    """Import a native list (text/plain, UTF-8); a bad line is rejected with its line number."""
    text = await read_text(request, "parameter list")
    where = f" of {target}" if target else ""
    await run_in_threadpool(services.audit.flush)  # as in `write`
    what = f"import the {scope} list{where}"
    with services.audit.refusals(Entry(actor.name, actor.session, "parameter", what, machine.id)):
        return await run_in_threadpool(
            params.import_list, actor, machine, services.store, Scope(scope), target, text
        )


@router.get("/machines/{mid}/parameters/audit", dependencies=[permit(Action.OBSERVE)])
def audit(
    mid: str, services: ServicesDep, limit: Annotated[int, Query(ge=1, le=100000)] = 1000
) -> list[AuditEntry]:
    """Accepted changes with time, actor, old and new value, oldest first (the parameter
    rows of the audit trail)."""
    services.audit.flush()
    return params.audit(services.store, mid, limit)
