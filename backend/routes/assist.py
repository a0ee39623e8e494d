"""Commissioning assistants on a copy of a machine: multi_gain by experiment, sign check."""

from __future__ import annotations

from fastapi import APIRouter

from api.assist import AssistResult, MultiGainRequest, SignCheckRequest
from api.auth import Action
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import responses

router = APIRouter(prefix="/api/machines/{mid}/assist", tags=["assistants"])
_WHY = {
    422: "the experiment cannot run as asked (no feed, unknown axis, refused motion)",
    504: "the experiment did not end in time",
}


@router.post(
    "/multi-gain",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(404, 422, why=_WHY),
)
async def multi_gain(
    body: MultiGainRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> AssistResult:
    """004 §3.6.2 on a copy of the machine with its parameters now, in simulated time: the
    axis at constant feed (a spindle at constant speed, position-controlled), the averaged
    lag, k = v/s, f = (kv/100)/k and the proposed multi_gain · f and kv / f. The live machine
    does not move; Apply is a parameter write. Stored (GET .../assist/runs)."""
    result = await services.assistants.run(machine.cfg, "multi-gain", body)
    await services.assist_runs.record(machine.id, actor.name, result, live=False)
    return result


@router.post(
    "/sign-check",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(404, 422, why=_WHY),
)
async def sign_check(
    body: SignCheckRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> AssistResult:
    """004 §3.5 on a copy of the machine: a short slow move; a wrong sign of the manipulated
    variable (vz_stellgr) or of the actual value (vz_istw) is found before lag monitoring
    trips, from the way the machine moved (`observed`, else the simulated plant's). Stored."""
    result = await services.assistants.run(machine.cfg, "sign-check", body)
    await services.assist_runs.record(machine.id, actor.name, result, live=False)
    return result
