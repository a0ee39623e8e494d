"""Commands to a machine."""

from __future__ import annotations

from fastapi import APIRouter

from api.commands import Command, CommandResult
from backend.deps import ActorDep, MachineDep
from backend.errors import WORKER_GONE, responses
from backend.services.commands import execute

router = APIRouter(prefix="/api/machines", tags=["commands"])


@router.post(
    "/{mid}/commands",
    responses=responses(
        403,
        404,
        why={
            409: "the NC refused the command (job error)",
            422: "bad input (an NC block with the column of the error)",
        }
        | WORKER_GONE,
    ),
)
async def command(cmd: Command, machine: MachineDep, actor: ActorDep) -> CommandResult:
    """MDI block, spindle, gear, homing, jog, move, override, HLI, PLC, reset, E-stop."""
    return await execute(actor, machine, cmd)
