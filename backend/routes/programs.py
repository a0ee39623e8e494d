"""NC programs: the stored ones (list, read, write, delete) and a program's preview on a
machine (its first error and its commanded tool path)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Request, Response
from fastapi.concurrency import run_in_threadpool

from api.auth import Action
from api.commands import ProgramName
from api.programs import Program, ProgramInfo, ProgramPreview, ProgramText
from backend.bodies import PROGRAM_BODY_BYTES, json_body, read_model
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import (
    NO_CONTENT,
    WORKER_GONE,
    Forbidden,
    Invalid,
    NotFound,
    TooLarge,
    responses,
)
from backend.services import programs
from backend.workers.protocol import ReadStatus, StatusRead

router = APIRouter(tags=["programs"])
NameDep = Annotated[ProgramName, Path()]
BODY = json_body(ProgramText, PROGRAM_BODY_BYTES)


@router.get("/api/programs", dependencies=[permit(Action.OBSERVE)])
def list_programs(services: ServicesDep, actor: ActorDep) -> list[ProgramInfo]:
    """Every stored program (without its text), by name; a class's student: their seat's own
    and the service-wide ones."""
    return programs.listed(services.store, actor)


@router.get(
    "/api/programs/{name}",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound, Invalid),
)
def read_program(name: NameDep, services: ServicesDep, actor: ActorDep) -> Program:
    """A stored program with its text (names match regardless of case; a student's own
    first)."""
    return programs.program_of(programs.get(services.store, actor, name))


@router.put(
    "/api/programs/{name}",
    dependencies=[permit(Action.PROGRAMS)],
    responses=responses(Forbidden, TooLarge, Invalid),
    openapi_extra=BODY,
    max_body_size=PROGRAM_BODY_BYTES,
)
async def write_program(
    name: NameDep, request: Request, services: ServicesDep, actor: ActorDep
) -> ProgramInfo:
    """Create or replace a program (body `{text}`); audited. It is stored as written, errors
    and all: the preview and `program_load` check it."""
    body = await read_model(request, ProgramText, "program")
    return await run_in_threadpool(programs.put, services.store, actor, name, body.text)


@router.delete(
    "/api/programs/{name}",
    status_code=NO_CONTENT,
    response_class=Response,
    dependencies=[permit(Action.PROGRAMS)],
    responses=responses(Forbidden, NotFound, Invalid),
)
def delete_program(name: NameDep, services: ServicesDep, actor: ActorDep) -> Response:
    """Delete a stored program; audited."""
    programs.delete(services.store, actor, name)
    return Response(status_code=NO_CONTENT)


@router.post(
    "/api/machines/{mid}/program-preview",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound, TooLarge, Invalid, why=WORKER_GONE),
    openapi_extra=BODY,
    max_body_size=PROGRAM_BODY_BYTES,
)
async def program_preview(request: Request, machine: MachineDep) -> ProgramPreview:
    """Check a program on this machine and draw it: its first error (line, column, job
    error) and the commanded tool path up to there, from the machine's commanded positions,
    in the plane the program selects (else G17, or G18 on a lathe). Changes nothing."""
    body = await read_model(request, ProgramText, "program")
    read = await machine.link.acall(ReadStatus(machine.id))
    assert isinstance(read, StatusRead)
    return await programs.program_preview_off_loop(read.snapshot, body.text)
