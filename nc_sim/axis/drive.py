"""Drive status and the simulated drive's power-up [004 §4.2].

Digital drives report `ready_for_power_on` (booted, the power stage may be switched on) and
`ready_for_control_loop_on` (power stage on: with the enables set the drive follows the NC).
Which drive types report which signal follows the manual's table; a drive type that reports
neither (terminal ±10 V, simulation) is ready as far as the NC can tell. Nothing here reads a
clock: the status is a function of the cycle.
"""

from __future__ import annotations

from dataclasses import dataclass

READY_FOR_POWER_ON = "ready_for_power_on"
READY_FOR_CONTROL_LOOP_ON = "ready_for_control_loop_on"
_BOTH = (READY_FOR_POWER_ON, READY_FOR_CONTROL_LOOP_ON)

# kenngr.antr_typ -> the status signals the drive supplies [004 §4.2]: ReadyPowerOn for
# SERCOS, PROFIDRIVE, Lightbus, RT Ethernet and CANopen; ReadyControlLoopOn for SERCOS,
# PROFIDRIVE and CANopen (the drive types that also take DriveOn, 004 §4.1)
STATUS_BY_DRIVE: dict[int, tuple[str, ...]] = {
    2: _BOTH,  # SERCOS
    3: _BOTH,  # PROFIDRIVE MC
    5: (READY_FOR_POWER_ON,),  # Lightbus
    7: (READY_FOR_POWER_ON,),  # RT Ethernet
    8: _BOTH,  # CANopen
}


@dataclass
class DriveStatus:
    """One drive's start-up: it boots, then powers its stage up after DriveOn.

    `boot_cycles` after power-on the drive is ready for power on; `power_up_cycles` after
    DriveOn (DC link charged, power stage on) it is ready for the control loop. Removing
    DriveOn switches the power stage off again.
    """

    signals: tuple[str, ...]
    boot_cycles: int
    power_up_cycles: int
    drive_on_since: int | None = None  # cycle DriveOn was seen set, None while it is off
    cycle: int = 0
    failed: bool = False  # a drive fault (injected for training): no ready signal at all

    def update(self, cycle: int, drive_on: bool) -> None:
        """Advance to `cycle` with the DriveOn enable as the PLC has it now."""
        self.cycle = cycle
        if not drive_on:
            self.drive_on_since = None
        elif self.drive_on_since is None:
            self.drive_on_since = cycle

    @property
    def ready_for_power_on(self) -> bool:
        return not self.failed and self.cycle >= self.boot_cycles

    @property
    def ready_for_control_loop_on(self) -> bool:
        return (
            self.ready_for_power_on
            and self.drive_on_since is not None
            and self.cycle - self.drive_on_since >= self.power_up_cycles
        )

    def ready(self) -> tuple[bool, bool]:
        """The reported signals as (ready for power on, ready for the control loop), an
        unreported one always true: what `missing` tells, cheap to compare each cycle."""
        return (
            self.ready_for_power_on or READY_FOR_POWER_ON not in self.signals,
            self.ready_for_control_loop_on or READY_FOR_CONTROL_LOOP_ON not in self.signals,
        )

    def reported(self) -> dict[str, bool]:
        """The status signals this drive type supplies, as the HLI shows them."""
        values = {
            READY_FOR_POWER_ON: self.ready_for_power_on,
            READY_FOR_CONTROL_LOOP_ON: self.ready_for_control_loop_on,
        }
        return {name: values[name] for name in self.signals}

    def missing(self) -> list[str]:
        """Reported status signals that are not (yet) present."""
        return [name for name, ok in self.reported().items() if not ok]

    def next_change(self) -> int | None:
        """The next cycle at which the status changes on its own (boot, power-up)."""
        if self.cycle < self.boot_cycles and self.signals:
            return self.boot_cycles
        if self.drive_on_since is not None and READY_FOR_CONTROL_LOOP_ON in self.signals:
            due = self.drive_on_since + self.power_up_cycles
            if self.cycle < due:
                return due
        return None
