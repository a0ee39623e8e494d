"""The drive's own oscilloscope: its signals at its own rate (8 kHz at 125 µs) over a short
move, as a drive's commissioning tool records them: speed setpoint and actual, the load's
speed, torque setpoint and torque, and how far the motor is ahead of the load (the coupling's
twist, the backlash taken up). The axis moves `distance` at `feed_mm_min` and goes back.
"""

from __future__ import annotations

import math

import numpy as np

from nc_sim.assist.drive_axis import drive_axis
from nc_sim.assist.procedure import Procedure, Wait, on_copy
from nc_sim.assist.result import ExperimentError, Figure, Result, Series
from nc_sim.commands import Accepted, Move, Refused
from nc_sim.config import MachineConfig
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.plant import layout as PL
from nc_sim.snapshot import AxisState
from nc_sim.units import RPM_TO_RAD_S

MAX_POINTS = 4000  # per signal; a longer record is decimated to this
UM_PER_MM = 1000.0


def drive_trace_experiment(
    cfg: MachineConfig,
    axis: str,
    distance: float = 5.0,
    feed_mm_min: float = 3000.0,
    duration_s: float = 0.5,
) -> Result:
    """`drive_trace` on a fresh copy of the machine `cfg` describes."""
    return on_copy(cfg, lambda m: drive_trace(m, axis, distance, feed_mm_min, duration_s))


def drive_trace(
    m: Machine,
    axis: str,
    distance: float = 5.0,
    feed_mm_min: float = 3000.0,
    duration_s: float = 0.5,
) -> Procedure:
    """Record `duration_s` of `axis`' drive at its rate from the start of a move of
    `distance` (mm | °; 0: at rest) at `feed_mm_min`, then take the axis back."""
    ax, model = drive_axis(m, axis, "the drive's trace")
    k = m.k
    if ax.state is not AxisState.STANDSTILL:
        raise ExperimentError(f"{ax.name} must stand still to start ({ax.state.name})")
    cycles = max(1, round(duration_s / k.cycle_s))
    p0 = float(k.st[ax.slot, L.S_P_CMD])
    k.start_probe(ax.slot, np.zeros(cycles * model.substeps), PL.INJECT_TORQUE)
    try:
        if distance != 0.0:
            out = m.submit(Move(ax.name, p0 + distance, rapid=False, feed_mm_min=feed_mm_min))
            if not isinstance(out, Accepted):
                why = out.error.message if isinstance(out, Refused) else str(out)
                raise ExperimentError(f"the move was refused: {why}")
        yield Wait(cycles, f"{ax.name}: the drive is recorded", duration_s + 1.0)
        trace = k.probe_trace().copy()
    finally:
        if k.probe[PL.PR_SLOT] == ax.slot:
            k.stop_probe()
    while ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
        yield Wait(20, f"{ax.name} comes to rest", duration_s + 1.0)
    if distance != 0.0 and ax.state is AxisState.STANDSTILL:
        back = m.submit(Move(ax.name, p0, rapid=False, feed_mm_min=feed_mm_min))
        if isinstance(back, Accepted):
            while ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
                yield Wait(20, f"{ax.name} goes back to {p0:g}", duration_s + 1.0)
    return _result(ax.name, trace, model.sampling_s)


def _result(name: str, tr: np.ndarray, ts: float) -> Result:
    every = max(1, math.ceil(len(tr) / MAX_POINTS))
    t = np.arange(len(tr)) * ts
    twist = (tr[:, PL.D_X_MOTOR] - tr[:, PL.D_X_LOAD]) * UM_PER_MM

    def series(label: str, y: np.ndarray, unit: str) -> Series:
        return Series(
            label,
            tuple(float(v) for v in t[::every]),
            tuple(float(v) for v in y[::every]),
            "s",
            unit,
        )

    torque = tr[:, PL.D_TORQUE]
    figures = (
        Figure("rate_hz", 1.0 / ts, "Hz", "the drive's sampling rate"),
        Figure("samples", float(len(tr)), "", "samples per signal recorded"),
        Figure("torque_peak_nm", float(np.max(np.abs(torque))), "Nm", "highest torque"),
        Figure("twist_peak_um", float(np.max(np.abs(twist))), "µm", "motor ahead of the load"),
    )
    notes = (
        f"{name}: the drive at {1.0 / ts:g} Hz"
        + (f", every {every}th sample shown" if every > 1 else ", every sample shown"),
    )
    return Result(
        "drive-trace",
        figures,
        (),
        (
            series("speed setpoint", tr[:, PL.D_W_REF] / RPM_TO_RAD_S, "rpm"),
            series("motor speed", tr[:, PL.D_W_MOTOR] / RPM_TO_RAD_S, "rpm"),
            series("load speed", tr[:, PL.D_W_LOAD] / RPM_TO_RAD_S, "rpm"),
            series("torque setpoint", tr[:, PL.D_T_SET], "Nm"),
            series("torque", torque, "Nm"),
            series("motor ahead of load", twist, "µm"),
        ),
        notes,
        inputs={"axis": name},
    )
