"""A machine's flight recorder: what it keeps, and the last seconds saved on demand."""

from __future__ import annotations

from fastapi import APIRouter

from api.auth import Action
from api.flight import FlightRecorderStatus, FlightSave
from api.scope import TraceInfo
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import CREATED, Invalid, NotFound, QuotaUsedUp, responses
from backend.services.audit_log import Entry

router = APIRouter(prefix="/api/machines", tags=["flight recorder"])


@router.get(
    "/{mid}/flight-recorder", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound)
)
def flight_recorder(machine: MachineDep, services: ServicesDep) -> FlightRecorderStatus:
    """How much of the machine's past the recorder holds, at which rate, at what memory."""
    return services.flight.status(machine)


@router.post(
    "/{mid}/flight-recorder/save",
    status_code=CREATED,
    dependencies=[permit(Action.CAPTURE)],
    responses=responses(
        NotFound,
        QuotaUsedUp,
        why={Invalid: "the recorder holds nothing of the machine yet"},
    ),
)
def save_last(
    req: FlightSave, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> TraceInfo:
    """The last seconds of the machine's main signals as a trace in the library: at full rate
    as far back as the sample ring reaches (16 s), one sample in `decimation` cycles beyond."""
    entry = Entry(actor.name, actor.session, "trace", f"saved the last {req.seconds:g} s",
                  machine.id, req.model_dump())  # fmt: skip
    with services.audit.refusals(entry):
        info = services.flight.save_last(machine, req.seconds, actor.name)
    services.audit.record_later(entry)
    return info
