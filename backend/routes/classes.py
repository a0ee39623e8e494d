"""Training: classes and their seats, the instructor's console (grid websocket)."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastapi import APIRouter, Path, Query, Request, Response, WebSocket, WebSocketDisconnect
from fastapi.concurrency import run_in_threadpool

from api.auth import SESSION_COOKIE, Action
from api.classes import (
    CLASS_ID,
    LINK_HOURS_MAX,
    MAX_PLAN,
    Broadcast,
    ClassCreate,
    ClassCreated,
    ClassFault,
    ClassInfo,
    Freeze,
    Present,
    SeatDetail,
    SeatFaults,
    SeatLink,
    SeatResult,
    SeatSelection,
    SnapshotInfo,
)
from api.history import HistoryEntry, HistoryPage
from api.replay import SeatReplay
from backend.bodies import LISTS_BODY_BYTES, dated_download, text_answer
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import (
    CREATED,
    NO_CONTENT,
    OK,
    WORKER_GONE,
    ApiError,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    TooLarge,
    Unavailable,
    Why,
    not_found,
    responses,
)
from backend.report import grades
from backend.report.pdf import html_to_pdf
from backend.routes.history import EntryId, FilterDep, Limit
from backend.services import class_results, lesson_plan, training
from backend.services.classes import Classes
from backend.services.exercises import hint_infos
from backend.services.seats import Seat

router = APIRouter(prefix="/api", tags=["training"])

ClassId = Annotated[str, Path(pattern=CLASS_ID, description="a class's id")]
SeatNo = Annotated[int, Path(ge=1, le=60, description="seat number from 1")]
_RUNNING: Why = {Conflict: "the class has ended"}


@router.get("/classes", dependencies=[permit(Action.TEACH)], responses=responses(Forbidden))
def list_classes(services: ServicesDep) -> list[ClassInfo]:
    """Every class, running and ended, newest first."""
    return [services.classes.info(c) for c in services.classes.all()]


@router.post(
    "/classes",
    status_code=CREATED,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, Conflict, TooLarge, Invalid, why=WORKER_GONE),
    max_body_size=LISTS_BODY_BYTES,  # the seats' machines may come from uploaded lists
)
def create_class(
    req: ClassCreate, request: Request, services: ServicesDep, actor: ActorDep
) -> ClassCreated:
    """A class of seats: a login and a machine each at the lesson plan's first exercise
    (its template, starting values and faults with each seat's own numbers; its checks
    running). The answer has each seat's one-time login link (shown this once; a new one:
    POST .../seats/{n}/link)."""
    created = services.classes.create(actor, req, str(request.base_url))
    if req.roster:
        services.roster.enrol(services.classes.get(req.id), actor.name)
    plan = ", ".join(f"'{e}'" for e in req.exercises)
    services.audit.record(
        Classes.entry(
            actor,
            f"created class '{req.id}' ({req.seats} seats, exercises {plan})",
            seats=req.seats,
            exercises=req.exercises,
        )
    )
    return created


@router.get(
    "/classes/{cid}", dependencies=[permit(Action.TEACH)], responses=responses(Forbidden, NotFound)
)
def get_class(cid: ClassId, services: ServicesDep) -> ClassInfo:
    return services.classes.info(services.classes.get(cid))


@router.post(
    "/classes/{cid}/end",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, why=_RUNNING),
)
def end_class(cid: ClassId, services: ServicesDep, actor: ActorDep) -> ClassInfo:
    """End the class: its machines and logins go; its record, results, injected faults,
    traces and audit stay for the debrief. Each student's page shows their result
    (GET /api/auth/seat-result)."""
    c = services.classes.get(cid)
    if c.ended_unix is None:
        services.console.record_last(c, c.seats)
    services.classes.end(c)
    services.console.recorder.flush(cid)
    services.sessions.poke()  # the students' websockets close now
    services.console.unwatch(c)  # its machines' snapshots and faults went with them
    services.audit.record(Classes.entry(actor, f"ended class '{cid}'"))
    return services.classes.info(c)


@router.delete(
    "/classes/{cid}",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, Conflict, why={Conflict: "the class still runs"}),
)
def delete_class(cid: ClassId, services: ServicesDep, actor: ActorDep) -> None:
    """Forget an ended class: its record, results and its students' result pages go, and its
    id can be used again. Its seats' histories and traces stay until their retention ends
    them; the audit keeps that it was deleted. 409 while it runs (end it first)."""
    services.classes.delete(services.classes.get(cid))
    services.console.recorder.forget(cid)
    services.roster.drop_class(cid)
    services.audit.record(Classes.entry(actor, f"deleted class '{cid}'"))


@router.post(
    "/classes/{cid}/freeze",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, why=_RUNNING | WORKER_GONE),
)
def freeze(cid: ClassId, req: Freeze, services: ServicesDep, actor: ActorDep) -> ClassInfo:
    """Freeze (pause) or resume seats' machines; a student cannot resume a frozen seat."""
    c = services.classes.running(cid)
    seats = services.classes.select(c, req.seats)
    services.classes.freeze(seats, req.frozen, actor.name)
    what = "froze" if req.frozen else "resumed"
    for seat in seats:  # each in its seat's history, for the debrief
        what_seat = f"{what} seat {seat.n} of class '{cid}'"
        services.audit.record(Classes.entry(actor, what_seat, seat.machine))
    return services.classes.info(c)


