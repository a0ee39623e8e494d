"""The machine's manual controls: the spindle buttons (M3/M4/M5, M19, M40-M45 outside a
block) and HLI writes of the channel's and the axes' control units [000 §2.9, 004 §4]."""

from __future__ import annotations

from nc_sim import hli
from nc_sim.axis.state import Axis
from nc_sim.errors import Code, NcUsageError
from nc_sim.events import Event
from nc_sim.machine.core import MachineCore
from nc_sim.plc import Waiter
from nc_sim.snapshot import ChannelState
from nc_sim.units import AxisKind


class Panel:
    """Manual commands to one machine."""

    def __init__(self, m: MachineCore) -> None:
        self.m = m

    # --- the spindle buttons [000] -------------------------------------------------------
    def _spindle(self, name: str) -> Axis:
        ax = self.m.axis(name)
        if ax.kind is not AxisKind.SPINDLE:
            raise NcUsageError(f"{name} is not a spindle")
        return ax

    def spindle_run(self, name: str, m: int, speed_rpm: float | None = None) -> Event | None:
        """M3/M4 with speed (rpm), or M5."""
        ax = self._spindle(name)
        if m == 5:
            self.m.sp.m5(ax)
            return None
        return self.m.sp.endless(ax, m, speed_rpm)

    def spindle_position(
        self,
        name: str,
        pos_deg: float,
        direction: int | None = None,
        speed_rpm: float | None = None,
    ) -> Event | None:
        """M19 S.POS=pos_deg with M3 (+1) / M4 (-1) or the shortest way (None)."""
        return self.m.sp.position(self._spindle(name), pos_deg, direction, speed_rpm)

    def spindle_gear(self, name: str, m: int) -> Event | None:
        """M40-M45: change gear stage (main spindle with P-CHAN-00052)."""
        if not 40 <= m <= 45:
            raise NcUsageError("gear stage M40..M45")
        ax = self._spindle(name)
        if not self.m.gear_change_enabled:  # then M40-M45 are free M functions
            self.m.handshake.output(m, "", Waiter())
            return None
        return self.m.sp.gears.only(ax, m - 39, None)

    # --- HLI ----------------------------------------------------------------------------
    def hli_write(self, unit: str, value: int, axis: str | None = None) -> None:
        """Write a control unit of the channel (axis=None) or of an axis."""
        if axis is None:
            hli.channel_write(unit, value)
            self.channel_unit(unit, int(value))
            return
        ax = self.m.axis(axis)
        value = hli.axis_write(unit, value)
        if unit == "spindle_reset" and value:
            self.m.moves.reset(ax)
            return
        ax.units[unit] = int(value)
        self.m.log(Code.EV_HLI, ax.name, f"{unit} = {int(value)}", signal=unit, value=int(value))
        if unit in ("DriveOn", "TorquePermission", "ReleaseFeedhold"):
            self.m.motion.enables_changed(ax)
        elif unit in ("override", "override_valid") or unit in hli.REDUCED_SPEED_UNITS:
            self.m.moves.replan(ax)
            if unit in hli.REDUCED_SPEED_UNITS:
                self.m.channel.replan()  # a path the axis is on slows (or speeds up) with it

    def channel_unit(self, unit: str, value: int) -> None:
        old = self.m.channel_units[unit]
        self.m.channel_units[unit] = hli.clamp(unit, value)
        self.m.log(Code.EV_HLI, "", f"channel {unit} = {value}", signal=unit, value=value)
        if unit == "override":
            cap = self.m.cfg.channel_eng("max_vb_override")
            self.m.channel.override = min(self.m.channel_units["override"] * 1e-3, cap)
            self.m.channel.replan()
        self.m.channel.feedhold = bool(self.m.channel_units["feedhold"])
        if unit == "feedhold" and bool(value) != bool(old):
            if value:
                self.m.channel.hold()
            elif self.m.channel.state is ChannelState.HELD:
                self.m.channel.resume()
            self.m.moves.feedhold(bool(value), self.m.axes)
            return
        for ax in self.m.axes:
            if self.m.moves.as_axis(ax):
                self.m.moves.replan(ax)
