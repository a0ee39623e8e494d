"""Machines: list, create, status, restart, delete, and pacing of their simulation."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.auth import Action
from api.machines import MachineCreate, SimulationControl, StepRequest
from api.status import MachineStatus, MachineSummary, SimulationStatus
from api.telemetry import SignalInfo
from backend.deps import ActorDep, HostDep, ServicesDep
from backend.errors import responses
from backend.services.auth import authorize
from backend.services.status import (
    machine_status,
    machine_summary,
    signal_infos,
    simulation_status,
)

router = APIRouter(prefix="/api/machines", tags=["machines"])


@router.get("")
def list_machines(services: ServicesDep) -> list[MachineSummary]:
    return [machine_summary(h) for h in services.machines.hosts()]


@router.post("", status_code=201, responses=responses(403, 409, 422))
def create_machine(req: MachineCreate, services: ServicesDep, actor: ActorDep) -> MachineSummary:
    """A new machine from the demo or from native parameter lists; it starts running."""
    return machine_summary(services.machines.create(actor, req))


@router.get("/{mid}/status", responses=responses(404))
def status(host: HostDep) -> MachineStatus:
    """Full snapshot: HLI objects, axis and spindle states, gear, job errors, PLC."""
    return machine_status(host)


@router.get("/{mid}/signals", responses=responses(404))
def signals(host: HostDep) -> list[SignalInfo]:
    """Every signal the machine records each cycle (for telemetry subscriptions)."""
    return signal_infos(host)


@router.post("/{mid}/restart", responses=responses(403, 404))
def restart(mid: str, services: ServicesDep, actor: ActorDep) -> MachineSummary:
    """Power off and on: cycle 0, every stored value (pending ones too) in force."""
    return machine_summary(services.machines.restart(actor, mid))


@router.delete("/{mid}", status_code=204, responses=responses(403, 404))
def delete(mid: str, services: ServicesDep, actor: ActorDep) -> Response:
    services.machines.delete(actor, mid)
    return Response(status_code=204)


@router.post("/{mid}/simulation", responses=responses(403, 404, 422))
def pace(req: SimulationControl, host: HostDep, actor: ActorDep) -> SimulationStatus:
    """Run in real time, pause, or run as fast as possible (until a cycle)."""
    authorize(actor, Action.SIMULATE, host.id)
    host.set_mode(req.mode, req.until_cycle)
    return simulation_status(host)


@router.post("/{mid}/simulation/step", responses=responses(403, 404, 422))
def step(req: StepRequest, host: HostDep, actor: ActorDep) -> SimulationStatus:
    """Pause and advance `cycles` cycles; an emergency stop, a pacing change or a restart
    meanwhile ends the step early (the answer's `cycle` says where it stopped)."""
    authorize(actor, Action.SIMULATE, host.id)
    host.step(req.cycles)
    return simulation_status(host)
