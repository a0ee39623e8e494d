"""Reading a machine into its snapshot (nc_sim/snapshot.py): every kernel column and every
unit conversion a status needs happens here, between cycles, in O(axes)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from nc_sim.axis.drive import READY_FOR_CONTROL_LOOP_ON, READY_FOR_POWER_ON
from nc_sim.axis.homing import Homing
from nc_sim.axis.params import in_modulo, modulo_range
from nc_sim.axis.state import Axis, target_and_distance
from nc_sim.kernel import layout as L
from nc_sim.kernel.step import moving_direction
from nc_sim.machine.channel_ops import PROGRAM_ACTIVE
from nc_sim.machine.core import MachineCore
from nc_sim.snapshot import (
    SETTLING,
    AxisSnapshot,
    AxisState,
    ChannelSnapshot,
    HomingSnapshot,
    InterfaceSignals,
    LoopMode,
    MachineSnapshot,
    ModalSnapshot,
    PendingMSnapshot,
    PlcSnapshot,
    SpindleSnapshot,
)
from nc_sim.units import AxisKind, Quantity, display_velocity, to_raw

if TYPE_CHECKING:
    from nc_sim.spindle.caxis import CAxis

_LOOP = {
    L.LOOP_CLOSED: LoopMode.CLOSED,
    L.LOOP_CONTROL_LIMIT: LoopMode.CONTROL_LIMIT,
    L.LOOP_SPEED_CONTROL: LoopMode.SPEED_CONTROL,
}


def axis_snapshot(m: MachineCore, ax: Axis) -> AxisSnapshot:
    """One axis or spindle as the HLI shows it now."""
    st, ist = m.k.st[ax.slot], m.k.ist[ax.slot]
    cax = m.cax if m.cax is not None and m.cax.ax is ax else None
    shown = AxisKind.ROTARY if cax is not None and cax.rotary else ax.kind  # C: °/min
    vel_cmd, vel_unit = display_velocity(float(st[L.S_V_CMD]), shown)
    vel_act, _ = display_velocity(float(st[L.S_V_ACT]), shown)
    target, to_go = target_and_distance(m.k, ax)
    on_path = m.ch_host.block_target(ax)
    if on_path is not None:
        target, to_go = on_path, on_path - float(st[L.S_P_CMD])
    drive = ax.drive.reported()
    pos_cmd, pos_act = float(st[L.S_P_CMD]), float(st[L.S_P_ACT])
    if ax.kind is AxisKind.SPINDLE:  # a modulo axis: shown within its range [000 §3.2.2]
        lo, hi = modulo_range(ax.cfg, ax.gear)
        pos_cmd, pos_act = in_modulo(pos_cmd, lo, hi), in_modulo(pos_act, lo, hi)
        target = None if target is None else in_modulo(target, lo, hi)
    spindle = None
    if ax.kind is AxisKind.SPINDLE:
        spindle = SpindleSnapshot(
            gear=ax.gear,
            speed_prog_rpm=display_velocity(abs(ax.speed_prog), ax.kind)[0],
            speed_reached=bool(ist[L.I_SPEED_REACHED]),
            stopped=bool(ist[L.I_STOPPED]),
            speed_monitoring_active=bool(ist[L.I_MON_ACTIVE]),
            speed_monitoring_invalid=bool(ist[L.I_MON_INVALID]),
            mode=cax.mode.value if cax else None,
            changeover=cax.phase if cax else None,
        )
    return AxisSnapshot(
        name=ax.name,
        kind=ax.kind,
        state=_shown_state(m, ax, to_go),
        pos_unit="mm" if ax.kind is AxisKind.LINEAR else "deg",
        vel_unit=vel_unit,
        pos_cmd=pos_cmd,
        pos_act=pos_act,
        lag=float(st[L.S_LAG]),
        vel_cmd=vel_cmd,
        vel_act=vel_act,
        homed=bool(ist[L.I_HOMED]),
        in_position=bool(ist[L.I_IN_POS]),
        target_pos=target,
        distance_to_go=to_go,
        enabled=ax.enables_ok(),
        missing_enables=tuple(ax.missing_enables()),
        ready_for_power_on=drive.get(READY_FOR_POWER_ON),
        ready_for_control_loop_on=drive.get(READY_FOR_CONTROL_LOOP_ON),
        control_units=dict(ax.units),
        override_pct=to_raw(Quantity.PERCENT, float(st[L.S_OVERRIDE])),
        job_error=ax.job_error,
        # without its enables the drive does not follow: no loop is closed, whatever the mode
        loop=_LOOP.get(int(ist[L.I_OPEN_LOOP]), LoopMode.CLOSED)
        if ist[L.I_ENABLED]
        else LoopMode.OPEN,
        spindle=spindle,
        display_name=cax.display_name if cax else ax.name,
        signals=_signals(m, ax, spindle is not None, cax),
        homing=_homing(ax),
    )


def _shown_state(m: MachineCore, ax: Axis, to_go: float | None) -> str:
    """The state as the axis itself is, not only its set-point: a set-point at rest with the
    axis still moving into its window is SETTLING (its lag outside the exact-stop window,
    kenngr.exact_stop_window, the NC's in-position criterion; a spindle until it reports
    stopped), and a path axis the current block does not move (no distance to go, no speed
    commanded) stands still (the path drives every path axis, so the NC counts it as
    moving)."""
    st, ist = m.k.st[ax.slot], m.k.ist[ax.slot]
    state = ax.state
    if (
        state is AxisState.MOVING
        and m.ch_host.block_target(ax) is not None
        and float(st[L.S_V_CMD]) == 0.0
        and to_go is not None
        and abs(to_go) <= 1e-9
    ):
        state = AxisState.STANDSTILL
    if state is not AxisState.STANDSTILL or not ist[L.I_ENABLED]:
        return state.name  # without its enables the drive does not follow: nothing settles
    if ax.kind is AxisKind.SPINDLE and (m.cax is None or m.cax.ax is not ax or not m.cax.rotary):
        settled = bool(ist[L.I_STOPPED])
    else:
        settled = abs(float(st[L.S_LAG])) <= float(m.k.pr[ax.slot, L.P_INPOS_WIN])
    return state.name if settled else SETTLING


def _homing(ax: Axis) -> HomingSnapshot | None:
    """The G74 of an axis in progress, in display units."""
    seq = ax.sequence
    if not isinstance(seq, Homing):
        return None
    phase, moved, to_go, speed = seq.progress()
    return HomingSnapshot(phase, moved, to_go, display_velocity(speed, ax.kind)[0])


def _signals(m: MachineCore, ax: Axis, spindle: bool, cax: CAxis | None) -> InterfaceSignals:
    """The 003 §4.2 status signals, as the kernel records them."""
    st, ist = m.k.st[ax.slot], m.k.ist[ax.slot]
    way = moving_direction(float(st[L.S_V_ACT]), float(m.k.pr[ax.slot, L.P_INPOS_WIN]))
    return InterfaceSignals(
        homed=bool(ist[L.I_HOMED]),
        moving_positive=way > 0,
        moving_negative=way < 0,
        ready=bool(ist[L.I_ENABLED]),  # as recorded (R_READY): the drive follows the NC
        in_position=bool(ist[L.I_IN_POS]),
        speed_reached=bool(ist[L.I_SPEED_REACHED]) if spindle else None,
        stopped=bool(ist[L.I_STOPPED]) if spindle else None,
        gear_bits=(bool(ax.gear & 1), bool(ax.gear & 2), bool(ax.gear & 4)) if spindle else None,
        rotary_mode=cax.rotary if cax else None,
    )


def _zero_passage(m: MachineCore) -> str | None:
    """A G33 thread waiting for its coupling angle, in the operator's words."""
    e = m.channel.path.current
    if e is None or e.coupling is None:
        return None
    c = e.coupling
    if c.kind != L.COUPLE_THREAD or m.channel.path.s > e.s0:
        return None
    name = m.ch_host.spindle_name(c.spindle)
    return f"zero passage of {name} at {c.theta0_deg % 360.0:g}° (G33)"


