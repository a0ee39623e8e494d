"""The service-axis view of a machine, read from its worker, in the API's words."""

from __future__ import annotations

from dataclasses import asdict

from api.service_axes import AxisService, LimitInForce, ServiceAxes
from backend.services.machines import MachineProxy
from backend.workers.protocol import ReadServiceAxes, ServiceAxesRead
from nc_sim.snapshot import AxisServiceSnapshot


def _axis(a: AxisServiceSnapshot) -> AxisService:
    return AxisService(
        name=a.name,
        gear=a.gear,
        kv_per_s=a.kv_per_s,
        ff_weight=a.ff_weight,
        multi_gain=a.multi_gain,
        lag_max=a.lag_max,
        v_cmd=a.v_cmd,
        lag_expected=a.lag_expected,
        lag_expected_why_not=a.lag_expected_why_not,
        k_measured_per_s=a.gain.k_per_s,
        k_why_not=a.gain.why_not,
        da_digits=a.da_digits,
        da_max_digits=a.da_max_digits,
        velocity=LimitInForce(**asdict(a.velocity)),
        acceleration=LimitInForce(**asdict(a.acceleration)),
        jerk=LimitInForce(**asdict(a.jerk)) if a.jerk is not None else None,
        jerk_why_none=a.jerk_why_none,
    )


async def service_axes(m: MachineProxy) -> ServiceAxes:
    """Every axis and spindle of the machine in the service-axis view, fresh from its worker."""
    read = await m.link.acall(ReadServiceAxes(m.id))
    assert isinstance(read, ServiceAxesRead)
    return ServiceAxes(cycle=read.cycle, axes=[_axis(a) for a in read.axes])
