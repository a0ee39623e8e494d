"""The status of a machine in its worker, consistent to one cycle."""

from __future__ import annotations

from typing import Literal

from api.status import (
    AxisStatus,
    MachineStatus,
    PendingM,
    PlcStatus,
)
from backend.services.commands import job_error_model
from backend.services.status import simulation_status
from backend.workers.host import MachineHost
from nc_sim.errors import JobError
from nc_sim.kernel import layout as L
from nc_sim.machine.axis import Axis, target_and_distance
from nc_sim.machine.drive import READY_FOR_CONTROL_LOOP_ON, READY_FOR_POWER_ON
from nc_sim.machine.machine import Machine
from nc_sim.units import RPM_TO_DEG_S, AxisKind

_LOOP: dict[int, Literal["open", "closed", "control_limit", "speed_control"]] = {
    L.LOOP_CLOSED: "closed",
    L.LOOP_CONTROL_LIMIT: "control_limit",
    L.LOOP_SPEED_CONTROL: "speed_control",
}


_KIND: dict[AxisKind, Literal["linear", "rotary", "spindle"]] = {
    AxisKind.LINEAR: "linear",
    AxisKind.ROTARY: "rotary",
    AxisKind.SPINDLE: "spindle",
}


RECENT_EVENTS = 50  # events a status snapshot carries


def _axis_status(m: Machine, ax: Axis) -> AxisStatus:
    st, ist = m.k.st[ax.slot], m.k.ist[ax.slot]
    spindle = ax.kind is AxisKind.SPINDLE
    vel_scale = 1.0 / RPM_TO_DEG_S if spindle else 60.0
    target, to_go = target_and_distance(m.k, ax)
    drive = ax.drive.reported()
    return AxisStatus(
        name=ax.name,
        kind=_KIND[ax.kind],
        state=ax.state.name,
        unit="mm" if ax.kind is AxisKind.LINEAR else "deg",
        pos_cmd=float(st[L.S_P_CMD]),
        pos_act=float(st[L.S_P_ACT]),
        lag=float(st[L.S_LAG]),
        vel_cmd=float(st[L.S_V_CMD]) * vel_scale,
        vel_act=float(st[L.S_V_ACT]) * vel_scale,
        homed=bool(ist[L.I_HOMED]),
        in_position=bool(ist[L.I_IN_POS]),
        target_pos=target,
        distance_to_go=to_go,
        enabled=ax.enables_ok(),
        missing_enables=ax.missing_enables(),
        ready_for_power_on=drive.get(READY_FOR_POWER_ON),
        ready_for_control_loop_on=drive.get(READY_FOR_CONTROL_LOOP_ON),
        control_units=dict(ax.units),
        override_pct=float(st[L.S_OVERRIDE]) * 100.0,
        job_error=ax.job_error,
        gear=ax.gear if spindle else None,
        speed_prog_rpm=abs(ax.speed_prog) / RPM_TO_DEG_S if spindle else None,
        speed_reached=bool(ist[L.I_SPEED_REACHED]) if spindle else None,
        stopped=bool(ist[L.I_STOPPED]) if spindle else None,
        speed_monitoring_active=bool(ist[L.I_MON_ACTIVE]) if spindle else None,
        speed_monitoring_invalid=bool(ist[L.I_MON_INVALID]) if spindle else None,
        # without its enables the drive does not follow: no loop is closed, whatever the mode
        loop=_LOOP.get(int(ist[L.I_OPEN_LOOP]), "closed") if ist[L.I_ENABLED] else "open",
    )


def machine_status(host: MachineHost) -> MachineStatus:
    """Everything the HMI shows about a machine, consistent to one cycle."""
    m = host.machine
    host.event_index.update(m.events)  # only the events since the last status
    latest: dict[str, JobError] = {}
    for ax in m.axes:  # the event that set each axis' job error (channel-wide ones too)
        e = host.event_index.newest(ax.job_error, (ax.name, "")) if ax.job_error else None
        if e is not None:
            latest[ax.name] = e
    # one entry per distinct error: an emergency stop is one error, not one per axis
    distinct = {(e.cycle, e.code, e.axis): e for e in latest.values()}
    return MachineStatus(
        id=host.id,
        name=host.name,
        simulation=simulation_status(host.pacing_now()),
        channel_units=dict(m.channel_units),
        emergency_stop=m.estop,
        queued_blocks=m.queued_blocks,
        axes=[_axis_status(m, ax) for ax in m.axes],
        plc=PlcStatus(
            mode=m.plc.mode.value,
            ack_delay_s=m.plc.delay_cycles * host.cycle_s,
            drives_powered=m.powered,
            pending=[PendingM(m=p.m, axis=p.axis, out_cycle=p.out_cycle) for p in m.plc.pending],
        ),
        job_errors=[job_error_model(e) for e in distinct.values()],
        recent_events=[job_error_model(e) for e in m.events.tail(RECENT_EVENTS)],
    )
