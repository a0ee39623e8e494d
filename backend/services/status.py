"""Status snapshots of a hosted machine, read between kernel batches."""

from __future__ import annotations

from typing import Literal

from api.status import (
    AxisStatus,
    MachineStatus,
    MachineSummary,
    PendingM,
    PlcStatus,
    SimMode,
    SimulationStatus,
)
from api.telemetry import SignalInfo
from backend.services.commands import job_error_model
from backend.services.host import MachineHost
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


def _mode(host: MachineHost) -> SimMode:
    mode = host.pacing.mode
    return "fast" if mode == "fast" else "pause" if mode == "pause" else "run"


def simulation_status(host: MachineHost) -> SimulationStatus:
    """Pacing and time of a machine, consistent to one cycle (the loop thread steps it)."""
    with host.lock:
        return SimulationStatus(
            mode=_mode(host),
            cycle=host.cycle,
            t_s=host.cycle * host.cycle_s,
            cycle_s=host.cycle_s,
            rt_factor=host.rt_factor(),
            until_cycle=host.pacing.until_cycle,
            t0_unix=host.t0_unix(),
            slips=host.pacing.slips,
        )


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
    with host.lock:
        m = host.machine
        # the event that set each axis' job error, once: an emergency stop is one error
        distinct = {e.seq: e for ax in m.axes if (e := ax.error_event) is not None}
        return MachineStatus(
            id=host.id,
            name=host.name,
            simulation=simulation_status(host),
            channel_units=dict(m.channel_units),
            emergency_stop=m.estop,
            queued_blocks=m.queued_blocks,
            axes=[_axis_status(m, ax) for ax in m.axes],
            plc=PlcStatus(
                mode=m.plc.mode.value,
                ack_delay_s=m.plc.delay_cycles * host.cycle_s,
                drives_powered=m.powered,
                pending=[
                    PendingM(m=p.m, axis=p.axis, out_cycle=p.out_cycle) for p in m.plc.pending
                ],
            ),
            job_errors=[job_error_model(e) for e in distinct.values()],
            recent_events=[job_error_model(e) for e in m.events.tail(RECENT_EVENTS)],
        )


def signal_infos(host: MachineHost) -> list[SignalInfo]:
    """Every signal the machine records each cycle, for the catalogue and `hello`."""
    return [SignalInfo(name=s.name, axis=s.axis, unit=s.unit, kind=s.kind) for s in host.signals]


def machine_summary(host: MachineHost) -> MachineSummary:
    with host.lock:
        return MachineSummary(
            id=host.id,
            name=host.name,
            source="demo" if host.source == "demo" else "lists",
            axes=[ax.name for ax in host.machine.axes],
            mode=_mode(host),
            cycle=host.cycle,
        )
