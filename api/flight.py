"""The flight recorder: the last minutes of every machine's main signals, and the seconds
around each job error saved as traces."""

from __future__ import annotations

from pydantic import BaseModel, Field

MAX_SAVE_S = 3600.0


class FlightRecorderStatus(BaseModel):
    """What a machine's flight recorder keeps."""

    before_s: float = Field(description="saved before a job error, at full rate")
    after_s: float = Field(description="saved after it")
    full_rate_s: float = Field(description="the last seconds held at full rate (every cycle)")
    held_s: float = Field(description="the last seconds held in all (decimated beyond)")
    reach_s: float = Field(description="what it holds once the machine has run that long")
    decimation: int = Field(description="one sample in this many cycles beyond the full rate")
    bytes: int = Field(description="memory of this machine's long tier")
    keep: int = Field(description="job-error traces kept per machine (newest)")


class FlightSave(BaseModel):
    """Save the last seconds of a machine as a trace."""

    seconds: float = Field(60.0, gt=0, le=MAX_SAVE_S)
