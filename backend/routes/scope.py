"""A machine's scope (setup, arm, force, stop, roll data) and its continuous recording."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Request
from fastapi.responses import FileResponse, RedirectResponse, Response

from api.auth import Action
from api.scope import RecordingInfo, RecordingStart, ScopeSetupModel, ScopeStatus
from backend.deps import ActorDep, MachineDep, ServicesDep
from backend.errors import WORKER_GONE, responses
from backend.services import scope
from backend.services.auth import authorize
from backend.services.viewer import viewer_url

router = APIRouter(prefix="/api", tags=["scope"])
BINARY: dict[int | str, dict[str, Any]] = {
    200: {"content": {"application/octet-stream": {}}, "description": "binary frame"}
}


@router.get("/machines/{mid}/scope", responses=responses(403, 404, why=WORKER_GONE))
def scope_status(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> ScopeStatus:
    """State of the scope, its setup and the recent captures (newest first)."""
    authorize(actor, Action.OBSERVE, machine.id)
    return scope.status(machine, services.traces, services.recorders)


@router.put(
    "/machines/{mid}/scope", responses=responses(403, 404, why={422: "bad setup"} | WORKER_GONE)
)
def scope_arm(
    req: ScopeSetupModel, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> ScopeStatus:
    """Arm (or start rolling) with this setup; the pre-trigger fills from recent history."""
    authorize(actor, Action.OBSERVE, machine.id)
    scope.arm(machine, req)
    return scope.status(machine, services.traces, services.recorders)


@router.post("/machines/{mid}/scope/force", responses=responses(403, 404, why=WORKER_GONE))
def scope_force(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> ScopeStatus:
    """Trigger now (an armed scope only)."""
    authorize(actor, Action.OBSERVE, machine.id)
    scope.force(machine)
    return scope.status(machine, services.traces, services.recorders)


@router.post("/machines/{mid}/scope/stop", responses=responses(403, 404, why=WORKER_GONE))
def scope_stop(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> ScopeStatus:
    authorize(actor, Action.OBSERVE, machine.id)
    scope.stop(machine)
    return scope.status(machine, services.traces, services.recorders)


@router.get(
    "/machines/{mid}/scope/roll",
    response_class=Response,
    responses=BINARY | responses(403, 404, 409, 422, why=WORKER_GONE),
)
def scope_roll(
    machine: MachineDep,
    actor: ActorDep,
    max_points: Annotated[int, Query(ge=100, le=200_000)] = 5000,
) -> Response:
    """The newest record length of a running scope (every stride-th cycle)."""
    authorize(actor, Action.OBSERVE, machine.id)
    return Response(scope.roll_frame(machine, max_points), media_type="application/octet-stream")


@router.post("/machines/{mid}/recording", status_code=201, responses=responses(403, 404, 409, 422))
def recording_start(
    req: RecordingStart, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> RecordingInfo:
    """Record these signals every cycle into a Rerun .rrd until stopped."""
    authorize(actor, Action.OBSERVE, machine.id)
    return services.recorders.begin(machine, req.signals)


@router.delete("/machines/{mid}/recording", responses=responses(403, 404, 409))
def recording_stop(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> RecordingInfo:
    authorize(actor, Action.OBSERVE, machine.id)
    return services.recorders.end(machine.id)


@router.get(
    "/recordings/{rid}/recording.rrd",
    response_class=FileResponse,
    responses=BINARY | responses(404),
)
def recording_rrd(rid: str, services: ServicesDep) -> FileResponse:
    """The recording as a Rerun .rrd file (so far, while it runs)."""
    path = services.recorders.path(rid)
    return FileResponse(path, media_type="application/octet-stream", filename=f"{rid}.rrd")


@router.get(
    "/recordings/{rid}/viewer",
    response_class=RedirectResponse,
    status_code=307,
    responses=responses(404),
)
def recording_viewer(rid: str, request: Request, services: ServicesDep) -> RedirectResponse:
    """Open the recording in the bundled Rerun web viewer."""
    services.recorders.path(rid)
    return RedirectResponse(viewer_url(request, f"/api/recordings/{rid}/recording.rrd"))
