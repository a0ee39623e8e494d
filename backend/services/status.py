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
from nc_sim.snapshot import AxisSnapshot, LoopMode
from nc_sim.units import AxisKind

_KIND: dict[AxisKind, Literal["linear", "rotary", "spindle"]] = {
    AxisKind.LINEAR: "linear",
    AxisKind.ROTARY: "rotary",
    AxisKind.SPINDLE: "spindle",
}
_LOOP: dict[LoopMode, Literal["open", "closed", "control_limit", "speed_control"]] = {
    LoopMode.OPEN: "open",
    LoopMode.CLOSED: "closed",
    LoopMode.CONTROL_LIMIT: "control_limit",
    LoopMode.SPEED_CONTROL: "speed_control",
}


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


def _axis_status(a: AxisSnapshot) -> AxisStatus:
    sp = a.spindle
    return AxisStatus(
        name=a.name,
        kind=_KIND[a.kind],
        state=a.state,
        unit=a.pos_unit,
        pos_cmd=a.pos_cmd,
        pos_act=a.pos_act,
        lag=a.lag,
        vel_cmd=a.vel_cmd,
        vel_act=a.vel_act,
        homed=a.homed,
        in_position=a.in_position,
        target_pos=a.target_pos,
        distance_to_go=a.distance_to_go,
        enabled=a.enabled,
        missing_enables=list(a.missing_enables),
        ready_for_power_on=a.ready_for_power_on,
        ready_for_control_loop_on=a.ready_for_control_loop_on,
        control_units=dict(a.control_units),
        override_pct=a.override_pct,
        job_error=a.job_error,
        gear=sp.gear if sp else None,
        speed_prog_rpm=sp.speed_prog_rpm if sp else None,
        speed_reached=sp.speed_reached if sp else None,
        stopped=sp.stopped if sp else None,
        speed_monitoring_active=sp.speed_monitoring_active if sp else None,
        speed_monitoring_invalid=sp.speed_monitoring_invalid if sp else None,
        loop=_LOOP[a.loop],
    )


def machine_status(host: MachineHost) -> MachineStatus:
    """Everything the HMI shows about a machine, consistent to one cycle: the machine's
    snapshot in the API's words."""
    with host.lock:
        snap = host.machine.snapshot()
        return MachineStatus(
            id=host.id,
            name=host.name,
            simulation=simulation_status(host),
            channel_units=dict(snap.channel_units),
            emergency_stop=snap.emergency_stop,
            queued_blocks=snap.queued_blocks,
            axes=[_axis_status(a) for a in snap.axes],
            plc=PlcStatus(
                mode=snap.plc.mode.value,
                ack_delay_s=snap.plc.ack_delay_s,
                drives_powered=snap.plc.drives_powered,
                pending=[
                    PendingM(m=p.m, axis=p.axis, out_cycle=p.out_cycle) for p in snap.plc.pending
                ],
            ),
            job_errors=[job_error_model(e) for e in snap.job_errors],
            recent_events=[job_error_model(e) for e in snap.recent_events],
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
