"""The trainer's roster: students as people across classes, each with their history."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path

from api.auth import Action
from api.roster import RosterStudent, StudentRecord
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import NO_CONTENT, Forbidden, NotFound, responses
from backend.services.classes import Classes

router = APIRouter(prefix="/api/roster", tags=["training"])

StudentId = Annotated[int, Path(ge=1, le=2**53, description="a roster student's id")]


@router.get("", dependencies=[permit(Action.TEACH)], responses=responses(Forbidden))
def roster(services: ServicesDep) -> list[RosterStudent]:
    """Every student of the roster by name: how many classes they sat in, the newest."""
    return services.roster.people()


@router.get("/{pid}", dependencies=[permit(Action.TEACH)], responses=responses(Forbidden, NotFound))
def student_record(pid: StudentId, services: ServicesDep) -> StudentRecord:
    """A student's classes, newest first, with their results in each exercise reached."""
    return services.roster.record(pid)


@router.delete(
    "/{pid}",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound),
)
def forget_student(pid: StudentId, services: ServicesDep, actor: ActorDep) -> None:
    """Take a student off the roster: their seats' results stay with their classes, under
    the name the seat had."""
    name = services.roster.record(pid).student.name
    services.roster.forget(pid)
    services.audit.record(Classes.entry(actor, f"took {name} off the roster"))
