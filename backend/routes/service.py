"""The service itself: status of the workers, clients and machines."""

from __future__ import annotations

import time

from fastapi import APIRouter

from api.auth import Action
from api.status import ServiceStatus
from backend import VERSION
from backend.deps import ActorDep, ServicesDep, permit
from backend.services.status import machine_simulation, worker_statuses

router = APIRouter(prefix="/api", tags=["service"])


@router.get("/service/status", dependencies=[permit(Action.OBSERVE)])
def service_status(services: ServicesDep, actor: ActorDep) -> ServiceStatus:
    """Each worker with its machines and loop figures, telemetry clients, and each machine's
    pacing and worker (a class's student sees their seat's machine only)."""
    workers = worker_statuses(services.machines)
    for w in workers:
        w.machines = [mid for mid in w.machines if actor.sees(mid)]
    return ServiceStatus(
        version=VERSION,
        uptime_s=time.time() - services.started,
        transport="ray" if services.settings.cluster else "local",
        workers=workers,
        workers_replaced=services.pool.replaced,
        machines_rebuilt=services.machines.rebuilt,
        clients=len(services.hub.subscribers),
        telemetry=services.hub.status(),
        machines={
            m.id: machine_simulation(m) for m in services.machines.proxies() if actor.sees(m.id)
        },
    )