@router.post(
    "/classes/{cid}/next",
    dependencies=[permit(Action.TEACH)],
    responses=responses(
        Forbidden,
        NotFound,
        why=WORKER_GONE
        | {Conflict: "the class ended, or a seat is at the plan's last exercise (none moves)"},
    ),
)
def move_on(cid: ClassId, req: SeatSelection, services: ServicesDep, actor: ActorDep) -> ClassInfo:
    """Move the selected seats (all when none are named) on to the lesson plan's next
    exercise: each one's result in its exercise kept, its machine powered on afresh for the
    next one, its clock from 0."""
    c = services.classes.running(cid)
    seats = services.classes.select(c, req.seats)
    services.console.record_last(c, seats)
    lesson_plan.move_on(services.classes, actor, c, seats)
    return services.classes.info(c)


@router.post(
    "/classes/{cid}/present",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, why=_RUNNING),
)
def present(cid: ClassId, req: Present, services: ServicesDep, actor: ActorDep) -> ClassInfo:
    """Show a machine (the instructor's, say) to every seat of the class: its students see
    it in their machine list and watch it read-only (no control, no command, no parameter
    write) until it stops (`machine`: null). Each seat is told."""
    c = services.classes.running(cid)
    services.classes.present(actor, c, req.machine)
    what = f"presents {req.machine} to" if req.machine else "stopped presenting to"
    services.audit.record(Classes.entry(actor, f"{what} class '{cid}'", req.machine or ""))
    return services.classes.info(c)


@router.post(
    "/classes/{cid}/broadcast",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, why=_RUNNING),
)
def broadcast(cid: ClassId, req: Broadcast, services: ServicesDep, actor: ActorDep) -> None:
    """A message every selected seat's HMI shows as a banner."""
    c = services.classes.running(cid)
    seats = services.classes.select(c, req.seats)
    services.classes.broadcast(seats, req.text, actor.name)
    for seat in seats:
        said = f"message to seat {seat.n} of class '{cid}': {req.text}"
        services.audit.record(Classes.entry(actor, said, seat.machine))


@router.post(
    "/classes/{cid}/faults",
    status_code=CREATED,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, Invalid, why=_RUNNING | WORKER_GONE),
)
def inject_class(
    cid: ClassId, req: ClassFault, services: ServicesDep, actor: ActorDep
) -> list[SeatFaults]:
    """Inject a fault into the selected seats (all when none are named)."""
    c = services.classes.running(cid)
    return services.classes.inject(services.classes.select(c, req.seats), req.inject, actor)


