"""A machine's scope as the service offers it: setup from the API model, arm, force, stop."""

from __future__ import annotations

from api.scope import EventTriggerModel, LevelTriggerModel, ScopeSetupModel, ScopeStatus
from api.telemetry import FrameHeader, encode_frame
from backend.errors import ApiError
from backend.services.host import MachineHost
from backend.services.recorder import Recorders
from backend.services.traces import TraceService
from nc_sim.scope import (
    EventKind,
    EventTrigger,
    LevelTrigger,
    ScopeMode,
    ScopeSetup,
    Trigger,
)


def _unknown(host: MachineHost, names: list[str], what: str) -> ApiError:
    bad = [n for n in names if n not in host.signal_by_name]
    return ApiError(422, {"message": f"{what}: unknown signals {bad}"})


def engine_setup(host: MachineHost, req: ScopeSetupModel) -> ScopeSetup:
    """The kernel-side setup; 422 naming an unknown signal or axis or a length too long."""
    if any(n not in host.signal_by_name for n in req.channels):
        raise _unknown(host, req.channels, "channels")
    trigger: Trigger | None = None
    t = req.trigger
    if isinstance(t, LevelTriggerModel):
        if t.signal not in host.signal_by_name:
            raise _unknown(host, [t.signal], "trigger")
        sig = host.signal_by_name[t.signal]
        trigger = LevelTrigger(sig, t.level, t.edge == "rising", t.hysteresis)
    elif isinstance(t, EventTriggerModel):
        if t.axis is not None and t.axis not in host.machine.by_name:
            raise ApiError(422, {"message": f"trigger: no axis {t.axis}"})
        trigger = EventTrigger(EventKind(t.event), t.axis, t.m)
    length = round(req.length_s / host.cycle_s)
    setup = ScopeSetup(
        [host.signal_by_name[n] for n in req.channels],
        length,
        req.pretrigger_pct,
        ScopeMode(req.mode),
        trigger,
    )
    try:
        setup.check()
    except ValueError as e:
        raise ApiError(422, {"message": str(e)}) from None
    return setup


def arm(host: MachineHost, req: ScopeSetupModel) -> None:
    """(Re)arm the scope with a setup; a capture in progress is dropped."""
    setup = engine_setup(host, req)
    with host.lock:
        host.scope_setup = req
        host.scope.arm(setup, host.cycle, host.history(setup.length_cycles), host.machine.events)


def force(host: MachineHost) -> None:
    """Trigger an armed scope now."""
    with host.lock:
        host.scope.force()


def stop(host: MachineHost) -> None:
    """Stop recording; a capture in progress is dropped."""
    with host.lock:
        host.scope.stop()


def status(host: MachineHost, traces: TraceService, recorders: Recorders) -> ScopeStatus:
    with host.lock:
        sc = host.scope
        setup = sc.setup
        out = ScopeStatus(
            state=sc.state.value,
            setup=host.scope_setup if setup is not None else None,
            cycle=host.cycle,
            length_cycles=setup.length_cycles if setup else 0,
            pre_cycles=setup.pre_cycles if setup else 0,
            filled_cycles=min(sc.filled, setup.length_cycles) if setup else 0,
            trigger_cycle=sc.trigger_cycle,
            captures=[],
            recording=None,
        )
    out.captures = traces.recent(host)
    out.recording = recorders.info(host.id)
    return out


def roll_frame(host: MachineHost, max_points: int) -> bytes:
    """The newest record length of the running scope as a binary frame, every `stride`-th
    cycle so that at most `max_points` samples per channel go out (a roll is for watching;
    a capture carries every cycle)."""
    with host.lock:
        snap = host.scope.snapshot()
        if snap is None:
            raise ApiError(409, {"message": "the scope is not recording: arm it first"})
        stride = max(1, -(-snap.count // max_points))
        data = snap.data[:, ::stride]
        header = FrameHeader(
            machine=host.id,
            first_cycle=snap.first_cycle,
            count=data.shape[1],
            stride=stride,
            cycle_s=snap.cycle_s,
            t0_unix=host.t0_unix(),
            signals=[s.name for s in snap.channels],
            decimated=stride > 1,
            skipped_cycles=0,
        )
        return encode_frame(header, data)
