"""Diagnostic bundles: a machine's in one zip, and bundles opened as offline machines."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Path, Request, Response
from fastapi.concurrency import run_in_threadpool
from fastapi.requests import HTTPConnection
from fastapi.responses import PlainTextResponse

from api.auth import Action
from api.bundle import BundleDetail, BundleInfo
from api.history import HistoryPage
from api.versions import VersionDiff
from backend.bodies import dated_download, text_answer
from backend.deps import ActorDep, MachineDep, ServicesDep, get_actor, permit
from backend.errors import (
    CREATED,
    NO_CONTENT,
    OK,
    Forbidden,
    Invalid,
    NotFound,
    TooLarge,
    responses,
)
from backend.routes.history import FilterDep
from backend.routes.service import service_status
from backend.services import parameters as params
from backend.services.audit_log import Entry
from backend.services.bundle import Contents, build, lists_of
from backend.services.machine_log import EXPORT_ROWS, HistoryFilter
from backend.services.machines import MachineProxy
from backend.services.status import status_of
from backend.workers.protocol import ReadStatus, StatusRead
from nc_sim.params import Scope


async def unseated(conn: HTTPConnection) -> None:
    """Offline machines are no class student's or share link's guest's to see (404)."""
    if (await get_actor(conn)).seat is not None:
        raise NotFound("no such bundle")


router = APIRouter(prefix="/api", tags=["bundles"], dependencies=[Depends(unseated)])
BUNDLE_BODY_BYTES = 256 * 1024 * 1024  # a bundle to open
ZIP: dict[int | str, dict[str, object]] = {
    OK: {"content": {"application/zip": {}}, "description": "the bundle (zip)"}
}
BundleId = Annotated[str, Path(pattern=r"^[0-9a-f]{12}$")]
ListName = Annotated[str, Path(pattern=r"^[a-z]+(_[A-Za-z0-9]{1,16})?\.txt$")]


def _contents(services: ServicesDep, actor: ActorDep, m: MachineProxy) -> Contents:
    scopes: list[tuple[Scope, str | None]] = [(Scope.CHANNEL, None), (Scope.TOOL, None)]
    scopes += [(Scope.AXIS, a.name) for a in m.cfg.axes]
    lists = lists_of(
        scopes, lambda s, t: params.export_list(m, s, t, not params.plant_hidden(actor))
    )
    diff = None
    if services.versions.baseline_diff_now(m.id) is not None:
        a, b, changes = services.versions.compare(m.id, "baseline", "live")
        diff = VersionDiff(from_="baseline", to="live", from_label=a.label, to_label=b.label,
                           changes=changes)  # fmt: skip
    rows, _ = services.history.page(m.id, HistoryFilter(), EXPORT_ROWS)
    read = m.link.call(ReadStatus(m.id))
    assert isinstance(read, StatusRead)
    status = {
        "machine": status_of(m, read).model_dump(mode="json"),
        "flight_recorder": services.flight.status(m).model_dump(mode="json"),
        "service": service_status(services, actor).model_dump(mode="json"),
    }
    machine = {"id": m.id, "name": m.name, "source": m.source}
    return Contents(machine, lists, services.versions.of(m.id), diff, rows[::-1], status)


@router.get(
    "/machines/{mid}/bundle",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=ZIP | responses(NotFound),
)
def bundle(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> Response:
    """The machine's diagnostic bundle: its lists, versions and the diff against its
    baseline, its history, the flight recorder's traces of its newest alarms (.rrd and CSV),
    its status and the service's, named after the machine and the time."""
    data, manifest = build(_contents(services, actor, machine), services.traces, machine.id,
                           actor.name)  # fmt: skip
    what = f"made a diagnostic bundle ({len(manifest.traces)} traces)"
    services.audit.record_later(Entry(actor.name, actor.session, "trace", what, machine.id))
    return dated_download(data, "application/zip", machine.name or machine.id, "bundle", "zip")


@router.post(
    "/bundles",
    status_code=CREATED,
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(TooLarge, why={Invalid: "not a bundle (the reason)"}),
    openapi_extra={
        "requestBody": {
            "required": True,
            "content": {
                media: {"schema": {"type": "string", "maxLength": BUNDLE_BODY_BYTES}}
                for media in ("application/zip", "application/octet-stream")
            },
        }
    },
    max_body_size=BUNDLE_BODY_BYTES,
)
async def open_bundle(request: Request, services: ServicesDep, actor: ActorDep) -> BundleDetail:
    """Open a diagnostic bundle (its zip as the body) read-only as an offline machine: its
    history, lists, versions and diff; its traces go into the library."""
    data = b"".join([chunk async for chunk in request.stream()])
    detail = await run_in_threadpool(services.bundles.open, data, actor.name)
    what = f"opened the bundle of {detail.manifest.machine_name} as {detail.id}"
    services.audit.record_later(Entry(actor.name, actor.session, "trace", what))
    return detail


@router.get("/bundles", dependencies=[permit(Action.OBSERVE)])
def bundles(services: ServicesDep) -> list[BundleInfo]:
    """The bundles opened here, newest first."""
    return services.bundles.opened()


@router.get("/bundles/{bid}", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound))
def bundle_detail(bid: BundleId, services: ServicesDep) -> BundleDetail:
    """The offline machine: its lists' names, versions, diff against its baseline, status."""
    return services.bundles.detail(bid)


@router.get(
    "/bundles/{bid}/history",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound),
)
def bundle_history(bid: BundleId, services: ServicesDep, f: FilterDep) -> HistoryPage:
    """The offline machine's history as it was when the bundle was made, newest first."""
    rows = services.bundles.history(bid, f)
    return HistoryPage(rows=rows, total=len(rows))


@router.get(
    "/bundles/{bid}/lists/{name}",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=text_answer("text/plain", "the list") | responses(NotFound),
)
def bundle_list(bid: BundleId, name: ListName, services: ServicesDep) -> PlainTextResponse:
    """One of its parameter lists in the native format."""
    return PlainTextResponse(services.bundles.list_text(bid, name))


@router.delete(
    "/bundles/{bid}",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.DELETE_TRACE)],
    responses=responses(Forbidden, NotFound),
)
def delete_bundle(bid: BundleId, services: ServicesDep, actor: ActorDep) -> None:
    """Forget an offline machine and its traces."""
    services.bundles.delete(bid)
    services.audit.record_later(Entry(actor.name, actor.session, "trace", f"deleted bundle {bid}"))