@router.get(
    "/classes/{cid}/seats/{n}",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound),
)
def seat_detail(cid: ClassId, n: SeatNo, services: ServicesDep) -> SeatDetail:
    """A seat's checks, hints and faults (for the console and the debrief: an ended
    class's as they stood at its end)."""
    c = services.classes.get(cid)
    seat = services.classes.seat(cid, n)
    ended = c.ended_unix is not None
    m = services.classes.proxy(seat) if not ended else None
    return SeatDetail(
        info=services.classes.seat_info(c, seat),
        checks=services.classes.checks(c, seat),
        hints=hint_infos(seat.exercise, seat.hints),
        faults=seat.faults if ended else training.faults_of(m) if m is not None else [],
        ended=ended,
        values=seat.values,
    )


@router.get("/auth/seat-result", responses=responses(NotFound))
def seat_result(request: Request, services: ServicesDep) -> SeatResult:
    """The final result of the class seat this browser was logged in to, once the class
    has ended and its login has gone (open: the ended session's cookie names the seat,
    until the session would have expired or its student logs out); 404 for any other."""
    sid = request.cookies.get(SESSION_COOKIE, "")
    result = services.classes.result_of(sid) if sid else None
    if result is None:
        raise NotFound("this browser's session was no seat of an ended class")
    return result


@router.get(
    "/classes/{cid}/seats/{n}/history",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound),
)
def seat_history(
    cid: ClassId,
    n: SeatNo,
    services: ServicesDep,
    f: FilterDep,
    limit: Limit = 200,
    before_unix: Annotated[float | None, Query(ge=0, le=1e11)] = None,
    before_id: EntryId = None,
) -> HistoryPage:
    """What happened on the seat's machine, newest first: job errors (with the command that
    raised them), commands, parameters, faults, hints, freezes and messages, power-ons; for
    the debrief, also once the class has ended and its machine is gone."""
    seat = services.classes.seat(cid, n)
    before = (before_unix, before_id) if before_unix is not None and before_id else None
    rows, total = services.history.page(seat.machine, f, limit, before)
    return HistoryPage(rows=[_named(seat, r) for r in rows], total=total)


def _named(seat: Seat, e: HistoryEntry) -> HistoryEntry:
    """An entry of the seat's student by their name, not the seat's login."""
    return e.model_copy(update={"actor": seat.student}) if e.actor == seat.user else e


@router.get(
    "/classes/{cid}/seats/{n}/replay",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound),
)
def seat_replay(
    cid: ClassId,
    n: SeatNo,
    services: ServicesDep,
    stage: Annotated[int | None, Query(ge=0, lt=MAX_PLAN)] = None,
) -> SeatReplay:
    """The seat's session in one exercise of the plan (its current one by default): its
    machine's main signals once a second of its clock, and what happened (commands, job
    errors, parameters, hints, faults, freezes, messages) placed on the same clock, to play
    back in the debrief."""
    c = services.classes.get(cid)
    seat = services.classes.seat(cid, n)
    k = seat.stage if stage is None else stage
    if k > seat.stage:
        raise not_found(f"exercise {k + 1} of seat {n} (it reached {seat.stage + 1})")
    title = c.plan[k].title
    replay = services.console.recorder.replay(cid, n, k, title, seat.machine)
    for mark in replay.marks:
        mark.entry = _named(seat, mark.entry)
    return replay


