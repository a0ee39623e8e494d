"""A machine's history: filtered pages, the export (CSV or JSON), notes and acknowledgements."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, Query, Response

from api.auth import Action
from api.history import HistoryEntry, HistoryKind, HistoryPage, NoteCreate, Severity
from backend.bodies import dated_download
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import CREATED, OK, Conflict, NotFound, responses
from backend.services.machine_log import EXPORT_ROWS, MAX_PAGE, HistoryFilter, csv_text

router = APIRouter(prefix="/api/machines", tags=["history"])

Limit = Annotated[int, Query(ge=1, le=MAX_PAGE)]
# an entry's id as a page cursor: 'a<seq>' or 'h<row>'
EntryId = Annotated[str | None, Query(pattern=r"^[ah][0-9]{1,15}$")]


def _filter(
    kind: Annotated[list[HistoryKind] | None, Query(max_length=32)] = None,
    severity: Annotated[list[Severity] | None, Query(max_length=3)] = None,
    actor: Annotated[str | None, Query(max_length=200, description="part of a user name")] = None,
    since_unix: Annotated[float | None, Query(ge=0, le=1e11)] = None,
    until_unix: Annotated[float | None, Query(ge=0, le=1e11)] = None,
    text: Annotated[
        str | None, Query(max_length=200, description="in the text, outcome or cause")
    ] = None,
) -> HistoryFilter:
    return HistoryFilter(
        tuple(kind or ()), tuple(severity or ()), actor, since_unix, until_unix, text
    )


FilterDep = Annotated[HistoryFilter, Depends(_filter)]
EXPORT_ANSWER: dict[int | str, Any] = {
    OK: {
        "description": "the matching entries, oldest first: CSV, or a JSON list of entries",
        "content": {
            "text/csv": {"schema": {"type": "string"}},
            "application/json": {
                "schema": {"type": "array", "items": {"$ref": "#/components/schemas/HistoryEntry"}}
            },
        },
    }
}


@router.get("/{mid}/history", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound))
def history(
    machine: MachineDep,
    services: ServicesDep,
    f: FilterDep,
    limit: Limit = 200,
    before_unix: Annotated[float | None, Query(ge=0, le=1e11)] = None,
    before_id: EntryId = None,
) -> HistoryPage:
    """The machine's history, newest first: job errors (with the command that raised them),
    events, commands and their outcomes, parameter and control changes, power-ons, service
    starts and stops, notes. Older pages: `before_unix` and `before_id` of the last entry."""
    before = (before_unix, before_id) if before_unix is not None and before_id else None
    rows, total = services.history.page(machine.id, f, limit, before)
    return HistoryPage(rows=rows, total=total)


@router.get(
    "/{mid}/history/export",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=EXPORT_ANSWER | responses(NotFound),
)
def export(
    machine: MachineDep,
    services: ServicesDep,
    f: FilterDep,
    format: Literal["csv", "json"] = "csv",
) -> Response:
    """The matching entries (at most the newest 100 000), oldest first, as a file named
    after the machine and the time of the export."""
    rows, _ = services.history.page(machine.id, f, EXPORT_ROWS)
    rows.reverse()
    if format == "csv":
        body, media = csv_text(rows), "text/csv"
    else:
        body = "[" + ",\n".join(r.model_dump_json() for r in rows) + "]\n"
        media = "application/json"
    return dated_download(body, media, machine.name or machine.id, "history", format)


@router.post(
    "/{mid}/history/notes",
    status_code=CREATED,
    dependencies=[permit(Action.NOTE)],
    responses=responses(NotFound),
)
def note(
    req: NoteCreate, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> HistoryEntry:
    """A logbook entry ('replaced the encoder cable of X'): into the machine's history at the
    machine's time now, shown on every viewer's timeline."""
    return services.history.note(machine, actor.name, req.text.strip() or req.text)


@router.post(
    "/{mid}/history/acknowledge",
    status_code=CREATED,
    dependencies=[permit(Action.NOTE)],
    responses=responses(NotFound, why={Conflict: "no job error is in force"}),
)
def acknowledge(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> HistoryEntry:
    """Acknowledge the job errors in force: who saw them, and when, goes into the history
    (they stay in force until a reset)."""
    return services.history.acknowledge(machine, actor.name)
