"""Machines: list, create, status, restart, delete, and pacing of their simulation."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.auth import Action
from api.machines import MachineCreate, SimulationControl, StepRequest
from api.service_axes import ServiceAxes
from api.status import MachineStatus, MachineSummary, SimulationStatus
from api.telemetry import SignalInfo
from backend.bodies import LISTS_BODY_BYTES
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import (
    CREATED,
    NO_CONTENT,
    WORKER_GONE,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    TooLarge,
    responses,
)
from backend.services.audit_log import Entry
from backend.services.service_axes import service_axes
from backend.services.status import (
    machine_status,
    machine_summary,
    paced,
    signal_infos,
)
from backend.workers.protocol import Pace, Step

router = APIRouter(prefix="/api/machines", tags=["machines"])


@router.get("", dependencies=[permit(Action.OBSERVE)])
def list_machines(services: ServicesDep, actor: ActorDep) -> list[MachineSummary]:
    """The machines this user may see (a class's student: their seat's only), by id (a
    class's seats in seat order, whichever was built first)."""
    seen = sorted((m for m in services.machines.proxies() if actor.sees(m.id)), key=lambda m: m.id)
    return [machine_summary(m) for m in seen]


@router.post(
    "",
    status_code=CREATED,
    dependencies=[permit(Action.MACHINES)],
    responses=responses(Forbidden, Conflict, TooLarge, Invalid, why=WORKER_GONE),
    max_body_size=LISTS_BODY_BYTES,
)
def create_machine(req: MachineCreate, services: ServicesDep, actor: ActorDep) -> MachineSummary:
    """A new machine from the demo or from native parameter lists; it starts running."""
    machine = services.machines.create(req)
    services.audit.record(
        Entry(
            actor.name,
            actor.session,
            "machine",
            f"created machine {machine.id}",
            machine.id,
            {"name": machine.name, "source": machine.source},
        )
    )
    return machine_summary(machine)


@router.get(
    "/{mid}/service-axes",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound, why=WORKER_GONE),
)
async def service_axes_view(machine: MachineDep) -> ServiceAxes:
    """The service-axis view: per axis and spindle kv, expected lag (1 − ff)·v/kv, measured
    gain k = v/lag, D/A output and limit, limits in force with their sources."""
    return await service_axes(machine)


@router.get(
    "/{mid}/status",
    dependencies=[permit(Action.OBSERVE)],
    responses=responses(NotFound, why=WORKER_GONE),
)
async def status(machine: MachineDep) -> MachineStatus:
    """Full snapshot: HLI objects, axis and spindle states, gear, job errors, PLC."""
    return await machine_status(machine)


@router.get("/{mid}/signals", dependencies=[permit(Action.OBSERVE)], responses=responses(NotFound))
def signals(machine: MachineDep) -> list[SignalInfo]:
    """Every signal the machine records each cycle (for telemetry subscriptions)."""
    return signal_infos(machine)


@router.post(
    "/{mid}/restart",
    dependencies=[permit(Action.COMMAND)],
    responses=responses(Forbidden, NotFound, why=WORKER_GONE),
)
def restart(mid: str, services: ServicesDep, actor: ActorDep) -> MachineSummary:
    """Power off and on (only while holding control): cycle 0, every stored value (pending
    ones too) in force."""
    machine = services.machines.restart(mid, actor.name)
    services.audit.record(Entry(actor.name, actor.session, "machine", "power cycle", mid))
    return machine_summary(machine)


@router.delete(
    "/{mid}",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.MACHINES)],
    responses=responses(Forbidden, NotFound),
)
def delete(mid: str, services: ServicesDep, actor: ActorDep) -> Response:
    services.machines.delete(mid)
    services.audit.record(
        Entry(actor.name, actor.session, "machine", f"deleted machine {mid}", mid)
    )
    return Response(status_code=NO_CONTENT)


@router.post(
    "/{mid}/simulation",
    dependencies=[permit(Action.SIMULATE)],
    responses=responses(Forbidden, NotFound, Invalid, why=WORKER_GONE),
)
def pace(
    req: SimulationControl, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> SimulationStatus:
    """Run in real time, pause, or run as fast as possible (until a cycle)."""
    until = f" until cycle {req.until_cycle}" if req.until_cycle is not None else ""
    services.audit.record_later(
        Entry(actor.name, actor.session, "simulation", f"{req.mode}{until}", machine.id)
    )
    return paced(machine, Pace(machine.id, req.mode, req.until_cycle))


@router.post(
    "/{mid}/simulation/step",
    dependencies=[permit(Action.SIMULATE)],
    responses=responses(Forbidden, NotFound, Invalid, why=WORKER_GONE),
)
def step(
    req: StepRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> SimulationStatus:
    """Pause and advance `cycles` cycles; an emergency stop, a pacing change or a restart
    meanwhile ends the step early (the answer's `cycle` says where it stopped)."""
    services.audit.record_later(
        Entry(actor.name, actor.session, "simulation", f"step {req.cycles} cycles", machine.id)
    )
    return paced(machine, Step(machine.id, req.cycles))
