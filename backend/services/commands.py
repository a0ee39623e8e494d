"""Commands to a machine: authorize, submit between kernel batches, answer with the outcome.

Every command passes `execute`, the one place that asks who may send it. The API command maps
onto its nc_sim command (`to_nc`), `Machine.submit` carries it out, and its outcome becomes the
answer: Accepted 200 with the cycle it took effect in, Refused 409 with the job error (a
precondition failed, or an MDI block failed while starting), Invalid 422 with the message and
the column of a bad NC block.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

from api.commands import (
    Command,
    CommandResult,
    CycleStartCommand,
    EmergencyStopCommand,
    FeedholdCommand,
    GearCommand,
    HliCommand,
    HomeCommand,
    JogCommand,
    MdiCommand,
    MoveCommand,
    OverrideCommand,
    PlcAckCommand,
    PlcModeCommand,
    PlcSignalCommand,
    ProgramLoadCommand,
    ProgramStopCommand,
    ResetCommand,
    SingleBlockCommand,
    SpindleCommand,
    SpindlePositionCommand,
)
from api.common import JobErrorModel, Refusal
from backend import errors
from backend.errors import ApiError
from backend.services.audit import Audit
from backend.services.audit_log import Entry
from backend.services.auth import Actor
from backend.services.history import History
from backend.services.machines import MachineProxy
from backend.services.parameters import pending_values, took_pending
from backend.workers.protocol import Submit, Submitted, Values
from nc_sim import commands as nc
from nc_sim.commands import Accepted, Invalid, Refused
from nc_sim.events import Event
from nc_sim.units import MS_PER_S


def job_error_model(e: Event) -> JobErrorModel:
    """The API model of an event or job error (nc_sim's Event)."""
    return JobErrorModel(
        cycle=e.cycle,
        t_s=e.t_s,
        axis=e.axis,
        code=e.code,
        message=e.message,
        error=e.error,
        seq=e.seq,
        m=e.m,
        gear=e.gear,
        line=e.line,
        column=e.column,
        signal=e.signal,
        value=e.value,
        block=e.block,
    )


def _refuse(kind: type[ApiError], message: str, **kw: object) -> ApiError:
    return kind(Refusal.model_validate({"message": message, **kw}).model_dump())


StoredText = Callable[[str], str]
"""The text of a stored program by name (raises ApiError 404 without one)."""


def _no_store(name: str) -> str:
    raise _refuse(errors.Invalid, f"program_load of {name} needs the program text here")


def to_nc(cmd: Command | EmergencyStopCommand, stored: StoredText = _no_store) -> nc.Command:
    """The nc_sim command an API command stands for (the host's jog lease aside); a
    program_load without text loads the stored program of that name."""
    match cmd:
        case MdiCommand():
            return nc.Mdi(cmd.block)
        case ProgramLoadCommand():
            return nc.ProgramLoad(cmd.name, stored(cmd.name) if cmd.text is None else cmd.text)
        case CycleStartCommand():
            return nc.CycleStart()
        case FeedholdCommand():
            return nc.Feedhold(cmd.on)
        case SingleBlockCommand():
            return nc.SingleBlock(cmd.on)
        case ProgramStopCommand():
            return nc.ProgramStop()
        case SpindleCommand():
            return nc.SpindleRun(cmd.spindle, cmd.m, cmd.speed_rpm)
        case SpindlePositionCommand():
            return nc.SpindlePosition(cmd.spindle, cmd.position_deg, cmd.direction, cmd.speed_rpm)
        case GearCommand():
            return nc.GearChange(cmd.spindle, cmd.m)
        case HomeCommand():
            return nc.Home(cmd.axis)
        case JogCommand(action="start"):
            return nc.JogStart(cmd.axis, cmd.direction, cmd.feed_mm_min)
        case JogCommand(action="stop"):
            return nc.JogStop(cmd.axis)
        case JogCommand():
            if cmd.distance is None:
                raise _refuse(errors.Invalid, "jog step needs a distance")
            return nc.JogStep(cmd.axis, cmd.direction * cmd.distance, cmd.feed_mm_min)
        case MoveCommand():
            return nc.Move(cmd.axis, cmd.target, cmd.rapid, cmd.feed_mm_min)
        case OverrideCommand():
            return nc.HliWrite("override", round(cmd.percent * 10), cmd.axis)  # HLI counts in ‰
        case HliCommand():
            return nc.HliWrite(cmd.unit, cmd.value, cmd.axis)
        case PlcModeCommand():
            return nc.PlcMode(cmd.mode, cmd.delay_s)
        case PlcAckCommand():
            return nc.PlcAck(cmd.m)
        case PlcSignalCommand():
            return nc.PlcSignal(cmd.signal, cmd.on)
        case ResetCommand():
            return nc.Reset()
        case EmergencyStopCommand():
            return nc.EmergencyStop()
    raise _refuse(errors.Invalid, f"unknown command {cmd!r}")


def _describe(cmd: Command | EmergencyStopCommand) -> str:
    """A command in words for the audit trail."""
    fields = cmd.model_dump(exclude={"type"}, exclude_none=True)
    return " ".join([cmd.type, *(f"{k}={v}" for k, v in fields.items())])


def _axis_name(m: MachineProxy, name: str) -> str:
    """An axis as its events name it: `S` is the (first) spindle's own name (S1)."""
    if name == "S":
        return next((s.axis for s in m.link.signals if s.name.endswith(".speed_act_rpm")), name)
    return name


def _renewal(m: MachineProxy, actor: Actor, cmd: Command | EmergencyStopCommand) -> bool:
    """A held jog's renewal (the same start again within a second): audited once."""
    if not isinstance(cmd, JogCommand) or cmd.action == "step":
        return False
    key = (cmd.axis, actor.session, actor.client)
    if cmd.action == "stop":
        m.jogs.stop(key)
        return False
    return m.jogs.start(key, cmd.direction, cmd.feed_mm_min)


async def execute(
    actor: Actor,
    m: MachineProxy,
    cmd: Command | EmergencyStopCommand,
    audit: Audit,
    history: History,
    stored: StoredText = _no_store,
) -> CommandResult:
    """Carry out one command on the machine's worker and audit it (the history remembers
    who sent what runs now); raises ApiError with the refusal. The route checked who may
    send it (backend/deps.py `permit`). Runs on the event loop: nothing here blocks but
    reading a stored program (`stored`, for program_load), the worker's answer wakes it."""
    outcome = "ok"
    # when it was sent: a job error it raises at once is logged at the cycle it runs in, after
    sent_unix, sent_at = time.time(), (m.link.epoch, m.link.cycle * m.link.cycle_s)
    m.last_command[actor.name] = sent_unix  # who works on it (a class seat's idle time)
    text = cmd.block if isinstance(cmd, MdiCommand) else _describe(cmd)
    axis = str(getattr(cmd, "axis", None) or getattr(cmd, "spindle", None) or "")
    # who sent what runs now, for the job errors it raises (at once, or later)
    history.sending(m.id, m.link.epoch, text, actor.name, _axis_name(m, axis))
    try:
        done = await _execute(m, cmd, stored)
        if done.block_id is not None:
            history.sent(m.id, m.link.epoch, text, actor.name, done.block_id)
        return done
    except ApiError as e:
        outcome = f"refused ({e.status}): {e}"
        raise
    finally:
        # audited before it is answered: an acknowledged command is in the trail even when the
        # service is killed straight after (the writer commits at once for it)
        if not _renewal(m, actor, cmd) or outcome != "ok":
            await audit.recorded(
                Entry(
                    actor=actor.name,
                    session=actor.session,
                    kind="command",
                    action=_describe(cmd),
                    machine=m.id,
                    detail=cmd.model_dump(mode="json"),
                    outcome=outcome,
                    time=sent_unix,
                    stamp=sent_at,
                )
            )


async def _execute(
    m: MachineProxy, cmd: Command | EmergencyStopCommand, stored: StoredText
) -> CommandResult:
    serial = m.link.next_serial()
    nc_cmd = replace(to_nc(cmd, stored), serial=serial)
    jog_hold_s, jog_release = None, False
    if isinstance(cmd, JogCommand) and cmd.action != "step":  # the dead-man lease of a jog
        jog_hold_s = cmd.hold_s if cmd.action == "start" else None
        jog_release = jog_hold_s is None
    reset_values: Values = []
    if isinstance(cmd, ResetCommand):  # values pending for reset go in the reset's own cycle
        with m.lock:
            reset_values = pending_values(m, {"reset"})
    submit = Submit(m.id, nc_cmd, jog_hold_s, jog_release, reset_values)
    done = await m.link.acall(submit)
    assert isinstance(done, Submitted)
    match done.outcome:
        case Invalid() as bad:
            raise _refuse(
                errors.Invalid,
                bad.message,
                code=bad.code,
                line=bad.line,
                column=bad.column,
                serial=serial,
            )
        case Refused() as refused:
            e = refused.error
            model = job_error_model(e).model_dump()
            raise _refuse(errors.Conflict, e.message, code=e.code, error=model, serial=serial)
        case Accepted() as ok:
            if reset_values:
                with m.lock:
                    took_pending(m, reset_values)
    return CommandResult(
        serial=serial,
        cycle=done.cycle,
        block_id=ok.block_id,
        acknowledged=ok.acknowledged,
        state=done.state,
        latency_ms=done.latency_s * MS_PER_S,
    )
