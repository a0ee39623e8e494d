"""What the parts of a machine (channel host and operations, operator panel, fault injection,
readouts) need of the machine that composes them (machine.py's `Machine` is it): they take
it as this protocol and never import the machine itself."""

from __future__ import annotations

from typing import Protocol

from nc_sim.axis.motion import AxisMotion
from nc_sim.axis.moves import Moves
from nc_sim.axis.state import Axis
from nc_sim.channel.channel import Channel
from nc_sim.config import MachineConfig
from nc_sim.errors import Code
from nc_sim.events import Event, EventLog
from nc_sim.kernel.arrays import Kernel
from nc_sim.plc import Handshake, SimPlc
from nc_sim.spindle.caxis import CAxis
from nc_sim.spindle.control import SpindleControl


class PathHost(Protocol):
    """The channel host as the readouts and channel operations see it."""

    @property
    def path_axes(self) -> list[Axis]: ...

    def spindle_name(self, name: str) -> str: ...

    def block_target(self, ax: Axis) -> float | None: ...


class MachineCore(Protocol):
    """A machine as its parts see it."""

    slope: int  # the path's acceleration profile (G-code slope type), set by the channel

    def modal_at_program_start(self) -> None: ...

    @property
    def cfg(self) -> MachineConfig: ...

    @property
    def k(self) -> Kernel: ...

    @property
    def cycle(self) -> int: ...

    @property
    def t_s(self) -> float: ...

    @property
    def axes(self) -> list[Axis]: ...

    @property
    def by_name(self) -> dict[str, Axis]: ...

    @property
    def main_spindle(self) -> str | None: ...

    @property
    def events(self) -> EventLog[Event]: ...

    @property
    def plc(self) -> SimPlc: ...

    @property
    def handshake(self) -> Handshake: ...

    @property
    def motion(self) -> AxisMotion: ...

    @property
    def sp(self) -> SpindleControl: ...

    @property
    def moves(self) -> Moves: ...

    @property
    def ch_host(self) -> PathHost: ...

    @property
    def channel(self) -> Channel: ...

    @property
    def cax(self) -> CAxis | None: ...

    @property
    def channel_units(self) -> dict[str, int]: ...

    @property
    def estop(self) -> bool: ...

    @property
    def powered(self) -> bool: ...

    @property
    def queued_blocks(self) -> int: ...

    @property
    def gear_change_enabled(self) -> bool: ...

    def axis(self, name: str) -> Axis: ...

    def log(
        self,
        code: Code,
        axis: str = "",
        detail: str = "",
        *,
        m: int | None = None,
        gear: int | None = None,
        line: int | None = None,
        column: int | None = None,
        signal: str | None = None,
        value: float | None = None,
        block: int | None = None,
    ) -> Event: ...
