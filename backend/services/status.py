"""Status as the gateway serves it: a machine's (fresh from its worker), its pacing, the
machine list, and the workers of the service."""

from __future__ import annotations

from typing import Literal, cast

from api.assist import AssistProgress
from api.status import (
    AxisSignals,
    AxisStatus,
    ChangeoverPhase,
    ChannelStatus,
    HomingPhaseName,
    HomingProgress,
    LoopStatus,
    MachineStatus,
    MachineSummary,
    ModalStatus,
    OverrunRecord,
    PendingM,
    PlcStatus,
    SimulationStatus,
    SpindleModeName,
    WorkerStatus,
)
from api.telemetry import SignalInfo
from backend.services.commands import job_error_model
from backend.services.machines import MachineProxy, MachineService
from backend.workers.client import WorkerClient
from backend.workers.protocol import (
    LoopFigures,
    Pace,
    Pacing,
    ReadStatus,
    StatusRead,
    Step,
    WorkerNews,
)
from nc_sim.snapshot import AxisSnapshot, ChannelSnapshot, LoopMode, MachineSnapshot
from nc_sim.units import AxisKind

RECENT_EVENTS = 50  # events a machine's status carries

AXIS_KIND: dict[AxisKind, Literal["linear", "rotary", "spindle"]] = {
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


def simulation_status(p: Pacing, epoch: int) -> SimulationStatus:
    """Pacing and time of a machine's build `epoch` as its worker reported it."""
    return SimulationStatus(
        mode=p.mode,
        cycle=p.cycle,
        epoch=epoch,
        t_s=p.cycle * p.cycle_s,
        cycle_s=p.cycle_s,
        rt_factor=p.rt_factor,
        until_cycle=p.until_cycle,
        t0_unix=p.t0_unix,
        slips=p.slips,
    )


def _loop_figures(worker: WorkerClient | None) -> LoopFigures | None:
    news = worker.latest if worker is not None else None
    return news.loop if isinstance(news, WorkerNews) else None


def with_loop_health(sim: SimulationStatus, worker: WorkerClient | None) -> SimulationStatus:
    """The machine's own loop health: its worker and that worker's overruns and work."""
    sim.worker = worker.id if worker is not None else None
    loop = _loop_figures(worker)
    if loop is not None:
        sim.loop_overruns, sim.loop_work_p99_ms = loop.overruns, loop.work_p99_ms
    return sim


def _signals(a: AxisSnapshot) -> AxisSignals:
    s = a.signals
    assert s is not None
    return AxisSignals(
        homed=s.homed,
        mvpos=s.moving_positive,
        mvneg=s.moving_negative,
        ready=s.ready,
        inpos=s.in_position,
        n_act_eq_n_comm=s.speed_reached,
        n_act_zero=s.stopped,
        gear_bits=list(s.gear_bits) if s.gear_bits is not None else None,
        rotary_mode=s.rotary_mode,
    )


def _axis_status(a: AxisSnapshot) -> AxisStatus:
    sp = a.spindle
    return AxisStatus(
        name=a.name,
        kind=AXIS_KIND[a.kind],
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
        display_name=a.display_name or a.name,
        spindle_mode=cast(SpindleModeName, sp.mode) if sp and sp.mode else None,
        changeover=cast(ChangeoverPhase, sp.changeover) if sp and sp.changeover else None,
        signals=_signals(a),
        homing=HomingProgress(
            phase=cast(HomingPhaseName, a.homing.phase),
            moved=a.homing.moved,
            to_go=a.homing.to_go,
            speed=a.homing.speed,
        )
        if a.homing
        else None,
    )


def channel_status(c: ChannelSnapshot) -> ChannelStatus:
    """The channel in the API's words."""
    md = c.modal
    return ChannelStatus(
        state=c.state.name.lower(),
        program=c.program,
        block_line=c.block_line,
        blocks_done=c.blocks_done,
        single_block=c.single_block,
        mdi=c.mdi,
        modal=ModalStatus(
            motion=f"G{md.motion:02d}",
            plane=f"G{md.plane}",
            distance="G90" if md.absolute else "G91",
            feed_mm_min=md.feed_mm_min,
            slope=md.slope,
            manual_mode="G201" if md.parallel_manual else "G200",
        ),
        path_feed_mm_min=c.path_feed_mm_min,
        distance_to_go_mm=c.distance_to_go_mm,
        waiting_for=c.waiting_for,
        error=job_error_model(c.error) if c.error else None,
    )


def status_of(m: MachineProxy, read: StatusRead, recent_events: bool = True) -> MachineStatus:
    """A machine's snapshot and pacing, as its worker read them, in the API's words, with
    the newest events of the gateway's copy of its log (`recent_events`; a viewer's pushed
    status goes without them: its events come as event messages)."""
    snap: MachineSnapshot = read.snapshot
    return MachineStatus(
        id=m.id,
        name=m.name,
        simulation=with_loop_health(simulation_status(read.pacing, m.link.epoch), m.link.worker),
        channel_units=dict(snap.channel_units),
        emergency_stop=snap.emergency_stop,
        queued_blocks=snap.queued_blocks,
        channel=channel_status(snap.channel),
        axes=[_axis_status(a) for a in snap.axes],
        plc=PlcStatus(
            mode=snap.plc.mode.value,
            ack_delay_s=snap.plc.ack_delay_s,
            drives_powered=snap.plc.drives_powered,
            pending=[
                PendingM(
                    m=p.m,
                    axis=p.axis,
                    out_cycle=p.out_cycle,
                    signal=p.signal,
                    timeout_cycle=p.timeout_cycle,
                )
                for p in snap.plc.pending
            ],
            signals=dict(snap.plc.signals),
        ),
        job_errors=[job_error_model(e) for e in snap.job_errors],
        recent_events=[job_error_model(e) for e in m.link.recent_events(RECENT_EVENTS)]
        if recent_events
        else [],
        control=m.control.state(),
        assist=AssistProgress(**vars(read.assist)) if read.assist is not None else None,
    )


async def machine_status(m: MachineProxy) -> MachineStatus:
    """Everything the HMI shows about a machine, fresh from its worker (one cycle)."""
    read = await m.link.acall(ReadStatus(m.id))
    assert isinstance(read, StatusRead)
    return status_of(m, read)


def machine_simulation(m: MachineProxy) -> SimulationStatus:
    """The machine's pacing as last reported (about a second old at most), its cycle live."""
    p = m.link.pacing
    if p is None:
        p = Pacing("run", m.link.cycle, m.link.cycle_s, 0.0, None, 0.0, 0)
    sim = simulation_status(p, m.link.epoch)
    sim.cycle = max(sim.cycle, m.link.cycle)
    sim.t_s = sim.cycle * sim.cycle_s
    return with_loop_health(sim, m.link.worker)


def signal_infos(m: MachineProxy) -> list[SignalInfo]:
    """Every signal the machine records each cycle, for the catalogue and `hello`."""
    return [SignalInfo(name=s.name, axis=s.axis, unit=s.unit, kind=s.kind) for s in m.link.signals]


def machine_summary(m: MachineProxy) -> MachineSummary:
    return MachineSummary(
        id=m.id,
        name=m.name,
        source="demo" if m.source == "demo" else "lists",
        axes=list(m.link.info.axes) if m.link.info else [],
        mode=m.link.pacing.mode if m.link.pacing else "run",
        cycle=m.link.cycle,
        seat=m.exercise is not None,
    )


def loop_status(f: LoopFigures) -> LoopStatus:
    return LoopStatus(
        period_s=f.period_s,
        ticks=f.ticks,
        overruns=f.overruns,
        missed_deadlines=f.missed_deadlines,
        work_p50_ms=f.work_p50_ms,
        work_p99_ms=f.work_p99_ms,
        work_max_ms=f.work_max_ms,
        wake_late_p99_ms=f.wake_late_p99_ms,
        recent_overruns=[
            OverrunRecord(time_unix=t, wake_late_ms=late, work_ms=w)
            for t, late, w in f.recent_overruns
        ],
        host_failures=f.host_failures,
        cpu_pct=f.cpu_pct,
    )


def worker_statuses(machines: MachineService) -> list[WorkerStatus]:
    """Every worker of the pool with its machines and loop figures."""
    out = []
    for w in machines.pool.workers:
        loop = _loop_figures(w)
        out.append(
            WorkerStatus(
                id=w.id,
                pid=w.pid,
                node=w.node,
                alive=w.alive,
                machines=[p.id for p in machines.on_machine(w)],
                loop=loop_status(loop) if loop is not None else None,
            )
        )
    return out


def paced(machine: MachineProxy, request: Pace | Step) -> SimulationStatus:
    """Carry out a pacing request (run, pause, fast, step); the answer is the pacing it
    left."""
    p = machine.link.call(request)
    assert isinstance(p, Pacing)
    machine.link.pacing = p
    return with_loop_health(simulation_status(p, machine.link.epoch), machine.link.worker)
