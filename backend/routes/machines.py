"""Machines: list, create, status, restart, delete, and pacing of their simulation."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.auth import Action
from api.machines import MachineCreate, SimulationControl, StepRequest
from api.status import MachineStatus, MachineSummary, SimulationStatus
from api.telemetry import SignalInfo
from backend.deps import ActorDep, MachineDep, ServicesDep
from backend.errors import WORKER_GONE, responses
from backend.services.auth import authorize
from backend.services.status import (
    machine_status,
    machine_summary,
    paced,
    signal_infos,
)
from backend.workers.protocol import Pace, Step

router = APIRouter(prefix="/api/machines", tags=["machines"])


@router.get("")
def list_machines(services: ServicesDep) -> list[MachineSummary]:
    return [machine_summary(m) for m in services.machines.proxies()]


@router.post("", status_code=201, responses=responses(403, 409, 422, why=WORKER_GONE))
def create_machine(req: MachineCreate, services: ServicesDep, actor: ActorDep) -> MachineSummary:
    """A new machine from the demo or from native parameter lists; it starts running."""
    return machine_summary(services.machines.create(actor, req))


@router.get("/{mid}/status", responses=responses(404, why=WORKER_GONE))
async def status(machine: MachineDep) -> MachineStatus:
    """Full snapshot: HLI objects, axis and spindle states, gear, job errors, PLC."""
    return await machine_status(machine)


@router.get("/{mid}/signals", responses=responses(404))
def signals(machine: MachineDep) -> list[SignalInfo]:
    """Every signal the machine records each cycle (for telemetry subscriptions)."""
    return signal_infos(machine)


@router.post("/{mid}/restart", responses=responses(403, 404, why=WORKER_GONE))
def restart(mid: str, services: ServicesDep, actor: ActorDep) -> MachineSummary:
    """Power off and on: cycle 0, every stored value (pending ones too) in force."""
    return machine_summary(services.machines.restart(actor, mid))


@router.delete("/{mid}", status_code=204, responses=responses(403, 404))
def delete(mid: str, services: ServicesDep, actor: ActorDep) -> Response:
    services.machines.delete(actor, mid)
    return Response(status_code=204)


@router.post("/{mid}/simulation", responses=responses(403, 404, 422, why=WORKER_GONE))
def pace(req: SimulationControl, machine: MachineDep, actor: ActorDep) -> SimulationStatus:
    """Run in real time, pause, or run as fast as possible (until a cycle)."""
    authorize(actor, Action.SIMULATE, machine.id)
    return paced(machine, Pace(machine.id, req.mode, req.until_cycle))


@router.post("/{mid}/simulation/step", responses=responses(403, 404, 422, why=WORKER_GONE))
def step(req: StepRequest, machine: MachineDep, actor: ActorDep) -> SimulationStatus:
    """Pause and advance `cycles` cycles; an emergency stop, a pacing change or a restart
    meanwhile ends the step early (the answer's `cycle` says where it stopped)."""
    authorize(actor, Action.SIMULATE, machine.id)
    return paced(machine, Step(machine.id, req.cycles))
