"""A class's results for its grade list: each seat's score, check by check, as
nc_sim/training/score.py weighs them (the rendering: backend/report/grades.py)."""

from __future__ import annotations

from backend.report.grades import CheckResultRow, ClassResults, SeatResultRow
from backend.services.classes import Class
from nc_sim.training.score import score as exercise_score


def results(c: Class) -> ClassResults:
    """The class's results as its seats stand now (an ended class's: at its end)."""
    seats = []
    for seat in c.seats:
        s = exercise_score(c.exercise, seat.first_passed_s, [n - 1 for n in seat.hints])
        checks = tuple(CheckResultRow(k.id, k.points, k.earned, k.passed_after_s) for k in s.checks)
        seats.append(
            SeatResultRow(
                seat.n,
                seat.student,
                seat.user,
                seat.joined_unix,
                seat.seat_time_s,
                checks,
                len(seat.hints),
                s.hint_cost,
                s.points,
                s.max_points,
            )
        )
    return ClassResults(
        c.id,
        c.title,
        c.exercise.id,
        c.exercise.title,
        c.instructor,
        c.created_unix,
        c.ended_unix,
        tuple((k.id, k.text) for k in c.exercise.checks),
        tuple(seats),
    )
