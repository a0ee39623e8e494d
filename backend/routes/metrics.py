"""The service's figures for Prometheus, authorized like the service status (a scrape uses an
API token: `Authorization: Bearer ...`)."""

from __future__ import annotations

from fastapi import APIRouter, Response
from prometheus_client import CONTENT_TYPE_LATEST

from api.auth import Action
from backend.bodies import text_answer
from backend.deps import ServicesDep, permit

router = APIRouter(tags=["service"])


@router.get(
    "/metrics",
    response_class=Response,
    dependencies=[permit(Action.OBSERVE)],
    responses=text_answer(CONTENT_TYPE_LATEST, "the Prometheus text format"),
)
def metrics(services: ServicesDep) -> Response:
    """Machines by pacing, each worker's loop (up, overruns, missed deadlines, work p99, CPU,
    calls waiting), telemetry clients and frames, classes, seats and consoles, the audit's
    queue, command latency (a histogram by command type)."""
    return Response(services.metrics.render(), media_type=CONTENT_TYPE_LATEST)
