"""Creating machines and pacing their simulation."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from api.common import STORE_INT_MAX


class MachineLists(BaseModel):
    """A machine's native parameter lists (the text of .lis files)."""

    channel_list: str = Field("", max_length=1_000_000)
    axis_lists: dict[int, str] = Field(
        default_factory=dict, description="axis lists by logical axis number (log_achs_nr)"
    )
    tool_list: str = Field("", max_length=1_000_000)


class MachineCreate(MachineLists):
    """A new machine: the demo lathe, or from native parameter lists."""

    id: str = Field(pattern=r"^[a-z0-9][a-z0-9_-]{0,31}$", description="URL name")
    name: str = Field("", max_length=80)
    demo: bool = Field(False, description="the shipped demo lathe (lists ignored)")


class SimulationControl(BaseModel):
    """Run in real time, pause, or run as fast as possible (optionally up to a cycle)."""

    mode: Literal["run", "pause", "fast"]
    until_cycle: int | None = Field(
        None, ge=0, le=STORE_INT_MAX, description="fast: pause at this cycle"
    )


MAX_STEP_CYCLES = 1_000_000  # one request; longer spans run in fast mode with until_cycle


class StepRequest(BaseModel):
    """Single-step a paused machine by whole cycles (answered when they are done)."""

    cycles: int = Field(
        1,
        ge=1,
        le=MAX_STEP_CYCLES,
        description="cycles to advance, at most 1 000 000 (1000 s at 1 ms); for longer spans "
        "use mode fast with until_cycle",
    )
