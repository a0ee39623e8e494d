"""The service itself: status of the workers, clients and machines."""

from __future__ import annotations

import time

from fastapi import APIRouter

from api.auth import Action
from api.status import ServiceStatus
from backend import VERSION
from backend.deps import ServicesDep, permit
from backend.services.status import machine_simulation, worker_statuses

router = APIRouter(prefix="/api", tags=["service"])


@router.get("/service/status", dependencies=[permit(Action.OBSERVE)])
def service_status(services: ServicesDep) -> ServiceStatus:
    """Each worker with its machines and loop figures, telemetry clients, and each machine's
    pacing and worker."""
    return ServiceStatus(
        version=VERSION,
        uptime_s=time.time() - services.started,
        transport="ray" if services.settings.cluster else "local",
        workers=worker_statuses(services.machines),
        workers_replaced=services.pool.replaced,
        machines_rebuilt=services.machines.rebuilt,
        clients=len(services.hub.subscribers),
        telemetry=services.hub.status(),
        machines={m.id: machine_simulation(m) for m in services.machines.proxies()},
    )
