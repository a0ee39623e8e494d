"""Parameter versions of a machine: take, list, compare, set the baseline, roll back, delete."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Query, Response
from fastapi.concurrency import run_in_threadpool

from api.auth import Action
from api.parameters import ParameterWriteResult
from api.versions import RollbackRequest, VersionCreate, VersionDiff, VersionInfo
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import (
    CREATED,
    NO_CONTENT,
    WORKER_GONE,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    Why,
    responses,
)
from backend.services.audit_log import Entry
from backend.services.versions import STATE_PATTERN

router = APIRouter(prefix="/api/machines/{mid}/versions", tags=["versions"])

VersionId = Annotated[int, Path(ge=1, le=2**53, description="a version's id")]
_STATE = (
    "a version's id, 'live' (as the next restart would load), 'baseline' or 'defaults' "
    "(the manuals')"
)
FromState = Annotated[str, Query(alias="from", pattern=STATE_PATTERN, description=_STATE)]
ToState = Annotated[str, Query(pattern=STATE_PATTERN, description=_STATE)]
_TAKEN: Why = {
    Conflict: "a version of that name exists (any case), or the machine has the most it keeps"
}
_REJECTED: Why = {
    Invalid: "rejected values: parameter, range, unit (nothing applied)"
} | WORKER_GONE


@router.get("", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound, Invalid))
def list_versions(machine: MachineDep, services: ServicesDep) -> list[VersionInfo]:
    """The machine's versions, newest first; the baseline is marked."""
    return services.versions.of(machine.id)


@router.post(
    "",
    status_code=CREATED,
    dependencies=[permit(Action.VERSIONS)],
    responses=responses(Forbidden, NotFound, Invalid, why=_TAKEN),
)
def take_version(
    req: VersionCreate, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> VersionInfo:
    """Store every list of the machine (pending values included) under a name; with
    `baseline` it becomes the machine's baseline. Audited."""
    services.audit.flush()  # the trail keeps the order things happened in
    what = f"take version '{req.name}'"
    with services.audit.refusals(Entry(actor.name, actor.session, "version", what, machine.id)):
        return services.versions.take(actor, machine.id, req.name, req.note, req.baseline)


@router.get("/diff", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound, Invalid))
def compare(
    machine: MachineDep,
    services: ServicesDep,
    from_: FromState = "baseline",
    to: ToState = "live",
) -> VersionDiff:
    """Every parameter that differs from one state to another (a value not written is the
    manual's default), with list and engineering units as the parameter page shows them."""
    a, b, changes = services.versions.compare(machine.id, from_, to)
    return VersionDiff(from_=from_, to=to, from_label=a.label, to_label=b.label, changes=changes)


@router.post(
    "/{vid}/baseline",
    dependencies=[permit(Action.VERSIONS)],
    responses=responses(Forbidden, NotFound, Invalid),
)
def set_baseline(
    vid: VersionId, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> VersionInfo:
    """Make a version the machine's baseline (the one before stays a version). Audited."""
    services.audit.flush()
    what = f"set version {vid} as baseline"
    with services.audit.refusals(Entry(actor.name, actor.session, "version", what, machine.id)):
        return services.versions.set_baseline(actor, machine.id, vid)


@router.post(
    "/{vid}/rollback",
    dependencies=[permit(Action.CONFIGURE)],
    responses=responses(Forbidden, NotFound, why=_REJECTED),
)
async def rollback(
    vid: VersionId,
    req: RollbackRequest,
    machine: MachineDep,
    services: ServicesDep,
    actor: ActorDep,
) -> ParameterWriteResult:
    """Write back every value that differs from the version (only while holding control):
    one parameter write, validated all together, values that take effect at reset or restart
    pending as any write; audited value by value and as a rollback."""
    await run_in_threadpool(services.audit.flush)
    what = f"roll back to version {vid}"
    with services.audit.refusals(Entry(actor.name, actor.session, "version", what, machine.id)):
        return await run_in_threadpool(
            services.versions.rollback, actor, machine.id, vid, req.comment
        )


@router.delete(
    "/{vid}",
    status_code=NO_CONTENT,
    response_class=Response,
    dependencies=[permit(Action.VERSIONS)],
    responses=responses(
        Forbidden, NotFound, Invalid, why={Conflict: "the baseline: make another one first"}
    ),
)
def delete_version(
    vid: VersionId, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> Response:
    """Delete a version (not the baseline). Audited."""
    services.audit.flush()
    what = f"delete version {vid}"
    with services.audit.refusals(Entry(actor.name, actor.session, "version", what, machine.id)):
        services.versions.delete(actor, machine.id, vid)
    return Response(status_code=NO_CONTENT)
