"""What a spindle sequence (task.py) and the gear change (gear_change.py) need of the spindle
control that runs them (control.py's `SpindleControl` is it): they call back into it without
importing it."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from nc_sim.axis.motion import AxisMotion
from nc_sim.axis.state import Axis
from nc_sim.config import MachineConfig
from nc_sim.events import Event
from nc_sim.plc import Handshake
from nc_sim.snapshot import AxisState


class GearAcks(Protocol):
    """The gear change's answers to the PLC's handshake of M40-M45."""

    def acknowledged(self, ax: Axis) -> None: ...

    def timed_out(self, ax: Axis, error: Event) -> None: ...


class SpindleOps(Protocol):
    """The spindle control as its sequences see it."""

    @property
    def motion(self) -> AxisMotion: ...

    @property
    def cfg(self) -> MachineConfig: ...

    @property
    def handshake(self) -> Handshake: ...

    @property
    def gears(self) -> GearAcks: ...

    def preferred(self, ax: Axis) -> int | None: ...

    def auto_homing(self, ax: Axis) -> bool: ...

    def v_max(self, ax: Axis) -> float: ...

    def override(self, ax: Axis) -> float: ...

    def limits(self, ax: Axis) -> np.ndarray: ...

    def velocity(self, ax: Axis, v: float) -> None: ...

    def set_state(self, ax: Axis, state: AxisState, monitoring: bool = False) -> None: ...

    def adopt_tool(self, ax: Axis) -> None: ...

    def cancel_task(self, ax: Axis) -> None: ...

    def switch_back(self, ax: Axis) -> None: ...

    def endless(
        self,
        ax: Axis,
        m: int,
        rpm: float | None,
        gear: int | None = None,
        block_id: int | None = None,
    ) -> Event | None: ...

    def target(self, ax: Axis, pos_deg: float, direction: int | None) -> float: ...
