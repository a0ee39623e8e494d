"""Parameters: the registry, a machine's values, validated writes, import/export, audit."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Body, Query
from fastapi.responses import PlainTextResponse

from api.parameters import (
    AuditEntry,
    ParameterDef,
    ParameterValue,
    ParameterWrite,
    ParameterWriteResult,
    ScopeName,
)
from backend.deps import ActorDep, HostDep, ServicesDep
from backend.services import parameters as params
from nc_sim.params import Scope, registry

router = APIRouter(prefix="/api", tags=["parameters"])

ScopeQ = Annotated[ScopeName, Query(description="axis, channel or tool list")]
TargetQ = Annotated[str | None, Query(description="axis name for the axis list")]
_REJECTED: dict[int | str, dict[str, Any]] = {
    422: {"description": "rejected values: parameter, range, unit (nothing applied)"}
}


@router.get("/parameters")
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
        )
        for d in registry()
    ]


@router.get("/machines/{mid}/parameters")
def values(host: HostDep, scope: ScopeQ = "axis", target: TargetQ = None) -> list[ParameterValue]:
    """Values of one list (every gear record for getriebe[i]), with pending values."""
    return params.read(host, Scope(scope), target)


@router.patch("/machines/{mid}/parameters", responses=_REJECTED)
def write(
    req: ParameterWrite, host: HostDep, services: ServicesDep, actor: ActorDep
) -> ParameterWriteResult:
    """Write one or many values: all are checked first, then stored, audited and applied."""
    return params.write(actor, host, services.store, req.changes, req.comment)


@router.get("/machines/{mid}/parameters/export", response_class=PlainTextResponse)
def export(host: HostDep, scope: ScopeQ = "axis", target: TargetQ = None) -> str:
    """The list in the native format, as a restart would load it."""
    return params.export_list(host, Scope(scope), target)


@router.post("/machines/{mid}/parameters/import", responses=_REJECTED)
def import_list(
    host: HostDep,
    services: ServicesDep,
    actor: ActorDep,
    text: Annotated[str, Body(media_type="text/plain", max_length=1_000_000)],
    scope: ScopeQ = "axis",
    target: TargetQ = None,
) -> ParameterWriteResult:
    """Import a native list (text/plain); a bad line is rejected with its line number."""
    return params.import_list(actor, host, services.store, Scope(scope), target, text)


@router.get("/machines/{mid}/parameters/audit")
def audit(
    mid: str, services: ServicesDep, limit: Annotated[int, Query(ge=1, le=100000)] = 1000
) -> list[AuditEntry]:
    """Accepted changes with time, actor, old and new value, oldest first."""
    return params.audit(services.store, mid, limit)
