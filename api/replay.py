"""A class seat's session as recorded for the debrief: a low-rate trace of its machine's main
signals and the timeline of what happened (its history), both on the exercise's seat clock."""

from __future__ import annotations

from pydantic import BaseModel, Field

from api.history import HistoryEntry


class ReplayMark(BaseModel):
    """One entry of the seat's history, placed on the exercise's clock."""

    seat_t_s: float = Field(description="seat time of the exercise when it happened, s")
    entry: HistoryEntry


class SeatReplay(BaseModel):
    """What a seat did in one exercise of its lesson plan, to play back in the debrief."""

    class_id: str
    seat: int
    stage: int = Field(description="the exercise's place in the plan, from 0")
    exercise: str = Field(description="its title")
    sample_s: float = Field(description="the recording's period, s of wall time")
    signals: list[str] = Field(description="e.g. 'X.pos', 'X.lag', 'S1.speed'")
    units: list[str] = Field(description="each signal's unit")
    t_s: list[float] = Field(description="seat time of each sample, s")
    values: list[list[float | None]] = Field(
        description="per signal, its value at each sample (null where the machine had none)"
    )
    marks: list[ReplayMark] = Field(description="what happened, oldest first")