def channel_snapshot(m: MachineCore) -> ChannelSnapshot:
    """The channel's program state and modal state now."""
    ch = m.channel
    c = ch.progress
    g, plane, absolute, feed = ch.modal  # of the block the program's path is in
    if c.state not in PROGRAM_ACTIVE or c.mdi:  # what the next MDI block starts from
        md = ch.mdi.modal
        g, plane, absolute, feed = md.motion, md.plane, md.absolute, md.feed_mm_min
    return ChannelSnapshot(
        state=c.state,
        program=c.program.name if c.program else None,
        block_line=c.block_line,
        blocks_done=c.blocks_done,
        single_block=c.single_block,
        mdi=c.mdi,
        modal=ModalSnapshot(
            motion=g,
            plane=plane,
            absolute=absolute,
            feed_mm_min=feed,
            slope=m.slope,
            parallel_manual=m.motion.ctx.parallel_manual,
        ),
        path_feed_mm_min=ch.path_feed_mm_min(),
        distance_to_go_mm=ch.distance_to_go_mm(),
        waiting_for=c.waiting_for or _zero_passage(m),
        error=c.error,
        axes=ch.axes,
        rotary_axis=m.cax.c_name if m.cax else None,
        rotary=m.cax.rotary if m.cax else False,
    )


def machine_snapshot(m: MachineCore) -> MachineSnapshot:
    """The whole machine now (its events are read from `m.events` by cursor)."""
    # the event that set each axis' job error, once: an emergency stop is one error
    active = {e.seq: e for ax in m.axes if (e := ax.error_event) is not None}
    return MachineSnapshot(
        cycle=m.cycle,
        t_s=m.t_s,
        channel_units=dict(m.channel_units),
        emergency_stop=m.estop,
        queued_blocks=m.queued_blocks,
        channel=channel_snapshot(m),
        axes=tuple(axis_snapshot(m, ax) for ax in m.axes),
        plc=PlcSnapshot(
            mode=m.plc.mode,
            ack_delay_s=m.plc.delay_cycles * m.k.cycle_s,
            drives_powered=m.powered,
            pending=tuple(
                PendingMSnapshot(
                    p.m, p.axis, p.out_cycle, p.signal, p.out_cycle + m.handshake.timeout_cycles
                )
                for p in m.plc.pending
            ),
            signals=tuple(sorted({**m.cax.requests, **m.plc.signals}.items())) if m.cax else (),
        ),
        job_errors=tuple(active[s] for s in sorted(active)),
        event_cursor=m.events.cursor,
    )
