"""Gear stage selection for the main spindle [000 §2.8.2, DOMAIN §4.2].

Gear stage g (1..6) is M(39+g), range_table[g-1] and gear record getriebe[g-1].
Pure functions (no kernel: the gateway previews the rule with them); the machine turns the
result into a change sequence or a job error.
"""

from __future__ import annotations

from dataclasses import dataclass

from nc_sim.config import MachineConfig
from nc_sim.errors import Code


@dataclass(frozen=True)
class GearRange:
    min_rpm: float
    max_rpm: float

    @property
    def used(self) -> bool:
        return self.max_rpm > 0

    def holds(self, rpm: float) -> bool:
        return self.used and self.min_rpm <= rpm <= self.max_rpm


@dataclass(frozen=True)
class GearChoice:
    """The gear stage to run S in, or the error that refuses it."""

    gear: int | None
    error: Code | None = None
    detail: str = ""


def spindle_index(cfg: MachineConfig, name: str) -> int | None:
    """Index i of spindel[i] in the channel list for this spindle."""
    for i in range(6):
        if cfg.channel.get(f"spindel[{i}].bezeichnung") == name:
            return i
    return None


def range_table(cfg: MachineConfig, i: int) -> list[GearRange]:
    """The six speed ranges of spindel[i] (P-CHAN-00058 min_speed, P-CHAN-00055 max_speed)."""
    pre = f"spindel[{i}].range_table"
    return [
        GearRange(
            float(cfg.channel_raw(f"{pre}[{g}].min_speed")),
            float(cfg.channel_raw(f"{pre}[{g}].max_speed")),
        )
        for g in range(6)
    ]


def m_of(gear: int) -> int:
    return 39 + gear


def select_gear(
    table: list[GearRange],
    current: int,
    rpm: float,
    automatic: bool,
    range_way: int,
    programmed: int | None,
) -> GearChoice:
    """Gear stage for speed `rpm` (absolute) given the current stage and an optional M4x.

    Automatic: keep the current stage when it holds S, else search bottom-up (range_way 0)
    or top-down for the first holding range; a programmed M4x is checked against S.
    Manual: M4x must come with S inside its range; S alone must fit the current stage.
    """
    rpm = abs(rpm)
    if programmed is not None:
        r = table[programmed - 1]
        if not r.holds(rpm):
            return GearChoice(
                None,
                Code.GEAR_WRONG_STAGE,
                f"S{rpm:g} is outside M{m_of(programmed)} ({r.min_rpm:g}-{r.max_rpm:g} rpm)",
            )
        return GearChoice(programmed)
    if table[current - 1].holds(rpm) or rpm == 0:
        return GearChoice(current)
    if not automatic:
        holding = [g for g in range(1, 7) if table[g - 1].holds(rpm)]
        hint = f" (M{m_of(holding[0])})" if holding else ""
        return GearChoice(None, Code.GEAR_NOT_PROGRAMMED, f"S{rpm:g} needs a gear stage{hint}")
    order = range(1, 7) if range_way == 0 else range(6, 0, -1)
    for g in order:
        if table[g - 1].holds(rpm):
            return GearChoice(g)
    used = [g for g in range(1, 7) if table[g - 1].used]
    top = max(used, key=lambda g: table[g - 1].max_rpm) if used else None
    if top is not None and rpm > table[top - 1].max_rpm:  # name the machine's own limit
        return GearChoice(
            None,
            Code.GEAR_NO_RANGE,
            f"S{rpm:.10g} rpm is above the highest gear stage, M{m_of(top)} up to "
            f"{table[top - 1].max_rpm:.10g} rpm (range_table[{top - 1}].max_speed, "
            "P-CHAN-00055)",
        )
    return GearChoice(None, Code.GEAR_NO_RANGE, f"no gear stage's range holds S{rpm:.10g} rpm")
