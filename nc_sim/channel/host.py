"""What the channel needs of its machine: the `ChannelHost` protocol (nc_sim/machine carries
it out in `MachineChannelHost`)."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from nc_sim.channel import canon
from nc_sim.channel.geometry import Element
from nc_sim.channel.planner import AxisDynamics
from nc_sim.events import Event


class ChannelHost(Protocol):
    """What the channel needs of its machine (nc_sim/machine)."""

    @property
    def cycle(self) -> int: ...

    def new_action_id(self) -> int:
        """A number for an action, unique among the machine's actions."""

    def start_action(self, call: canon.Call, action_id: int) -> Event | None:
        """Start a non-motion call; the job error (logged) when it failed."""

    def busy(self, action_id: int) -> bool:
        """The action still runs (spindle not at speed, M function not acknowledged, ...)."""

    def sync_of(self, call: canon.Call) -> int:
        """Synchronisation type in force for a spindle call [000 §2.5]."""

    def path_limits(self, call: canon.VectorLimit) -> tuple[float, float, float]:
        """#VECTOR LIMIT as path speed (mm/s), acceleration and deceleration (mm/s²); ∞
        where it sets none [002 §2.5.2]."""

    def manual_mode(self, parallel: bool) -> None:
        """G201 (`parallel`): the path's axes may be jogged while it runs; G200: not."""

    def check_element(self, e: Element) -> Event | None:
        """None when the element may run, else the job error (logged) that forbids it."""

    def start_coupling(self, e: Element) -> Event | None:
        """Couple a G33/G63 element to its spindle (the path is at rest where it starts);
        None when it may run, else the job error (logged) that forbids it."""

    def path_in_position(self) -> bool:
        """Every path axis stands within its exact-stop window (an in-position event comes
        when the last one gets there)."""

    def dynamics(self, e: Element) -> list[AxisDynamics]:
        """The path axes' limits for this element's kind of motion."""

    def hold_limits(self, e: Element | None) -> np.ndarray:
        """Path braking limits for feedhold."""

    def path_moving(self, line: int | None) -> None:
        """The path axes move (line) or stand (None)."""

    def program_end(self, call: canon.ProgramEnd) -> None:
        """M30/M02: what the machine does at program end (spindles per the HLI flag)."""

    def spindle_name(self, name: str) -> str:
        """A spindle's configured name ("S", the main spindle, by its own)."""

    def block_done(self, block_id: int, text: str) -> None:
        """An MDI block has run completely."""

    def block_dropped(self, block_id: int, text: str, cause: Event) -> None:
        """A job error (`cause`) ended an MDI block before it was done: the block that raised
        it and each queued behind it, so the error can be put down to the command that sent
        the block."""

    def path_left(self) -> None:
        """The path was abandoned mid-way (job error, reset, E-stop, a stopped thread): its
        axes, and a tapping spindle, brake on their own."""
