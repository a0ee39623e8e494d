"""Every machine at a glance: state, alarms, control, viewers, loop health; and the alarms
across the machines."""

from __future__ import annotations

import time
from typing import Annotated

from fastapi import APIRouter, Query

from api.auth import Action
from api.fleet import Fleet, FleetMachine
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import ApiError
from backend.services.machines import MachineProxy
from backend.workers.protocol import ReadStatus, StatusRead, WorkerNews

router = APIRouter(prefix="/api", tags=["fleet"])


def _machine(m: MachineProxy, services: ServicesDep) -> FleetMachine:
    link = m.link
    worker = link.live_worker
    reachable = (
        "running"
        if worker is not None
        else ("rebuilding" if services.machines.building(m.id) else "unreachable")
    )
    snap = None
    if worker is not None:
        try:  # fresh (a pushed status comes only while somebody watches)
            read = link.call(ReadStatus(m.id))
            snap = read.snapshot if isinstance(read, StatusRead) else None
        except ApiError:
            reachable = "unreachable"
    state = "—" if snap is None else snap.channel.state.name.lower()
    if snap is not None and snap.emergency_stop:
        state = "emergency stop"
    news = worker.latest if worker is not None else None
    overruns = None
    if isinstance(news, WorkerNews) and news.loop is not None:
        recent = time.time() - 60.0
        overruns = float(sum(1 for t, _, _ in news.loop.recent_overruns if t >= recent))
    viewers = m.control.state().viewers
    holder = m.control.holder
    last = services.history.alarms([m.id], 1)
    return FleetMachine(
        id=m.id,
        name=m.name,
        reachable=reachable,
        mode=link.pacing.mode if link.pacing else "run",
        state=state,
        active_errors=services.history.active(m.id),
        last_alarm=last[0][1] if last else None,
        holder=f"{holder.user} ({holder.role.value})" if holder else None,
        viewers=len(viewers),
        guests=sum(v.guest for v in viewers),
        overruns_per_min=overruns,
        seat=m.exercise is not None,
    )


@router.get("/fleet", dependencies=[permit(Action.OBSERVE)])
def fleet(
    services: ServicesDep,
    actor: ActorDep,
    alarms: Annotated[int, Query(ge=0, le=500, description="newest alarms across them")] = 50,
) -> Fleet:
    """Every machine the actor may see at a glance, and the newest job errors across them."""
    mine = [m for m in services.machines.proxies() if actor.sees(m.id)]
    newest = services.history.alarms([m.id for m in mine], alarms)
    return Fleet(
        machines=[_machine(m, services) for m in mine],
        alarms=[e for _, e in newest],
        machine_of={e.id: mid for mid, e in newest},
    )
