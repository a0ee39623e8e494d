"""Exercise authoring: an exercise file tried before it is saved (checked, then run on a copy
of a seat with nobody at it)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from api.classes import ExerciseInfo

MAX_DRY_S = 120.0  # nc_sim/training/dry_run.py


class DryRunRequest(BaseModel):
    """An exercise file to try, and how long its seat runs untouched."""

    model_config = ConfigDict(extra="forbid")

    text: str = Field(min_length=1, max_length=100_000, description="the exercise file (TOML)")
    seconds: float = Field(20.0, ge=1.0, le=MAX_DRY_S, description="simulated time, s")


class DryCheck(BaseModel):
    """A check as it stood on the untouched seat."""

    id: str
    text: str
    points: float
    passed: bool = Field(description="held at the end of the run")
    first_passed_s: float | None = Field(description="when it first held (None: never)")
    detail: str


class DryJobError(BaseModel):
    code: int
    message: str
    t_s: float = Field(description="simulated time, s, from the seat's start")


class ExerciseDryRun(BaseModel):
    """The exercise checked (as an upload would be) and its seat run untouched."""

    info: ExerciseInfo
    seconds: float = Field(description="simulated time the seat ran")
    values: dict[str, float] = Field(description="the numbers seat 1 of a class would get")
    checks: list[DryCheck] = Field(description="the checks the seat's worker judges")
    job_errors: list[DryJobError] = Field(description="raised with nobody at the machine")
    warnings: list[str] = Field(description="what would make a poor exercise, in words")
