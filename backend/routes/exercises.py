"""Exercises: the shipped and uploaded ones, authoring (an exercise file checked and run
untouched on a copy before it is saved), their files, removing an uploaded one."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Response

from api.auth import Action
from api.classes import ExerciseInfo, ExerciseUpload
from api.exercises import DryCheck, DryJobError, DryRunRequest, ExerciseDryRun
from backend.bodies import EXERCISE_BODY_BYTES, text_answer
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import (
    CREATED,
    NO_CONTENT,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    TimedOut,
    TooLarge,
    responses,
)
from backend.services.classes import Classes
from backend.services.exercises import exercise_info
from nc_sim.training.dry_run import DryRun
from nc_sim.training.exercise import Exercise
from nc_sim.training.variation import seat_seed

router = APIRouter(prefix="/api", tags=["training"])

ExerciseId = Annotated[
    str, Path(pattern=r"^[a-z0-9][a-z0-9-]{0,63}$", description="an exercise's id")
]
DRY_CLASS = "dry-run"  # the class name a dry run draws seat 1's numbers for


@router.get("/exercises", dependencies=[permit(Action.TEACH)], responses=responses(Forbidden))
def list_exercises(services: ServicesDep) -> list[ExerciseInfo]:
    """Shipped and uploaded exercises, with every hint's text (instructors)."""
    return services.exercises.list()


@router.post(
    "/exercises",
    status_code=CREATED,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, Conflict, TooLarge, Invalid),
    max_body_size=EXERCISE_BODY_BYTES,
)
def upload_exercise(req: ExerciseUpload, services: ServicesDep, actor: ActorDep) -> ExerciseInfo:
    """Add an exercise file (TOML, the format of `exercises/`), or replace an uploaded one of
    the same id (classes that ran it keep their copy); a wrong file is refused with the key,
    value or line and column that is wrong."""
    info = services.exercises.upload(req.text, actor.name)
    services.audit.record(Classes.entry(actor, f"uploaded exercise '{info.id}'"))
    return info


@router.post(
    "/exercises/dry-run",
    dependencies=[permit(Action.TEACH)],
    responses=responses(
        Forbidden,
        TooLarge,
        Invalid,
        TimedOut,
        why={Invalid: "the file is wrong (its key, value, or line and column)"},
    ),
    max_body_size=EXERCISE_BODY_BYTES,
)
async def dry_run(req: DryRunRequest, services: ServicesDep) -> ExerciseDryRun:
    """Check an exercise file as an upload would, then run seat 1 of a class (its numbers
    drawn) untouched on a copy for `seconds` of simulated time, its checks judged as a
    seat's worker judges them. Nothing is saved. The warnings say what would make a poor
    exercise: a check that passes with nobody at the machine gives its points away."""
    ex = services.exercises.check(req.text, "the file")
    seat, values = ex.for_seat(seat_seed(DRY_CLASS, ex.id), 1)
    ran = await services.assistants.dry_run(seat, req.seconds)
    return ExerciseDryRun(
        info=exercise_info(ex, "dry run"),
        seconds=ran.seconds,
        values=values,
        checks=_checks(ex, ran),
        job_errors=[DryJobError(code=c, message=m, t_s=round(t, 3)) for c, m, t in ran.job_errors],
        warnings=_warnings(ex, ran),
    )


def _checks(ex: Exercise, ran: DryRun) -> list[DryCheck]:
    by_id = {k.id: k for k in ex.checks}
    start = ran.start_cycle
    return [
        DryCheck(
            id=r.id,
            text=by_id[r.id].text,
            points=by_id[r.id].points,
            passed=r.passed,
            first_passed_s=None
            if r.first_passed_cycle is None
            else round((r.first_passed_cycle - start) * ran.cycle_s, 3),
            detail=r.detail,
        )
        for r in ran.checks
    ]


def _warnings(ex: Exercise, ran: DryRun) -> list[str]:
    """What would make the exercise a poor one, as the dry run shows it."""
    out = [
        f"check '{r.id}' passes with nobody at the machine: it gives its points away"
        for r in ran.checks
        if r.first_passed_cycle is not None
    ]
    if not ex.faults and not ex.start:
        out.append(
            "it injects no fault and starts no parameter value: the seat is the template, "
            "sound, with nothing to find"
        )
    judged = {r.id for r in ran.checks}
    out += [
        f"check '{k.id}' is answered by the student (a finding): not run here"
        for k in ex.checks
        if k.id not in judged
    ]
    if not ex.hints:
        out.append("it has no hints: a student who is stuck can only raise their hand")
    return out


@router.get(
    "/exercises/{eid}/text",
    response_class=Response,
    dependencies=[permit(Action.TEACH)],
    responses=text_answer("application/toml", "the exercise file") | responses(Forbidden, NotFound),
)
def exercise_text(eid: ExerciseId, services: ServicesDep) -> Response:
    """An exercise's file (TOML) as shipped or uploaded: to edit a copy of it."""
    return Response(services.exercises.text(eid), media_type="application/toml")


@router.delete(
    "/exercises/{eid}",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, Conflict, why={Conflict: "a shipped exercise"}),
)
def remove_exercise(eid: ExerciseId, services: ServicesDep, actor: ActorDep) -> None:
    """Forget an uploaded exercise (classes that ran it keep their copy of it)."""
    services.exercises.remove(eid)
    services.audit.record(Classes.entry(actor, f"removed exercise '{eid}'"))
