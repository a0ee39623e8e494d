"""A machine's scope as the service offers it: setup from the API model, arm, force, stop.

The scope runs in the machine's worker, where the cycles are; completed captures are pushed
to the gateway with the machine's news."""

from __future__ import annotations

import time

import numpy as np

from api.auth import ALLOWED, Action
from api.scope import (
    MAX_DRIVE_LENGTH_S,
    ChannelInfo,
    EventTriggerModel,
    LevelTriggerModel,
    ScopeSetupModel,
    ScopeStatus,
)
from api.telemetry import FrameHeader, encode_frame
from backend.errors import ApiError, Conflict, Forbidden, Invalid
from backend.services.auth import Actor
from backend.services.machines import MachineProxy
from backend.services.recorder import Recorders
from backend.services.traces import TraceService
from backend.workers.protocol import Roll, ScopeAct, ScopeArm, ScopeRoll, ScopeState
from nc_sim.scope import (
    EventKind,
    EventTrigger,
    LevelTrigger,
    ScopeMode,
    ScopeSetup,
    Trigger,
)
from nc_sim.signals import Signal


def _unknown(m: MachineProxy, names: list[str], what: str) -> ApiError:
    bad = [n for n in names if n not in m.link.signal_by_name]
    return Invalid(f"{what}: unknown signals {bad}")


def engine_setup(m: MachineProxy, req: ScopeSetupModel) -> tuple[ScopeSetup, list[Signal]]:
    """The kernel-side setup and the drive signals of a drive-rate capture (else none); 422
    naming an unknown signal or axis, a length too long, or what a drive-rate capture
    cannot do."""
    drive: list[Signal] = []
    if req.rate == "drive":
        drive = _drive_channels(m, req)
    elif any(n not in m.link.signal_by_name for n in req.channels):
        raise _unknown(m, req.channels, "channels")
    trigger: Trigger | None = None
    t = req.trigger
    if isinstance(t, LevelTriggerModel):
        if t.signal not in m.link.signal_by_name:
            why = " (a trigger is the NC's: a drive signal cannot trigger)" if drive else ""
            raise Invalid(f"trigger: unknown signals {[t.signal]}{why}")
        sig = m.link.signal_by_name[t.signal]
        trigger = LevelTrigger(sig, t.level, t.edge == "rising", t.hysteresis)
    elif isinstance(t, EventTriggerModel):
        if t.axis is not None and t.axis not in m.link.axes:
            raise Invalid(f"trigger: no axis {t.axis}")
        trigger = EventTrigger(EventKind(t.event), t.axis, t.m)
    length = round(req.length_s / m.link.cycle_s)
    # a drive-rate capture's NC record only finds the trigger and the span: one signal
    channels = (
        [m.link.signal_by_name[n] for n in req.channels]
        if not drive
        else [next(s for s in m.link.signal_by_name.values() if s.axis == drive[0].axis)]
    )
    setup = ScopeSetup(channels, length, req.pretrigger_pct, ScopeMode(req.mode), trigger)
    try:
        setup.check()
    except ValueError as e:
        raise Invalid(str(e)) from None
    return setup, drive


def _drive_channels(m: MachineProxy, req: ScopeSetupModel) -> list[Signal]:
    known = m.link.drive_signal_by_name
    if any(n not in known for n in req.channels):
        bad = [n for n in req.channels if n not in known]
        raise Invalid(f"channels: {bad} are no drive signals (`<axis>.drive.*`)")
    drive = [known[n] for n in req.channels]
    axes = sorted({s.axis for s in drive})
    if len(axes) > 1:
        raise Invalid(f"channels: a drive-rate capture records one axis' drive, got {axes}")
    if req.mode == "roll":
        raise Invalid("mode: a drive-rate capture is single or normal (a trace, not a roll)")
    if req.length_s > MAX_DRIVE_LENGTH_S:
        raise Invalid(f"length_s: a drive-rate capture is 0 … {MAX_DRIVE_LENGTH_S:g} s")
    return drive


def _busy(m: MachineProxy) -> bool:
    """The scope records for someone (armed, triggered, rolling)."""
    st = m.link.call(ScopeAct(m.id, "state"))
    assert isinstance(st, ScopeState)
    return st.state in ("roll", "armed", "triggered")


