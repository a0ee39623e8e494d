"""A machine's scope (setup, arm, force, stop, roll data) and its continuous recording."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any

from fastapi import APIRouter, Query, Request
from fastapi.responses import RedirectResponse, Response, StreamingResponse

from api.auth import Action
from api.scope import RecordingInfo, RecordingStart, ScopeSetupModel, ScopeStatus
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import (
    CREATED,
    OK,
    TEMPORARY_REDIRECT,
    WORKER_GONE,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    QuotaUsedUp,
    responses,
)
from backend.services import scope
from backend.services.audit_log import Entry
from backend.services.viewer import viewer_url

router = APIRouter(prefix="/api", tags=["scope"])
BINARY: dict[int | str, dict[str, Any]] = {
    OK: {"content": {"application/octet-stream": {}}, "description": "binary frame"}
}


@router.get(
    "/machines/{mid}/scope",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound, why=WORKER_GONE),
)
def scope_status(machine: MachineDep, services: ServicesDep) -> ScopeStatus:
    """State of the scope, its setup and the recent captures (newest first)."""
    return scope.status(machine, services.traces, services.recorders)


@router.put(
    "/machines/{mid}/scope",
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(
        Forbidden,
        NotFound,
        why={Invalid: "bad setup", Conflict: "another person's scope still records"} | WORKER_GONE,
    ),
)
def scope_arm(
    req: ScopeSetupModel, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> ScopeStatus:
    """Arm (or start rolling) with this setup; the pre-trigger fills from recent history.
    The scope is then the actor's: another person's scope that still records is refused
    (409) unless taken over (`take_over`: the control holder, instructors, admins; its
    viewers are told)."""
    taken = scope.arm(machine, req, actor)
    if taken is not None:
        what = f"took over the scope from {taken}"
        services.audit.record_later(Entry(actor.name, actor.session, "trace", what, machine.id))
    return scope.status(machine, services.traces, services.recorders)


@router.post(
    "/machines/{mid}/scope/force",
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(
        Forbidden, NotFound, why={Conflict: "another person's scope"} | WORKER_GONE
    ),
)
def scope_force(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> ScopeStatus:
    """Trigger now (an armed scope only; another person's as for arming)."""
    scope.force(machine, actor)
    return scope.status(machine, services.traces, services.recorders)


@router.post(
    "/machines/{mid}/scope/stop",
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(
        Forbidden, NotFound, why={Conflict: "another person's scope"} | WORKER_GONE
    ),
)
def scope_stop(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> ScopeStatus:
    """Stop recording (one's own scope; another person's as for arming)."""
    scope.stop(machine, actor)
    return scope.status(machine, services.traces, services.recorders)


@router.get(
    "/machines/{mid}/scope/roll",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=BINARY | responses(NotFound, Conflict, Invalid, why=WORKER_GONE),
)
def scope_roll(
    machine: MachineDep,
    max_points: Annotated[int, Query(ge=100, le=200_000)] = 5000,
) -> Response:
    """The newest record length of a running scope (every stride-th cycle)."""
    return Response(scope.roll_frame(machine, max_points), media_type="application/octet-stream")


@router.post(
    "/machines/{mid}/recording",
    status_code=CREATED,
    dependencies=[permit(Action.RECORD)],
    responses=responses(
        Forbidden,
        NotFound,
        Conflict,
        Invalid,
        why={QuotaUsedUp: "the recordings' disk quota is used up"},
    ),
)
def recording_start(
    req: RecordingStart, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> RecordingInfo:
    """Record these signals every cycle into a Rerun .rrd until stopped (or until the
    recordings' disk quota is reached)."""
    info = services.recorders.begin(machine, req.signals)
    services.audit.record_later(
        Entry(
            actor.name,
            actor.session,
            "recording",
            f"started recording {info.id}",
            machine.id,
            {"signals": req.signals},
        )
    )
    return info


@router.delete(
    "/machines/{mid}/recording",
    dependencies=[permit(Action.RECORD)],
    responses=responses(Forbidden, NotFound, Conflict),
)
def recording_stop(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> RecordingInfo:
    info = services.recorders.end(machine.id)
    services.audit.record_later(
        Entry(actor.name, actor.session, "recording", f"stopped recording {info.id}", machine.id)
    )
    return info


@router.get(
    "/recordings/{rid}/recording.rrd",
    response_class=StreamingResponse,
    dependencies=[permit(Action.OBSERVE)],
    responses=BINARY | responses(NotFound),
)
def recording_rrd(rid: str, services: ServicesDep, actor: ActorDep) -> StreamingResponse:
    """The recording as a Rerun .rrd file (so far, while it runs); a class's student gets
    their seat's only (others: 404)."""
    path = services.recorders.path(rid, actor.seat)
    # a running recording grows while it is sent: send the bytes there are now, no more
    # (a file response would read on to the new end and overrun its Content-Length)
    size = path.stat().st_size
    return StreamingResponse(
        _first_bytes(path, size),
        media_type="application/octet-stream",
        headers={
            "Content-Length": str(size),
            "Content-Disposition": f'attachment; filename="{rid}.rrd"',
        },
    )


def _first_bytes(path: Path, size: int, chunk: int = 1 << 16) -> Iterator[bytes]:
    with path.open("rb") as f:
        while size > 0:
            data = f.read(min(chunk, size))
            if not data:
                return
            size -= len(data)
            yield data


@router.get(
    "/recordings/{rid}/viewer",
    response_class=RedirectResponse,
    status_code=TEMPORARY_REDIRECT,
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(NotFound),
)
def recording_viewer(
    rid: str, request: Request, services: ServicesDep, actor: ActorDep
) -> RedirectResponse:
    """Open the recording in the bundled Rerun web viewer. Its loader fetches the .rrd
    without the session cookie, so the URL carries a ticket for that one request."""
    services.recorders.path(rid, actor.seat)
    path = f"/api/recordings/{rid}/recording.rrd"
    ticket = services.accounts.issue_ticket(actor, path)
    return RedirectResponse(viewer_url(request, f"{path}?ticket={ticket}"))
