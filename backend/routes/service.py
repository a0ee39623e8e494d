"""The service itself: health and status of the loop, clients and machines."""

from __future__ import annotations

import time

from fastapi import APIRouter

from api.status import ServiceStatus
from backend import VERSION
from backend.deps import ServicesDep
from backend.services.status import simulation_status

router = APIRouter(prefix="/api", tags=["service"])


@router.get("/health")
def health() -> dict[str, str]:
    return {"status": "ok"}


@router.get("/service/status")
def service_status(services: ServicesDep) -> ServiceStatus:
    """Loop timing and overruns, telemetry clients, and each machine's real-time factor."""
    return ServiceStatus(
        version=VERSION,
        uptime_s=time.time() - services.started,
        loop=services.loop.status(),
        clients=len(services.hub.subscribers),
        telemetry=services.hub.status(),
        machines={h.id: simulation_status(h) for h in services.machines.hosts()},
    )
