"""The trace library and captures: data, CSV, Rerun .rrd, viewer, measurements, compare."""

from __future__ import annotations

import re
import time
from typing import Annotated

from fastapi import APIRouter, Depends, Query, Request, Response
from fastapi.concurrency import run_in_threadpool
from fastapi.requests import HTTPConnection
from fastapi.responses import FileResponse, RedirectResponse

from api.auth import Action
from api.scope import MeasurementsModel, TraceCompare, TraceDetail, TraceInfo, TracePatch, TraceSave
from backend.bodies import CSV_BODY_BYTES, read_text, text_answer, text_body
from backend.deps import ActorDep, ServicesDep, get_actor, permit
from backend.errors import (
    CREATED,
    NO_CONTENT,
    TEMPORARY_REDIRECT,
    ApiError,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    QuotaUsedUp,
    TooLarge,
    not_found,
    responses,
)
from backend.routes.scope import BINARY
from backend.services.audit_log import Entry
from backend.services.trace_csv import from_csv, to_csv
from backend.services.viewer import viewer_url


async def seat_scope(conn: HTTPConnection, services: ServicesDep) -> None:
    """A class's student reaches the traces of their seat's machine only (others: 404)."""
    actor = await get_actor(conn)
    if actor.seat is None:
        return
    tids = [conn.path_params.get("tid")] + [conn.query_params.get(k) for k in ("a", "b")]
    for tid in tids:
        if tid is not None and services.store.trace_machine(tid) not in (actor.seat, None):
            raise not_found(f"trace {tid}")


router = APIRouter(prefix="/api/traces", tags=["traces"], dependencies=[Depends(seat_scope)])


@router.get("", dependencies=[permit(Action.OBSERVE)])
def library(services: ServicesDep, actor: ActorDep, machine: str | None = None) -> list[TraceInfo]:
    """Stored traces, newest first (of one machine when given; a student: their seat's)."""
    return services.traces.library(actor.seat or machine)


@router.get(
    "/compare", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound, Invalid)
)
def compare(a: str, b: str, services: ServicesDep) -> TraceCompare:
    """Parameters that differ between two traces, and the channels they share."""
    return services.traces.compare(a, b)


@router.post(
    "/import",
    status_code=CREATED,
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(
        Forbidden, TooLarge, QuotaUsedUp, why={Invalid: "bad CSV: which row or column, and why"}
    ),
    openapi_extra=text_body("text/csv", CSV_BODY_BYTES, "a trace as CSV, e.g. one exported"),
    max_body_size=CSV_BODY_BYTES,
)
async def import_csv(
    request: Request,
    services: ServicesDep,
    actor: ActorDep,
    name: Annotated[str, Query(max_length=200)] = "",
) -> TraceInfo:
    """Store a CSV trace (body text/csv), e.g. one exported earlier, to overlay it."""
    text = await read_text(request, "CSV import")
    # parsing and writing take seconds for a big file: off the event loop
    trace = await run_in_threadpool(from_csv, text, name)
    info = await run_in_threadpool(services.traces.add, trace, actor.name)
    _audit(services, actor, f"imported trace {info.id} ({info.name})")
    return info


@router.get("/{tid}", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound))
def detail(tid: str, services: ServicesDep) -> TraceDetail:
    """Description, parameters that differed from defaults, and the events in the record."""
    return services.traces.get(tid).detail


@router.get(
    "/{tid}/data",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=BINARY | responses(NotFound),
)
def data(tid: str, services: ServicesDep) -> Response:
    """Every sample as one binary frame (api/telemetry.py format)."""
    return Response(services.traces.frame(tid), media_type="application/octet-stream")


@router.get(
    "/{tid}/csv",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=text_answer("text/csv", "CSV text") | responses(NotFound),
)
def csv(tid: str, services: ServicesDep) -> Response:
    """Every sample as CSV, its description in a first comment line; named for what it is."""
    trace = services.traces.get(tid)
    return Response(
        to_csv(trace),
        media_type="text/csv",
        headers={
            "Content-Disposition": f'attachment; filename="{download_name(trace.detail)}.csv"'
        },
    )


