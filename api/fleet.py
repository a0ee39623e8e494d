"""Every machine at a glance, and the alarms across them."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from api.history import HistoryEntry


class FleetMachine(BaseModel):
    """One machine as the fleet view shows it."""

    id: str
    name: str
    reachable: Literal["running", "rebuilding", "unreachable"] = Field(
        description="its worker runs it; it is being built again; no live worker has it"
    )
    mode: str = Field(description="run, pause or fast")
    state: str = Field(description="the channel's state, or 'emergency stop'")
    active_errors: list[str] = Field(description="job errors in force, as 'code axis'")
    last_alarm: HistoryEntry | None = Field(description="its newest job error (history)")
    holder: str | None = Field(description="who holds control, 'NAME (role)'")
    viewers: int = Field(description="browser tabs and scripts watching it live")
    guests: int = Field(description="of them through share links")
    overruns_per_min: float | None = Field(description="its worker's loop overruns a minute")
    seat: bool = Field(description="a class seat")


class Fleet(BaseModel):
    machines: list[FleetMachine]
    alarms: list[HistoryEntry] = Field(description="the newest job errors of all, newest first")
    machine_of: dict[str, str] = Field(description="alarm id -> machine id")
