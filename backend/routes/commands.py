"""Commands to a machine, and its emergency stop."""

from __future__ import annotations

from fastapi import APIRouter

from api.auth import Action
from api.commands import Command, CommandResult, EmergencyStopCommand
from backend.bodies import PROGRAM_BODY_BYTES
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import WORKER_GONE, Conflict, Forbidden, Invalid, NotFound, TooLarge, responses
from backend.services import programs
from backend.services.commands import execute

router = APIRouter(prefix="/api/machines", tags=["commands"])


@router.post(
    "/{mid}/commands",
    dependencies=[permit(Action.COMMAND)],
    responses=responses(
        Forbidden,
        NotFound,
        TooLarge,
        why={
            NotFound: "no such machine, or no stored program of that name (program_load)",
            Conflict: "the NC refused the command (job error)",
            Invalid: "bad input (an NC block with the column of the error)",
        }
        | WORKER_GONE,
    ),
    max_body_size=PROGRAM_BODY_BYTES,  # a program_load may bring its text
)
async def command(
    cmd: Command, machine: MachineDep, actor: ActorDep, services: ServicesDep
) -> CommandResult:
    """MDI block, program load (a stored program by name, or a text), cycle start, feedhold,
    single block, program stop, spindle, gear, homing, jog, move, override, HLI, PLC, reset
    (only while holding control of the machine: the first command takes a free one)."""
    store = services.store
    answered = services.metrics.observe_command(cmd.type)  # refused ones too: the NC answered
    try:
        return await execute(
            actor,
            machine,
            cmd,
            services.audit,
            services.history,
            lambda name: programs.stored_text(store, actor, name),
        )
    finally:
        answered()


@router.post(
    "/{mid}/emergency-stop",
    dependencies=[permit(Action.STOP)],
    responses=responses(Forbidden, NotFound, why=WORKER_GONE),
)
async def emergency_stop(
    machine: MachineDep, actor: ActorDep, services: ServicesDep
) -> CommandResult:
    """Every axis brakes at a_emergency, the drives lose their enables; whoever may command
    may stop, holding control or not. A reset (by the holder) ends it."""
    return await execute(actor, machine, EmergencyStopCommand(), services.audit, services.history)