def _theirs(m: MachineProxy, actor: Actor, take_over: bool, what: str) -> str | None:
    """Pass when the scope is idle, done or the actor's own; 409 when another person's
    (unless `take_over` by one who may: the control holder, an instructor or admin, 403 for
    others). The owner it is taken from, in words, or None."""
    owner = m.captures.owner
    if owner is None or owner[2] == actor.session or not _busy(m):
        return None
    who = f"{owner[0]} ({owner[1]})"
    since = time.strftime("%H:%M:%S", time.localtime(m.captures.armed_unix or 0))
    if not take_over:
        raise Conflict(
            f"the scope is {who}'s (armed at {since}) and still records: {what} would end "
            "their capture; ask them, or take it over"
        )
    holder = m.control.holder
    if Action.TAKE_CONTROL not in ALLOWED[actor.role] and (
        holder is None or holder.session != actor.session
    ):
        raise Forbidden(
            f"the scope is {who}'s: only the machine's control holder, an instructor or an "
            "admin may take it over"
        )
    return who


def arm(m: MachineProxy, req: ScopeSetupModel, actor: Actor) -> str | None:
    """(Re)arm the scope with a setup; a capture in progress is dropped. Another person's
    scope only with `take_over` (see `_theirs`); whose it was then, else None."""
    setup, drive = engine_setup(m, req)
    taken = _theirs(m, actor, req.take_over, "arming it")
    m.link.call(ScopeArm(m.id, setup, drive))
    m.captures.setup = req.model_copy(update={"take_over": False})
    m.captures.owner = (actor.name, actor.role.value, actor.session)
    m.captures.armed_unix = time.time()
    if taken is not None:
        m.notices.add("message", f"{actor.name}: took over the scope from {taken}")
    return taken


def force(m: MachineProxy, actor: Actor) -> None:
    """Trigger an armed scope now (one's own, or taken over as for arming)."""
    _theirs(m, actor, True, "triggering it")
    m.link.call(ScopeAct(m.id, "force"))


def stop(m: MachineProxy, actor: Actor) -> None:
    """Stop recording; a capture in progress is dropped (one's own, or as for arming)."""
    _theirs(m, actor, True, "stopping it")
    m.link.call(ScopeAct(m.id, "stop"))


def status(m: MachineProxy, traces: TraceService, recorders: Recorders) -> ScopeStatus:
    st = m.link.call(ScopeAct(m.id, "state"))
    assert isinstance(st, ScopeState)
    idle = st.length_cycles == 0
    owner = m.captures.owner
    setup = m.captures.setup if not idle else None
    assert setup is None or isinstance(setup, ScopeSetupModel)
    return ScopeStatus(
        state=st.state,
        setup=setup,
        cycle=st.cycle,
        length_cycles=st.length_cycles,
        pre_cycles=st.pre_cycles,
        filled_cycles=st.filled_cycles,
        trigger_cycle=st.trigger_cycle,
        captures=traces.recent(m),
        recording=recorders.info(m.id),
        drive_channels=[
            ChannelInfo(name=s.name, unit=s.unit, kind="float")
            for s in m.link.drive_signal_by_name.values()
        ],
        armed_by=f"{owner[0]} ({owner[1]})" if owner is not None and not idle else None,
        armed_unix=m.captures.armed_unix if owner is not None and not idle else None,
    )


def roll_frame(m: MachineProxy, max_points: int) -> bytes:
    """The newest record length of the running scope as a binary frame, every `stride`-th
    cycle so that at most `max_points` samples per channel go out (a roll is for watching;
    a capture carries every cycle)."""
    roll = m.link.call(ScopeRoll(m.id, max_points))
    assert isinstance(roll, Roll)
    data = roll.data
    assert isinstance(data, np.ndarray)
    t0 = m.link.pacing.t0_unix if m.link.pacing else 0.0
    header = FrameHeader(
        machine=m.id,
        first_cycle=roll.first_cycle,
        count=data.shape[1],
        stride=roll.stride,
        cycle_s=m.link.cycle_s,
        t0_unix=t0,
        signals=roll.signals,
        decimated=roll.stride > 1,
        skipped_cycles=0,
    )
    return encode_frame(header, data)
