"""The scope at the drive's rate: a short capture of one axis' drive signals around the
scope's trigger, one sample per drive step, as a drive's own oscilloscope records it.

The NC scope (nc_sim/scope.py) finds the trigger and the record's span in NC cycles; the
kernel's drive probe runs as a ring meanwhile (`Kernel.start_probe_ring`), holding the axis'
drive trace. When the NC scope completes a record, `DriveScope.record` cuts the same span out
of the ring at the drive's rate. Sample k of NC cycle c (c counted as `Simulation.cycle`
after it ran) is drive step (c - 1)·n + k since power-on: the state at the start of that
step, at (c - 1)·cycle + k·step seconds. An NC sample is the state at the end of its cycle,
so the trigger (NC cycle T) is drive step T·n, and a drive record, covering every step of the
NC record's cycles, starts n steps (one cycle) before the NC record's first sample: its
pre-trigger holds one cycle more. Pure like the kernel: the owner feeds it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from nc_sim.kernel.arrays import Kernel
from nc_sim.plant import layout as PL
from nc_sim.scope import Record
from nc_sim.signals import Signal
from nc_sim.units import RPM_TO_RAD_S, AxisKind

MAX_LENGTH_S = 2.0  # a drive's trace memory: 16 000 samples at 125 µs
RAD_S_TO_RPM = 1.0 / RPM_TO_RAD_S


def drive_signals(axis: str, kind: AxisKind, slot: int) -> list[Signal]:
    """The drive signals of one axis, `<axis>.drive.<signal>`: speeds and torques referred
    to the motor, positions in the axis' unit (the load's and the motor's true position, the
    position loop's command and actual value in NC coordinates)."""
    u = "mm" if kind is AxisKind.LINEAR else "deg"
    rows = [
        ("speed_set_rpm", PL.D_W_SET, RAD_S_TO_RPM, "rpm"),
        ("speed_ref_rpm", PL.D_W_REF, RAD_S_TO_RPM, "rpm"),
        ("speed_motor_rpm", PL.D_W_MOTOR, RAD_S_TO_RPM, "rpm"),
        ("speed_load_rpm", PL.D_W_LOAD, RAD_S_TO_RPM, "rpm"),
        ("torque_set_nm", PL.D_T_SET, 1.0, "Nm"),
        ("torque_nm", PL.D_TORQUE, 1.0, "Nm"),
        (f"pos_cmd_{u}", PL.D_P_REF, 1.0, u),
        (f"pos_act_{u}", PL.D_P_ACT, 1.0, u),
        (f"pos_motor_{u}", PL.D_X_MOTOR, 1.0, u),
        (f"pos_load_{u}", PL.D_X_LOAD, 1.0, u),
    ]
    return [
        Signal(f"{axis}.drive.{n}", axis, slot, col, k, unit, "float") for n, col, k, unit in rows
    ]


class DriveScope:
    """A drive-rate capture of one axis while the NC scope is armed. The owner feeds the NC
    scope at least every FEED_CYCLES cycles, so a record it completes is still in the ring."""

    SLACK_CYCLES = 200  # ring beyond the record's length
    FEED_CYCLES = SLACK_CYCLES // 2

    def __init__(
        self, kernel: Kernel, cycle: int, slot: int, channels: list[Signal], length_cycles: int
    ) -> None:
        """Start the ring on `slot` now, after cycle `cycle`. The ring holds the record and
        SLACK_CYCLES more: the NC scope completes a record some cycles after its end (the
        owner steps in stretches)."""
        self.kernel = kernel
        self.slot = slot
        self.channels = channels
        self.steps = int(kernel.pl[slot, PL.PL_SUBSTEPS])
        self.step_s = kernel.cycle_s / self.steps
        self.started = cycle  # the ring's sample 0 is the first step of the next cycle
        kernel.start_probe_ring(slot, (length_cycles + self.SLACK_CYCLES) * self.steps)

    def record(self, nc: Record) -> Record | None:
        """The drive-rate record of the span of `nc` (an NC record completed just now); None
        when the ring does not hold it (it started after the record did)."""
        n = self.steps
        first = (nc.first_cycle - self.started - 1) * n
        rows = self.kernel.probe_ring(first, nc.count * n)
        if rows is None:
            return None
        data = np.stack([rows[:, s.column] * s.scale for s in self.channels])
        return Record(
            channels=list(self.channels),
            data=data,
            first_cycle=(nc.first_cycle - 1) * n,
            cycle_s=self.step_s,
            trigger_cycle=None if nc.trigger_cycle is None else nc.trigger_cycle * n,
            trigger=f"{nc.trigger} (drive rate, {self.step_s * 1e6:g} µs)",
            forced=nc.forced,
            events=[replace(e, cycle=e.cycle * n) for e in nc.events],
        )

    def stop(self) -> None:
        """End the ring."""
        self.kernel.stop_probe()
