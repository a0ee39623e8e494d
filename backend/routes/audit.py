"""The audit trail: filtered pages, CSV export and the chain check. A machine's rows are for
everyone who may watch it; the whole trail (logins, users) is for admins."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Query, Response

from api.audit import AuditKind, AuditPage, AuditVerification
from api.auth import Action
from api.common import STORE_INT_MAX
from backend.bodies import text_answer
from backend.deps import MachineDep, ServicesDep, permit
from backend.errors import Forbidden, NotFound, responses
from backend.services.audit import MAX_PAGE, AuditFilter

router = APIRouter(prefix="/api", tags=["audit"])

Text = Annotated[str | None, Query(max_length=200)]
Limit = Annotated[int, Query(ge=1, le=MAX_PAGE)]
CSV_ANSWER = text_answer("text/csv", "the matching rows, oldest first")


def _filter(
    kind: AuditKind | None = None,
    actor: Annotated[str | None, Query(max_length=200, description="part of a user name")] = None,
    since_unix: Annotated[float | None, Query(ge=0, le=1e11)] = None,
    until_unix: Annotated[float | None, Query(ge=0, le=1e11)] = None,
    text: Annotated[str | None, Query(max_length=200, description="in action or outcome")] = None,
    machine: Text = None,
) -> AuditFilter:
    return AuditFilter(machine, kind, actor, since_unix, until_unix, text)


FilterDep = Annotated[AuditFilter, Depends(_filter)]


def _csv(text: str, name: str) -> Response:
    return Response(
        text,
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="{name}.csv"'},
    )


def _of(machine: MachineDep, f: AuditFilter) -> AuditFilter:
    return AuditFilter(machine.id, f.kind, f.actor, f.since_unix, f.until_unix, f.text)


@router.get(
    "/machines/{mid}/audit", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound)
)
def machine_audit(
    machine: MachineDep,
    services: ServicesDep,
    f: FilterDep,
    limit: Limit = 200,
    before_seq: Annotated[int | None, Query(ge=1, le=STORE_INT_MAX)] = None,
) -> AuditPage:
    """The machine's rows (commands, parameters, control, pacing, traces), newest first."""
    return services.audit.page(_of(machine, f), limit, before_seq)


@router.get(
    "/machines/{mid}/audit.csv",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=CSV_ANSWER | responses(NotFound),
)
def machine_audit_csv(machine: MachineDep, services: ServicesDep, f: FilterDep) -> Response:
    return _csv(services.audit.csv(_of(machine, f)), f"audit-{machine.id}")


@router.get("/audit", dependencies=[permit(Action.USERS)], responses=responses(Forbidden))
def audit(
    services: ServicesDep,
    f: FilterDep,
    limit: Limit = 200,
    before_seq: Annotated[int | None, Query(ge=1, le=STORE_INT_MAX)] = None,
) -> AuditPage:
    """Every row, logins and failed logins too, newest first."""
    return services.audit.page(f, limit, before_seq)


@router.get(
    "/audit.csv",
    response_class=Response,
    dependencies=[permit(Action.USERS)],
    responses=CSV_ANSWER | responses(Forbidden),
)
def audit_csv(services: ServicesDep, f: FilterDep) -> Response:
    return _csv(services.audit.csv(f), "audit")


@router.get("/audit/verify", dependencies=[permit(Action.USERS)], responses=responses(Forbidden))
def verify(services: ServicesDep) -> AuditVerification:
    """Recompute the hash chain: the first row changed, inserted or removed since written."""
    return services.audit.verify()
