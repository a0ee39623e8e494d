"""The trainer's roster: students as people across classes (a seat's login stays per class;
a roster student's seats in every class are theirs), each with their history."""

from __future__ import annotations

from pydantic import BaseModel, Field

from api.classes import StageResult

MAX_ROSTER = 5000  # people on one service's roster


class RosterStudent(BaseModel):
    """A student of the roster, as listed."""

    id: int
    name: str
    classes: int = Field(description="classes they had a seat in")
    last_unix: float | None = Field(description="when their newest class began")
    created_unix: float
    by: str = Field(description="the instructor who put them on the roster")


class StudentSession(BaseModel):
    """One class a roster student sat in: their results in its lesson plan."""

    class_id: str
    title: str
    instructor: str
    seat: int
    created_unix: float
    ended_unix: float | None
    stages: list[StageResult] = Field(description="each exercise of the plan they reached")
    score: float
    max_points: float = Field(description="over the whole plan")


class StudentRecord(BaseModel):
    """A roster student with every class they sat in, newest first."""

    student: RosterStudent
    sessions: list[StudentSession]
