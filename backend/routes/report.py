"""The commissioning report of a machine (HTML and PDF), its sign-off, and the stored
assistant runs it shows."""

from __future__ import annotations

import re
from typing import Annotated, Any

from fastapi import APIRouter, Path, Query, Response
from fastapi.responses import HTMLResponse

from api.auth import Action
from api.common import STORE_INT_MAX
from api.report import AssistRun, AssistRunInfo, SignOff, SignOffRequest
from backend.bodies import text_answer
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import CREATED, OK, Forbidden, Invalid, NotFound, Unavailable, Why, responses
from backend.report.pdf import html_to_pdf
from backend.services.assist_runs import MAX_LIST
from backend.services.audit_log import Entry
from backend.services.report import MAX_TRACES

router = APIRouter(prefix="/api/machines/{mid}", tags=["report"])
TraceIds = Annotated[
    list[str],
    Query(
        alias="trace",
        default_factory=list,
        max_length=MAX_TRACES,
        description=f"stored traces of this machine to plot (repeat: ?trace=A&trace=B; at most "
        f"{MAX_TRACES})",
    ),
]
_TRACE_WHY: Why = {Invalid: "a trace of another machine, without samples, or too many"}
_PDF: dict[int | str, Any] = {
    OK: {"content": {"application/pdf": {}}, "description": "the report as PDF"}
}


@router.get("/assist/runs", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound))
def runs(
    machine: MachineDep,
    services: ServicesDep,
    limit: Annotated[int, Query(ge=1, le=MAX_LIST)] = 50,
) -> list[AssistRunInfo]:
    """The machine's stored assistant runs, newest first (without their results)."""
    return services.assist_runs.latest(machine.id, limit)


@router.get(
    "/assist/runs/{run_id}", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound)
)
def run(
    run_id: Annotated[int, Path(ge=1, le=STORE_INT_MAX)], machine: MachineDep, services: ServicesDep
) -> AssistRun:
    """One stored run with everything the assistant answered (figures, changes, series)."""
    return services.assist_runs.get(machine.id, run_id)


@router.get(
    "/report",
    response_class=Response,  # its errors are JSON, as every route's
    dependencies=[permit(Action.OBSERVE)],
    responses=text_answer("text/html", "the report, printable (A4)")
    | responses(NotFound, Invalid, why=_TRACE_WHY),
)
async def report(
    machine: MachineDep, services: ServicesDep, actor: ActorDep, trace: TraceIds
) -> HTMLResponse:
    """The commissioning report: the machine, who commissioned it and when, every stored
    assistant run with its figures and plots, the parameter differences against the
    baseline, the chosen traces plotted, an audit excerpt and the sign-offs."""
    text = await services.reports.build(machine, trace, actor.name)
    return HTMLResponse(text)


@router.get(
    "/report.pdf",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=_PDF
    | responses(
        NotFound, Invalid, why=_TRACE_WHY | {Unavailable: "Chromium is missing or failed to print"}
    ),
)
async def report_pdf(
    machine: MachineDep, services: ServicesDep, actor: ActorDep, trace: TraceIds
) -> Response:
    """The report printed to PDF (A4) by headless Chromium."""
    text = await services.reports.build(machine, trace, actor.name)
    pdf = await html_to_pdf(text, services.settings.chromium)
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", machine.id)
    disposition = f'attachment; filename="commissioning-report-{name}.pdf"'
    return Response(pdf, media_type="application/pdf", headers={"content-disposition": disposition})


@router.get(
    "/report/sign-offs", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound)
)
def sign_offs(machine: MachineDep, services: ServicesDep) -> list[SignOff]:
    """Who signed the machine's commissioning off, oldest first."""
    return services.reports.sign_offs(machine.id)


@router.post(
    "/report/sign-off",
    status_code=CREATED,
    dependencies=[permit(Action.SIGN_OFF)],
    responses=responses(Forbidden, NotFound, Invalid),
)
def sign_off(
    body: SignOffRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> SignOff:
    """Sign the machine's commissioning off (name, function, remark): stored with the account
    and time, in the audit trail, and shown in the report."""
    with services.audit.refusals(
        Entry(actor.name, actor.session, "report", f"sign-off by {body.name}", machine.id)
    ):
        return services.reports.sign_off(machine.id, actor, body)
