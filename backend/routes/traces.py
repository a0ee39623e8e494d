"""The trace library and captures: data, CSV, Rerun .rrd, viewer, measurements, compare."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import FileResponse, PlainTextResponse, RedirectResponse

from api.auth import Action
from api.scope import MeasurementsModel, TraceCompare, TraceDetail, TraceInfo, TracePatch, TraceSave
from backend.deps import ActorDep, ServicesDep
from backend.errors import ApiError
from backend.routes.scope import BINARY
from backend.services.auth import authorize
from backend.services.trace_csv import from_csv, to_csv
from backend.services.viewer import viewer_url

router = APIRouter(prefix="/api/traces", tags=["traces"])
MAX_CSV_BYTES = 64 * 1024 * 1024


@router.get("")
def library(services: ServicesDep, machine: str | None = None) -> list[TraceInfo]:
    """Stored traces, newest first (of one machine when given)."""
    return services.traces.library(machine)


@router.get("/compare")
def compare(a: str, b: str, services: ServicesDep) -> TraceCompare:
    """Parameters that differ between two traces, and the channels they share."""
    return services.traces.compare(a, b)


@router.post("/import", status_code=201, responses={422: {"description": "bad CSV"}})
async def import_csv(
    request: Request, services: ServicesDep, actor: ActorDep, name: str = ""
) -> TraceInfo:
    """Store a CSV trace (body text/csv), e.g. one exported earlier, to overlay it."""
    authorize(actor, Action.OBSERVE, "")
    body = await request.body()
    if len(body) > MAX_CSV_BYTES:
        raise ApiError(413, {"message": f"CSV larger than {MAX_CSV_BYTES} bytes"})
    try:
        text = body.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ApiError(422, {"message": "CSV import: not UTF-8 text"}) from None
    return services.traces.add(from_csv(text, name))


@router.get("/{tid}")
def detail(tid: str, services: ServicesDep) -> TraceDetail:
    """Description, parameters that differed from defaults, and the events in the record."""
    return services.traces.get(tid).detail


@router.get("/{tid}/data", response_class=Response, responses=BINARY)
def data(tid: str, services: ServicesDep) -> Response:
    """Every sample as one binary frame (api/telemetry.py format)."""
    return Response(services.traces.frame(tid), media_type="application/octet-stream")


@router.get("/{tid}/csv", response_class=PlainTextResponse)
def csv(tid: str, services: ServicesDep) -> PlainTextResponse:
    trace = services.traces.get(tid)
    return PlainTextResponse(
        to_csv(trace),
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="{tid}.csv"'},
    )


@router.get("/{tid}/trace.rrd", response_class=FileResponse)
def rrd(tid: str, services: ServicesDep) -> FileResponse:
    """The trace as a Rerun recording."""
    path = services.traces.rrd_path(tid)
    return FileResponse(path, media_type="application/octet-stream", filename=f"{tid}.rrd")


@router.get("/{tid}/viewer", response_class=RedirectResponse)
def viewer(tid: str, request: Request, services: ServicesDep) -> RedirectResponse:
    """Open the trace in the bundled Rerun web viewer."""
    services.traces.get(tid)
    return RedirectResponse(viewer_url(request, f"/api/traces/{tid}/trace.rrd"))


@router.get("/{tid}/measure", responses={422: {"description": "unknown channel, empty window"}})
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


@router.post("/{tid}/save", status_code=201)
def save(tid: str, req: TraceSave, services: ServicesDep, actor: ActorDep) -> TraceInfo:
    """Keep a recent capture in the library, with a name and notes."""
    authorize(actor, Action.OBSERVE, "")
    return services.traces.save(tid, req)


@router.patch("/{tid}")
def patch(tid: str, req: TracePatch, services: ServicesDep, actor: ActorDep) -> TraceInfo:
    """Rename a stored trace or change its notes."""
    authorize(actor, Action.OBSERVE, "")
    return services.traces.patch(tid, req)


@router.delete("/{tid}", status_code=204)
def delete(tid: str, services: ServicesDep, actor: ActorDep) -> None:
    authorize(actor, Action.OBSERVE, "")
    services.traces.delete(tid)