@router.post(
    "/classes/{cid}/seats/{n}/reset",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, why=_RUNNING | WORKER_GONE),
)
def reset_seat(cid: ClassId, n: SeatNo, services: ServicesDep, actor: ActorDep) -> SnapshotInfo:
    """Put the seat's machine back to the exercise's start (the snapshot taken when it was
    built): its lists, state and faults as then. Its record (checks passed, hints, seat
    time) stays; the reset is in its history."""
    services.classes.running(cid)
    seat = services.classes.seat(cid, n)
    m = services.machines.get(seat.machine)
    info = services.snapshots.restore(actor, m, services.snapshots.start_of(m.id))
    what = f"reset seat {n} of class '{cid}' to the exercise's start"
    services.audit.record(Classes.entry(actor, what, m.id))
    return info


@router.get(
    "/classes/{cid}/results.csv",
    response_class=Response,
    dependencies=[permit(Action.TEACH)],
    responses=text_answer("text/csv", "one line per seat") | responses(Forbidden, NotFound),
)
def results_csv(cid: ClassId, services: ServicesDep) -> Response:
    """The class's results: per seat who, when they joined, seat time, each check's points
    earned and first pass, hints, score of the maximum."""
    c = services.classes.get(cid)
    return dated_download(
        grades.to_csv(class_results.results(services.classes, c)),
        "text/csv",
        cid,
        "results",
        "csv",
    )


_GRADE_LIST: dict[int | str, Any] = {
    OK: {"content": {"application/pdf": {}}, "description": "the grade list"}
}


@router.get(
    "/classes/{cid}/results.pdf",
    response_class=Response,
    dependencies=[permit(Action.TEACH)],
    responses=_GRADE_LIST
    | responses(Forbidden, NotFound, why={Unavailable: "Chromium is missing or failed to print"}),
)
async def results_pdf(cid: ClassId, services: ServicesDep) -> Response:
    """The grade list to print (A4): every seat's points per check, hints, score; a line for
    the instructor's signature."""
    c = await run_in_threadpool(services.classes.get, cid)
    pdf = await html_to_pdf(
        grades.to_html(class_results.results(services.classes, c)), services.settings.chromium
    )
    return dated_download(pdf, "application/pdf", cid, "grade-list", "pdf")


@router.post(
    "/classes/{cid}/seats/{n}/link",
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, why=_RUNNING),
)
def seat_link(
    cid: ClassId,
    n: SeatNo,
    request: Request,
    services: ServicesDep,
    actor: ActorDep,
    hours: Annotated[float, Query(ge=0.25, le=LINK_HOURS_MAX, description="good for, h")] = 1.0,
) -> SeatLink:
    """A new one-time login link of a seat (good once, for `hours`). The seat's current
    session and its earlier links end: whoever has them is logged out."""
    services.classes.running(cid)
    seat = services.classes.seat(cid, n)
    link = services.classes.link(seat, str(request.base_url), hours)
    services.sessions.poke()  # the old session's websockets close now
    services.audit.record(Classes.entry(actor, f"login link for seat {n} of class '{cid}'"))
    return link


@router.websocket("/classes/{cid}/grid", dependencies=[permit(Action.TEACH)])
async def grid(ws: WebSocket, cid: ClassId, services: ServicesDep) -> None:
    """The console's grid: a `GridFrame` (JSON) a few times a second while the class runs.
    Nothing is read from the client."""
    try:
        await run_in_threadpool(services.classes.get, cid)
    except ApiError as e:
        await ws.close(code=4404, reason=str(e)[:120])
        return
    await ws.accept()
    console = services.console.open(cid)
    reader = asyncio.get_running_loop().create_task(_drain(ws))
    try:
        while not reader.done():
            getter = asyncio.ensure_future(console.mailbox.get())
            await asyncio.wait({getter, reader}, return_when=asyncio.FIRST_COMPLETED)
            if not getter.done():
                getter.cancel()
                break
            await ws.send_text(getter.result())
    except (WebSocketDisconnect, RuntimeError):
        pass
    finally:
        reader.cancel()
        services.console.close(console)


async def _drain(ws: WebSocket) -> None:
    """Read (and drop) what the client sends until it goes."""
    while True:
        msg = await ws.receive()
        if msg["type"] == "websocket.disconnect":
            return
