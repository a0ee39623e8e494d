"""Commissioning assistants: one route family made from their descriptors
(nc_sim/assist/registry.py) — `POST .../assist/{name}` on a copy (a calculator: at once),
`POST .../assist/live/{name}` on the machine itself where the assistant may run live — the
catalogue the HMI builds its forms from, the live run's cancel, and the gear-range preview."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

from fastapi import APIRouter
from pydantic import BaseModel

from api.assist import (
    REQUESTS,
    AssistantInfo,
    AssistResult,
    GearSelectionRequest,
    GearSelectionResult,
    LiveCancel,
    catalogue,
)
from api.auth import Action
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import (
    NO_CONTENT,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    TimedOut,
    Unavailable,
    Why,
    responses,
)
from backend.services.assist import calculate, cancel_live, run_live
from backend.services.gear_ranges import gear_selection
from nc_sim.assist.descriptor import Assistant, Kind
from nc_sim.assist.registry import ASSISTANTS

machine_routes = APIRouter(prefix="/api/machines/{mid}/assist", tags=["assistants"])
catalogue_routes = APIRouter(prefix="/api/assistants", tags=["assistants"])
_WHY: Why = {
    Invalid: "the experiment cannot run as asked (no feed, unknown axis, refused motion)",
    TimedOut: "the experiment did not end in time",
}
_CALC_WHY: Why = {
    Invalid: "the inputs do not fit together (which one, and why) or the axis is unknown"
}
_LOCKED: Why = {Forbidden: "a class seat's exercise locks the assistant for its student"}
_LIVE_WHY: Why = {
    Conflict: "another assistant runs, the run was cancelled (E-stop, cancel) or the machine "
    "rebuilt",
    Invalid: "the NC refused the run's motion (not ready, limits, busy) or bad inputs",
    Unavailable: "the machine has no worker now, or the run did not end in time (then it is "
    "cancelled)",
}


def _on_copy(a: Assistant, model: type[BaseModel]) -> Callable[..., Awaitable[AssistResult]]:
    """The route body of `a` on a copy: an experiment in the assistants' process, a
    calculator at once (a thread: no kernel, no simulation); stored for the report."""

    async def route(
        body: Any, machine: MachineDep, services: ServicesDep, actor: ActorDep
    ) -> AssistResult:
        services.classes.check_unlocked(machine.id, a.name, actor)
        if a.kind is Kind.CALCULATOR:
            return await asyncio.to_thread(calculate, machine.cfg, a.name, body)
        # the copy carries the faults in force on the machine, as the machine's plant has them
        faults = [f.fault for f in machine.link.faults.values() if f.active_since is not None]
        result = await services.assistants.run(machine.cfg, a.name, body, faults)
        run_id = await services.assist_runs.record(machine.id, actor.name, result, live=False)
        return result.model_copy(update={"run_id": run_id})

    route.__annotations__["body"] = model
    return route


def _live(a: Assistant, model: type[BaseModel]) -> Callable[..., Awaitable[AssistResult]]:
    """The route body of `a` on the machine itself, stored for the report."""

    async def route(
        body: Any, machine: MachineDep, actor: ActorDep, services: ServicesDep
    ) -> AssistResult:
        services.classes.check_unlocked(machine.id, a.name, actor)
        result = await run_live(machine, a.name, body, actor, services.audit)
        run_id = await services.assist_runs.record(machine.id, actor.name, result, live=True)
        return result.model_copy(update={"run_id": run_id})

    route.__annotations__["body"] = model
    return route


_COPY = {
    Kind.EXPERIMENT: "On a copy of the machine with its parameters now, in simulated time: "
    "the live machine does not move; Apply is a parameter write. Stored (GET .../assist/runs).",
    Kind.CALCULATOR: "Arithmetic on the inputs, answered at once; the machine supplies the "
    "values the proposal replaces.",
}
_LIVE = (
    "On the machine itself, as paced (real time, fast or stepped): it moves for the run's "
    "planned time, which the machine's status shows as `assist` with its phase. Needs control "
    "of the machine. Stored."
)
for _a in ASSISTANTS:
    machine_routes.add_api_route(
        f"/{_a.name}",
        _on_copy(_a, REQUESTS[_a.name]),
        methods=["POST"],
        name=f"{_a.name} on a copy",
        summary=f"{_a.title} ({_a.section})",
        description=f"{_a.text}\n\n{_COPY[_a.kind]}",
        dependencies=[permit(Action.ASSIST)],
        responses=responses(
            Forbidden,
            NotFound,
            Invalid,
            why=(_CALC_WHY if _a.kind is Kind.CALCULATOR else _WHY) | _LOCKED,
        ),
    )
    if _a.live:
        machine_routes.add_api_route(
            f"/live/{_a.name}",
            _live(_a, REQUESTS[_a.name]),
            methods=["POST"],
            name=f"{_a.name} live",
            summary=f"{_a.title} ({_a.section}) on the machine",
            description=f"{_a.text}\n\n{_LIVE}",
            dependencies=[permit(Action.COMMAND)],
            responses=responses(Forbidden, NotFound, Conflict, Invalid, Unavailable, why=_LIVE_WHY),
        )


@catalogue_routes.get("", dependencies=[permit(Action.OBSERVE)])
def assistants() -> list[AssistantInfo]:
    """Every commissioning assistant as the HMI offers it: title, manual section, where it
    runs, and the JSON schema of its inputs (the HMI's form is made from it)."""
    return catalogue()


@machine_routes.post(
    "/gear-ranges",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_CALC_WHY),
)
def gear_ranges(body: GearSelectionRequest, machine: MachineDep) -> GearSelectionResult:
    """000 §2.8.2: the main spindle's six speed ranges (as edited, else the machine's), the
    stage the NC's automatic selection picks for each S in turn, and the edited ranges as
    parameter changes (spindel[i].range_table[j].min_speed / max_speed)."""
    return gear_selection(machine.cfg, body)


@machine_routes.post(
    "/live/cancel",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.STOP)],
    responses=responses(
        Forbidden, NotFound, Conflict, why={Conflict: "no assistant runs on the machine"}
    ),
)
async def cancel(
    body: LiveCancel, machine: MachineDep, actor: ActorDep, services: ServicesDep
) -> None:
    """End the machine's live run now: an axis brakes as at a CNC reset, a spindle stops
    (M5). Like the emergency stop, any operator may, holding control or not."""
    await cancel_live(machine, body.why, actor, services.audit)


router = APIRouter()
router.include_router(catalogue_routes)
router.include_router(machine_routes)
