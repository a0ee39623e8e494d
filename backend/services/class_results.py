"""A class's results for its grade list: each seat's score in each exercise of the lesson
plan, check by check, as nc_sim/training/score.py weighs them (the rendering:
backend/report/grades.py)."""

from __future__ import annotations

from api.classes import StageResult
from backend.report.grades import (
    CheckResultRow,
    ClassResults,
    ExerciseColumns,
    SeatResultRow,
    StageRow,
)
from backend.services.classes import Classes
from backend.services.seats import Class


def _row(d: StageResult) -> StageRow:
    checks = tuple(CheckResultRow(k.id, k.points, k.earned, k.first_passed_s) for k in d.checks)
    return StageRow(
        d.exercise, d.seat_time_s, d.finished_s, checks, d.hints_taken, d.hint_cost, d.score
    )


def results(classes: Classes, c: Class) -> ClassResults:
    """The class's results as its seats stand now (an ended class's: at its end); an
    exercise a seat has not reached yet has no row."""
    seats = []
    for seat in c.seats:
        now = classes.stage_result(c, seat, "", c.ended_unix or 0.0)
        stages = tuple(_row(d) for d in [*seat.done, now])
        seats.append(SeatResultRow(seat.n, seat.student, seat.user, seat.joined_unix, stages))
    return ClassResults(
        c.id,
        c.title,
        c.instructor,
        c.created_unix,
        c.ended_unix,
        tuple(
            ExerciseColumns(
                ex.id, ex.title, ex.max_points, tuple((k.id, k.text) for k in ex.checks)
            )
            for ex in c.plan
        ),
        tuple(seats),
    )
