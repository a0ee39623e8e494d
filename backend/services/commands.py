"""Commands to a machine: authorize, carry out between kernel batches, acknowledge or refuse.

Every command passes `execute`, the one place that asks who may send it. A command the NC
refuses (a job error raised by the command itself) is answered 409 with that job error; a bad
NC block 422 with its column; an accepted command with the cycle it took effect in.
"""

from __future__ import annotations

from api.auth import Action
from api.commands import (
    Command,
    CommandResult,
    EmergencyStopCommand,
    GearCommand,
    HliCommand,
    HomeCommand,
    JogCommand,
    MdiCommand,
    MoveCommand,
    OverrideCommand,
    PlcAckCommand,
    PlcModeCommand,
    ResetCommand,
    SpindleCommand,
    SpindlePositionCommand,
)
from api.common import JobErrorModel, Refusal
from backend.errors import ApiError
from backend.services.auth import Actor, authorize
from backend.services.host import MachineHost
from backend.services.parameters import apply_pending
from nc_sim.errors import JobError, NcUsageError
from nc_sim.machine.machine import Ack, Machine


def job_error_model(e: JobError) -> JobErrorModel:
    return JobErrorModel(
        cycle=e.cycle, t_s=e.t_s, axis=e.axis, code=e.code, message=e.message, error=e.error
    )


def _refuse(status: int, message: str, **kw: object) -> ApiError:
    return ApiError(status, Refusal.model_validate({"message": message, **kw}).model_dump())


def _carry_out(m: Machine, cmd: Command) -> JobError | Ack | int | None:
    """Call the machine; returns what it answered."""
    match cmd:
        case MdiCommand():
            return m.mdi(cmd.block)
        case SpindleCommand():
            return m.spindle(cmd.spindle, cmd.m, cmd.speed_rpm)
        case SpindlePositionCommand():
            return m.spindle_position(cmd.spindle, cmd.position_deg, cmd.direction, cmd.speed_rpm)
        case GearCommand():
            return m.spindle_gear(cmd.spindle, cmd.m)
        case HomeCommand():
            return m.home(cmd.axis)
        case JogCommand(action="start"):
            return m.jog_start(cmd.axis, cmd.direction, cmd.feed_mm_min)
        case JogCommand(action="stop"):
            m.jog_stop(cmd.axis)
            return None
        case JogCommand():
            if cmd.distance is None:
                raise NcUsageError("jog step needs a distance")
            return m.jog_step(cmd.axis, cmd.direction * cmd.distance, cmd.feed_mm_min)
        case MoveCommand():
            return m.move(cmd.axis, cmd.target, cmd.rapid, cmd.feed_mm_min)
        case OverrideCommand():
            m.hli_write("override", round(cmd.percent * 10), cmd.axis)  # HLI counts in ‰
            return None
        case HliCommand():
            m.hli_write(cmd.unit, cmd.value, cmd.axis)
            return None
        case PlcModeCommand():
            m.plc_mode(cmd.mode, cmd.delay_s)
            return None
        case PlcAckCommand():
            return m.plc_acknowledge(cmd.m)
        case ResetCommand():
            m.reset()
            return None
        case EmergencyStopCommand():
            m.emergency_stop()
            return None
    raise NcUsageError(f"unknown command {cmd!r}")


def execute(actor: Actor, host: MachineHost, cmd: Command) -> CommandResult:
    """Authorize and carry out one command; raises ApiError with the refusal."""
    authorize(actor, Action.COMMAND, host.id)
    with host.lock:
        m = host.machine
        seen = m.events.cursor
        try:
            answer = _carry_out(m, cmd)
        except NcUsageError as e:
            raise _refuse(422, str(e)) from None
        block_id = answer.id if isinstance(answer, Ack) else None
        if isinstance(answer, Ack):
            if not answer.ok:
                raise _refuse(422, answer.message, code=answer.code, column=answer.column)
            # a block that cannot start is refused in the same call
            failed = [e for e in m.events.since(seen).entries if e.error]
            if failed:
                answer = failed[0]
        if isinstance(answer, JobError):
            raise _refuse(
                409, answer.message, code=answer.code, error=job_error_model(answer).model_dump()
            )
        if isinstance(cmd, JogCommand) and cmd.action != "step":
            host.hold_jog(cmd.axis, cmd.hold_s if cmd.action == "start" else None)
        if isinstance(cmd, EmergencyStopCommand):
            host.interrupt_steps()  # stop means stop: a long single step ends here too
        if isinstance(cmd, ResetCommand):
            apply_pending(host, {"reset"})  # values that take effect at reset [params]
        return CommandResult(
            cycle=host.cycle,
            block_id=block_id,
            acknowledged=answer if isinstance(answer, int) else None,
            state={ax.name: ax.state.name for ax in m.axes},
        )
