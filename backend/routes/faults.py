"""Training faults of a machine (instructors only: a student must find them, not read them)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Response

from api.auth import Action
from api.faults import FaultInfo, FaultInject
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import CREATED, NO_CONTENT, WORKER_GONE, Forbidden, Invalid, NotFound, responses
from backend.services import training
from backend.services.audit_log import Entry

router = APIRouter(prefix="/api/machines/{mid}/faults", tags=["training"])

FaultId = Annotated[int, Path(ge=1, le=2**31, description="a fault's id on its machine")]


@router.get("", dependencies=[permit(Action.TEACH)], responses=responses(Forbidden, NotFound))
def list_faults(machine: MachineDep) -> list[FaultInfo]:
    """The faults injected into the machine, active or armed."""
    return training.faults_of(machine)


@router.post(
    "",
    status_code=CREATED,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, Invalid, why=WORKER_GONE),
)
def inject(
    req: FaultInject, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> FaultInfo:
    """Inject a fault into the machine's plant or PLC, now or at a trigger. Its parameters
    stay as they are: the fault is what the student must find."""
    what = f"inject fault: {training.describe(training.to_fault(req.fault))}"
    entry = Entry(actor.name, actor.session, "training", what, machine.id, req.model_dump())
    with services.audit.refusals(entry):
        info = training.inject(machine, req)
    services.faults.keep(machine)
    services.audit.record(entry)
    return info


@router.delete(
    "/{fid}",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.TEACH)],
    responses=responses(Forbidden, NotFound, why=WORKER_GONE),
)
def remove(fid: FaultId, machine: MachineDep, services: ServicesDep, actor: ActorDep) -> Response:
    """Take a fault out: the plant is as its parameters say again."""
    training.remove(machine, fid)
    services.faults.keep(machine)
    services.audit.record(
        Entry(actor.name, actor.session, "training", f"removed fault {fid}", machine.id)
    )
    return Response(status_code=NO_CONTENT)