@router.get(
    "/{tid}/trace.rrd",
    response_class=FileResponse,
    dependencies=[permit(Action.OBSERVE)],
    responses=BINARY | responses(NotFound, QuotaUsedUp),
)
def rrd(tid: str, services: ServicesDep) -> FileResponse:
    """The trace as a Rerun recording."""
    path = services.traces.rrd_path(tid)
    name = download_name(services.traces.get(tid).detail)
    return FileResponse(path, media_type="application/octet-stream", filename=f"{name}.rrd")


def download_name(d: TraceDetail) -> str:
    """What a downloaded trace is, in its file name (a ticket's attachment, a folder of them):
    machine, the trace's name (or its first channels), when it was captured (UTC), its id:
    `demo_X-lag-at-1-m-min_20261129-051203_40d351329495` instead of `40d351329495`."""
    what = d.name or "+".join(c.name for c in d.channels[:3]) or "trace"
    when = time.strftime("%Y%m%d-%H%M%S", time.gmtime(d.created_unix))
    safe = re.sub(r"[^A-Za-z0-9._+-]+", "-", f"{d.machine}_{what}").strip("-")[:80]
    return f"{safe}_{when}_{d.id}"


@router.get(
    "/{tid}/viewer",
    response_class=RedirectResponse,
    status_code=TEMPORARY_REDIRECT,
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(NotFound),
)
def viewer(tid: str, request: Request, services: ServicesDep, actor: ActorDep) -> RedirectResponse:
    """Open the trace in the bundled Rerun web viewer. Its loader fetches the .rrd without
    the session cookie, so the URL carries a ticket for that one request."""
    services.traces.get(tid)
    path = f"/api/traces/{tid}/trace.rrd"
    ticket = services.accounts.issue_ticket(actor, path)
    return RedirectResponse(viewer_url(request, f"{path}?ticket={ticket}"))


@router.get(
    "/{tid}/measure",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound, why={Invalid: "unknown channel, empty window"}),
)
def measure(
    tid: str,
    channel: str,
    services: ServicesDep,
    t0_s: float | None = None,
    t1_s: float | None = None,
    band_pct: Annotated[float, Query(gt=0, le=100)] = 2.0,
    band_abs: Annotated[float | None, Query(gt=0)] = None,
) -> MeasurementsModel:
    """Max |value|, overshoot, rise time 10–90 %, settling into a band, steady mean."""
    return services.traces.measure(tid, channel, t0_s, t1_s, band_pct, band_abs)


@router.post(
    "/{tid}/save",
    status_code=CREATED,
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(Forbidden, NotFound, Conflict, Invalid, QuotaUsedUp),
)
def save(tid: str, req: TraceSave, services: ServicesDep, actor: ActorDep) -> TraceInfo:
    """Keep a recent capture in the library, with a name and notes."""
    info = services.traces.save(tid, req, actor.name)
    _audit(services, actor, f"saved trace {info.id} ({info.name})", info.machine)
    return info


@router.patch(
    "/{tid}",
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(Forbidden, NotFound, Conflict, Invalid),
)
def patch(tid: str, req: TracePatch, services: ServicesDep, actor: ActorDep) -> TraceInfo:
    """Rename a stored trace or change its notes."""
    info = services.traces.patch(tid, req)
    _audit(services, actor, f"renamed or annotated trace {tid}", info.machine)
    return info


@router.delete(
    "/{tid}",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.DELETE_TRACE)],
    responses=responses(Forbidden, NotFound),
)
def delete(tid: str, services: ServicesDep, actor: ActorDep) -> None:
    try:
        machine = services.traces.get(tid).detail.machine
    except ApiError:  # a row that no longer reads is deleted all the same
        machine = ""
    services.traces.delete(tid)
    _audit(services, actor, f"deleted trace {tid}", machine)


def _audit(services: ServicesDep, actor: ActorDep, what: str, machine: str = "") -> None:
    services.audit.record_later(Entry(actor.name, actor.session, "trace", what, machine))
