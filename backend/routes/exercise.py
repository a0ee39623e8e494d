"""The exercise of a class's seat, as its student works on it: task, checks, hints, score."""

from __future__ import annotations

from fastapi import APIRouter

from api.auth import Action
from api.classes import (
    AnswerGiven,
    Exercise,
    FindingAnswer,
    HandRequest,
    HintInfo,
    HintTake,
    RaisedHand,
)
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import Conflict, Forbidden, Invalid, NotFound, responses
from backend.services import lesson_plan
from backend.services.classes import Classes
from backend.services.exercises import exercise_info, hint_infos
from nc_sim.training.findings import say, unit_of

router = APIRouter(prefix="/api/machines/{mid}/exercise", tags=["training"])


@router.get("", dependencies=[permit(Action.EXERCISE)], responses=responses(Forbidden, NotFound))
def my_exercise(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> Exercise:
    """The exercise of the seat this machine is (404 when it is none): the task, every
    check as it stands on the live machine, the hints (their text once taken), the score;
    whether the asker may take hints (the seat's student only)."""
    c, seat = services.classes.seat_by_machine(machine.id)
    progress, score = services.classes.score(seat)
    info = exercise_info(seat.exercise, "class", seat.hints)
    return Exercise(
        class_id=c.id,
        seat=seat.n,
        student=seat.student,
        user=seat.user,
        takes_hints=actor.name == seat.user,
        exercise=info.model_copy(update={"faults": 0}),  # the student's to find
        checks=services.classes.checks(c, seat),
        hints=hint_infos(seat.exercise, seat.hints),
        score=score,
        progress=progress,
        seat_time_s=seat.seat_time_s,
        frozen=seat.frozen,
        hand=seat.hand,
        stage=seat.stage,
        plan=[ex.title for ex in c.plan],
        done=seat.done,
        may_move_on=lesson_plan.may_move_on(actor, c, seat) is None,
    )


@router.post(
    "/next",
    dependencies=[permit(Action.EXERCISE)],
    responses=responses(
        Forbidden,
        NotFound,
        Conflict,
        why={
            Forbidden: "neither the seat's student nor an instructor",
            Conflict: "a check has not passed yet (a student), the last exercise of the plan, "
            "or the class ended",
        },
    ),
)
def move_on(machine: MachineDep, services: ServicesDep, actor: ActorDep) -> Exercise:
    """Move the seat on to its lesson plan's next exercise: its student once every check has
    passed (the instructor at any time). Its result in this one is kept; the machine powers
    on afresh for the next (its starting values, faults and checks), its clock from 0."""
    c, seat = services.classes.seat_by_machine(machine.id)
    if lesson_plan.may_move_on(actor, c, seat) is None:
        services.console.record_last(c, [seat])
    lesson_plan.move_on(services.classes, actor, c, [seat])
    return my_exercise(machine, services, actor)


@router.post(
    "/hand",
    dependencies=[permit(Action.EXERCISE)],
    responses=responses(
        Forbidden,
        NotFound,
        Conflict,
        why={Forbidden: "raised by another than the seat's student", Conflict: "the class ended"},
    ),
)
def hand(
    req: HandRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> RaisedHand | None:
    """The student raises their hand (the instructor's grid shows it, with its words) or
    lowers it; an instructor lowers it once seen to. Both are in the seat's history."""
    c, seat = services.classes.seat_by_machine(machine.id)
    raised = services.classes.hand(actor, seat, c, req)
    what = f"raised hand: {req.text}" if req.raised else "lowered hand"
    services.audit.record(Classes.entry(actor, what.rstrip(": "), machine.id))
    return raised


@router.post(
    "/hints",
    dependencies=[permit(Action.EXERCISE)],
    responses=responses(Forbidden, NotFound, why={Forbidden: "not the seat's own student"}),
)
def take_hint(
    req: HintTake, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> HintInfo:
    """Take a hint: its text, and its cost comes off the score (once). Only the seat's own
    student takes its hints (anyone else: 403)."""
    c, seat = services.classes.seat_by_machine(machine.id)
    text = services.classes.take_hint(actor, seat, c, req.n)
    ex = seat.exercise
    services.audit.record(
        Classes.entry(actor, f"took hint {req.n} of exercise '{ex.id}'", machine.id)
    )
    return HintInfo(n=req.n, cost=ex.hints[req.n - 1].cost, text=text)


@router.post(
    "/findings",
    dependencies=[permit(Action.EXERCISE)],
    responses=responses(
        Forbidden,
        NotFound,
        Conflict,
        Invalid,
        why={
            Forbidden: "not the seat's own student",
            Conflict: "the attempts are used, the finding is already right, or the class ended",
            Invalid: "not a finding check, or an axis the machine lacks",
        },
    ),
)
def answer_finding(
    req: FindingAnswer, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> AnswerGiven:
    """Answer a finding check (which axis carries the hidden fault, and how large it is):
    graded at once and kept with the seat; each answer uses one of the check's attempts."""
    c, seat = services.classes.seat_by_machine(machine.id)
    given = services.classes.answer(actor, seat, c, req)
    services.audit.record(
        Classes.entry(
            actor,
            f"answered finding '{req.check}' of exercise '{seat.exercise.id}':"
            f" {req.axis} {say(req.value, unit_of(c.seat_machine(seat), req.axis))}"
            f" ({'right' if given.passed else 'wrong'})",
            machine.id,
        )
    )
    return given
