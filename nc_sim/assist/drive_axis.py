"""The axis a drive measurement (frequency response, step) works on: it must run the drive
cascade, and the worker's one drive probe must be free."""

from __future__ import annotations

from nc_sim.assist.result import ExperimentError
from nc_sim.axis.plant import cascade, drive_model
from nc_sim.axis.state import Axis
from nc_sim.machine.machine import Machine
from nc_sim.plant import layout as PL
from nc_sim.plant.model import DriveModel


def drive_axis(m: Machine, axis: str, what: str) -> tuple[Axis, DriveModel]:
    """`axis` of `m` and its drive as its parameters describe it (the drive knows no more);
    ExperimentError naming why `what` cannot run on it."""
    try:
        ax = m.axis(axis)
    except ValueError as e:
        raise ExperimentError(str(e)) from None
    if not cascade(ax.cfg):
        raise ExperimentError(
            f"{ax.name} runs the IDEAL plant (sim.plant): {what} needs the drive cascade "
            "(DRIVE_CASCADE)"
        )
    probe = m.k.probe
    if probe[PL.PR_SLOT] >= 0 and probe[PL.PR_POS] < probe[PL.PR_LEN]:
        raise ExperimentError("another drive measurement runs on this machine: try again after it")
    return ax, drive_model(ax.cfg, m.k.cycle_s, gear=ax.gear)
