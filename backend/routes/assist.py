"""Commissioning assistants on a copy of a machine: multi_gain by experiment, sign check,
position loop gain."""

from __future__ import annotations

from fastapi import APIRouter

from api.assist import AssistResult, LoopGainRequest, MultiGainRequest, SignCheckRequest
from api.auth import Action
from backend.deps import MachineDep, ServicesDep, permit
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
    body: MultiGainRequest, machine: MachineDep, services: ServicesDep
) -> AssistResult:
    """004 §3.6.2 on a copy of the machine with its parameters now, in simulated time: the
    axis at constant feed (a spindle at constant speed, position-controlled), the averaged
    lag, k = v/s, f = (kv/100)/k and the proposed multi_gain · f and kv / f. The live machine
    does not move; Apply is a parameter write."""
    return await services.assistants.run(machine.cfg, "multi-gain", body)


@router.post(
    "/sign-check",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(404, 422, why=_WHY),
)
async def sign_check(
    body: SignCheckRequest, machine: MachineDep, services: ServicesDep
) -> AssistResult:
    """004 §3.5 on a copy of the machine: a short slow move; a wrong sign of the manipulated
    variable (vz_stellgr) or of the actual value (vz_istw) is found before lag monitoring
    trips, from the way the machine moved (`observed`, else the simulated plant's)."""
    return await services.assistants.run(machine.cfg, "sign-check", body)


@router.post(
    "/loop-gain",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(404, 422, why=_WHY),
)
async def loop_gain(
    body: LoopGainRequest, machine: MachineDep, services: ServicesDep
) -> AssistResult:
    """004 §3.6 on copies of the machine, one per kv: a G00 step (overshoot, settling into the
    exact-stop window) and a G01 ramp (steady lag v/kv); the highest kv meeting the target
    is proposed as getriebe[g].kv. The live machine does not move."""
    return await services.assistants.run(machine.cfg, "loop-gain", body)
