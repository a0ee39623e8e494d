"""Training: exercises, classes of seats (one simulated machine per student), the
instructor's console frames, snapshots of a machine."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from api.faults import FaultInfo, FaultInject
from api.machines import MachineLists

CLASS_ID = r"^[a-z0-9][a-z0-9-]{0,23}$"
MAX_SEATS = 60


class CheckInfo(BaseModel):
    """An objective check of an exercise, as the student reads it."""

    id: str
    text: str
    points: float


class HintInfo(BaseModel):
    """A hint: its cost; its text once taken."""

    n: int = Field(description="number from 1")
    cost: float = Field(description="points it costs")
    text: str | None = Field(None, description="null until the hint is taken")


class ExerciseInfo(BaseModel):
    """An exercise as listed (faults are the instructor's: `faults` counts them)."""

    id: str
    title: str
    summary: str
    task: str
    par_time_s: float = Field(description="time a good student needs (simulated s)")
    checks: list[CheckInfo]
    hints: list[HintInfo]
    faults: int = Field(description="faults it injects (shown to instructors only)")
    source: str = Field(description="shipped file or 'uploaded by <user>'")
    locked_assistants: list[str] = Field(description="assistants its student may not use")
    varied: list[str] = Field(
        description="the numbers each seat gets its own of, e.g. 'faults[0].factor' (seeded "
        "per class and seat: neighbours cannot copy)",
    )


class ExerciseUpload(BaseModel):
    """An exercise file (TOML) to add to the service's exercises."""

    text: str = Field(min_length=1, max_length=100_000)


LINK_HOURS_MAX = 72.0  # a seat's login link is good for at most three days
MAX_PLAN = 8  # exercises in one lesson plan


class ClassCreate(BaseModel):
    """A class: every seat gets its own machine, the demo lathe or one built from uploaded
    parameter lists (as POST /api/machines takes them), the exercise's starting values and
    faults in it."""

    model_config = ConfigDict(extra="forbid")

    id: str = Field(pattern=CLASS_ID, description="URL name; seat machines are <id>-s01 …")
    title: str = Field("", max_length=80)
    exercises: list[Annotated[str, Field(min_length=1, max_length=64)]] = Field(
        min_length=1,
        max_length=MAX_PLAN,
        description="the lesson plan: exercise ids in the order the seats work through them",
    )
    seats: int = Field(ge=1, le=MAX_SEATS)
    students: list[str] = Field(
        default_factory=list,
        max_length=MAX_SEATS,
        description="students' names, seat by seat (optional; shown in the console)",
    )
    lists: MachineLists | None = Field(
        None,
        description="the seats' machine template: these parameter lists; null for the demo "
        "lathe. The exercise's axes, spindles and gear stages must be in them (else 422)",
    )
    roster: bool = Field(
        False,
        description="the students' names are people of the roster: each found by name or "
        "added, their results gathered across classes (the logins stay per seat)",
    )
    link_hours: float = Field(
        1.0,
        ge=0.25,
        le=LINK_HOURS_MAX,
        description="how long the seats' login links stay good, h (prepared the day before: 24)",
    )

    @field_validator("exercises")
    @classmethod
    def _once_each(cls, v: list[str]) -> list[str]:
        twice = sorted({e for e in v if v.count(e) > 1})
        if twice:
            raise ValueError(f"each exercise once in a plan: {', '.join(twice)} is named twice")
        return v


class AnswerGiven(BaseModel):
    """One answer to a finding, as it was graded."""

    axis: str
    value: float = Field(description="the size named, in the axis' unit (mm | °)")
    passed: bool
    detail: str


class FindingState(BaseModel):
    """What a finding check asks of the student, and the answers given so far."""

    fault: str = Field(description="the kind of fault to find, e.g. 'backlash'")
    axes: list[str] = Field(description="the axes to choose from, each with its unit")
    units: list[str] = Field(description="the unit of each axis' size: mm or °")
    attempts_left: int
    answers: list[AnswerGiven]


class CheckState(BaseModel):
    """A check of one seat, evaluated on its live machine (a finding: graded on its answers)."""

    id: str
    text: str
    points: float
    earned: float = Field(0.0, description="its points × the time weight of its first pass")
    passed: bool = Field(description="holds now")
    first_passed_s: float | None = Field(description="seat time it first held, s")
    detail: str = Field(description="the measured figure, e.g. 'k = 19.96 1/s (−0.2 %)'")
    finding: FindingState | None = Field(
        None, description="a check the student answers (which axis, how much): its state"
    )


class FindingAnswer(BaseModel):
    """A student's answer to a finding check: the axis that carries the fault, and its size."""

    model_config = ConfigDict(extra="forbid")

    check: str = Field(min_length=1, max_length=64, pattern=r"^[a-z0-9][a-z0-9-]*$")
    axis: str = Field(min_length=1, max_length=16, pattern=r"^[A-Z][A-Z0-9]*$")
    value: float = Field(gt=0.0, le=1e6, description="the size in the axis' unit (mm | °)")


class StageResult(BaseModel):
    """One exercise of the lesson plan as a seat left it (moved on to the next)."""

    exercise: str = Field(description="exercise id")
    title: str
    score: float
    max_points: float
    checks: list[CheckState] = Field(description="as they stood when the seat moved on")
    hints_taken: int
    hint_cost: float
    seat_time_s: float = Field(description="the exercise's own clock, s")
    finished_s: float | None = Field(
        None, description="its clock when every check had passed (None: not all have)"
    )
    values: dict[str, float] = Field(description="the seat's own numbers in it")
    moved_on_by: str = Field(description="who moved the seat on (its student or an instructor)")
    moved_on_unix: float


class SeatInfo(BaseModel):
    """One seat of a class."""

    n: int = Field(description="seat number from 1")
    student: str = Field(description="the student's name (or 'Seat n')")
    user: str = Field(description="the seat's login (its one-time links log in as it)")
    machine: str
    frozen: bool
    control: str | None = Field(description="who holds control of the seat's machine")
    progress: float = Field(description="share of the checks that hold or held, 0..1")
    score: float = Field(description="in the exercise it is at")
    hints_taken: int
    seat_time_s: float = Field(description="simulated time the seat has run in its exercise, s")
    joined_unix: float | None = Field(
        None, description="its student's first login (None: nobody yet; its clock stands)"
    )
    stage: int = Field(description="the exercise it is at: index into the class's exercises")
    done: list[StageResult] = Field(description="the exercises of the plan it has moved on from")
    total_score: float = Field(description="its score over the plan so far")


class ClassResumed(BaseModel):
    """A running class the service built again when it restarted: what it kept."""

    at_unix: float = Field(description="when the service started again")
    seats: int
    faults: int = Field(description="training faults in force again, over all its seats")
    snapshots: int = Field(description="its seats' snapshots, each restorable")


class ClassInfo(BaseModel):
    id: str
    title: str
    exercises: list[str] = Field(description="the lesson plan: exercise ids in order")
    template: Literal["demo", "lists"] = Field(
        description="the seats' machines: the demo lathe or the class's uploaded lists"
    )
    instructor: str
    created_unix: float
    ended_unix: float | None
    seats: list[SeatInfo]
    resumed: ClassResumed | None = Field(
        None, description="the service restarted while it ran, and what the class kept"
    )
    presenting: str | None = Field(
        None, description="the machine the instructor presents to every seat (watch only)"
    )


class SeatLink(BaseModel):
    """A one-time login link of a seat (good once, until it expires)."""

    n: int
    url: str
    expires_unix: float = Field(0.0, description="when it stops working if unused")


class ClassCreated(BaseModel):
    """The new class and its seats' login links (shown this once)."""

    info: ClassInfo
    links: list[SeatLink]


class SeatSelection(BaseModel):
    """Some seats of a class (all when empty)."""

    model_config = ConfigDict(extra="forbid")

    seats: list[Annotated[int, Field(ge=1, le=MAX_SEATS)]] = Field(
        default_factory=list, max_length=MAX_SEATS
    )


class Freeze(SeatSelection):
    """Freeze (pause) or resume seats' machines."""

    frozen: bool


class Broadcast(SeatSelection):
    """A message every selected seat sees as a banner."""

    text: str = Field(min_length=1, max_length=500)


class Present(BaseModel):
    """Show a machine to every seat of the class, read-only (None: stop)."""

    model_config = ConfigDict(extra="forbid")

    machine: str | None = Field(None, min_length=1, max_length=64)


class ClassFault(SeatSelection):
    """A fault injected into the selected seats."""

    inject: FaultInject


class SeatFaults(BaseModel):
    n: int
    faults: list[FaultInfo]


class SeatDetail(BaseModel):
    """A seat for the instructor and the debrief: checks, hints, faults."""

    info: SeatInfo
    checks: list[CheckState]
    hints: list[HintInfo]
    faults: list[FaultInfo] = Field(
        description="the injected faults (the exercise's and the instructor's): live while "
        "the class runs, as they stood at its end once it has ended"
    )
    ended: bool = Field(
        description="the class has ended: checks' details and faults are their last state"
    )
    values: dict[str, float] = Field(description="the seat's own numbers in its exercise")


class Exercise(BaseModel):
    """The exercise of a seat: task, checks as they stand, hints, score (for the seat's
    student, or an instructor watching it)."""

    class_id: str
    seat: int = Field(description="seat number from 1")
    student: str = Field(description="the seat's student's name (or 'Seat n')")
    user: str = Field(description="the seat's login (control held by it is the student's)")
    takes_hints: bool = Field(
        description="whether the asker may take hints: only the seat's own student (a hint "
        "costs the student's points)"
    )
    exercise: ExerciseInfo
    checks: list[CheckState]
    hints: list[HintInfo]
    score: float
    progress: float
    seat_time_s: float
    frozen: bool = Field(description="paused by the instructor (the student cannot resume)")
    hand: RaisedHand | None = Field(None, description="the student's raised hand (None: down)")
    stage: int = Field(description="the exercise's place in the lesson plan, from 0")
    plan: list[str] = Field(description="the plan's exercise titles")
    done: list[StageResult] = Field(description="the plan's exercises the seat has moved on from")
    may_move_on: bool = Field(
        description="the asker may move the seat on now: an instructor while a next exercise "
        "exists, its student once every check has passed",
    )


class RaisedHand(BaseModel):
    """A student asking their instructor for help."""

    since_unix: float
    text: str = Field("", description="what they wrote with it")


class HandRequest(BaseModel):
    """Raise the seat's hand (its student) or lower it (its student or an instructor)."""

    raised: bool
    text: str = Field("", max_length=200, description="what the student wants, optional")


class SeatResult(BaseModel):
    """A seat's final result, for its student once the class has ended (their login is gone:
    the ended session's cookie still names the seat)."""

    class_id: str
    title: str = Field(description="the class's title")
    exercise: str = Field(description="the exercise's title")
    seat: int
    student: str
    ended_unix: float
    score: float = Field(description="over the lesson plan's exercises")
    max_points: float = Field(description="the sum of the checks' points, over the plan")
    checks_passed: int = Field(description="checks that held at some time")
    checks_total: int
    hints_taken: int
    seat_time_s: float
    stages: list[StageResult] = Field(description="each exercise of the plan the seat reached")


class HintTake(BaseModel):
    n: int = Field(ge=1, le=32)


# --- the instructor console's grid (websocket /api/classes/{cid}/grid) ------------------------
class AxisLine(BaseModel):
    """One axis of a seat in the grid: where it is, how fast, its lag."""

    name: str
    kind: Literal["linear", "rotary", "spindle"] = Field(
        description="spindles' lines show speed, axes' lag"
    )
    state: str
    lag: float = Field(description="mm | °, as the newest status says")
    speed: float = Field(description="mm/min | rpm (spindles), as the newest status says")
    lag_peak: float = Field(
        description="the lag of the largest magnitude (sign kept) in every cycle since the "
        "previous frame: a spike between two frames still shows (mm | °)"
    )
    speed_peak: float = Field(
        description="the speed of the largest magnitude since the previous frame, every cycle "
        "(mm/min | rpm)"
    )


class SeatFrame(BaseModel):
    """One seat as the grid shows it now."""

    n: int
    machine: str
    student: str
    channel: str = Field(description="channel state (IDLE, RUNNING, ERROR, ...)")
    mode: Literal["run", "pause", "fast", "gone"]
    frozen: bool
    axes: list[AxisLine]
    error: str | None = Field(description="the newest job error in words, null for none")
    error_code: int | None
    control: str | None
    progress: float
    score: float
    faults: int = Field(description="injected faults (active or armed)")
    seat_time_s: float
    stage: int = Field(description="the exercise it is at (index into the plan)")
    total_score: float = Field(description="its score over the lesson plan so far")
    hand: RaisedHand | None = Field(None, description="its student asks for help")
    joined: bool = Field(True, description="its student has logged in (its clock runs since)")
    idle_s: float | None = Field(
        None, description="since its student's last command (None: none yet)"
    )
    status_unix: float | None = Field(
        description="wall time the status shown was pushed by its worker (grid latency)"
    )


class GridFrame(BaseModel):
    """Every seat of a class, pushed a few times a second."""

    class_id: str
    ended: bool
    t_unix: float
    seats: list[SeatFrame]


class SnapshotCreate(BaseModel):
    label: str = Field("", max_length=80)


class SnapshotInfo(BaseModel):
    """A machine's saved state (simulated time, every axis, the channel, PLC, faults)."""

    id: int
    machine: str
    label: str
    cycle: int
    t_s: float
    created_unix: float
    by: str
    size_bytes: int
