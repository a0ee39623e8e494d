"""Snapshots of a machine's whole state, and restoring one (instructors: pacing rights)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path

from api.auth import Action
from api.classes import SnapshotCreate, SnapshotInfo
from backend.deps import ActorDep, MachineDep, ServicesDep, permit
from backend.errors import CREATED, WORKER_GONE, Forbidden, Invalid, NotFound, responses
from backend.services.audit_log import Entry

router = APIRouter(prefix="/api/machines/{mid}/snapshots", tags=["training"])

SnapshotId = Annotated[int, Path(ge=1, le=2**53, description="a snapshot's id")]


@router.get("", dependencies=[permit(Action.SIMULATE)], responses=responses(Forbidden, NotFound))
def list_snapshots(machine: MachineDep, services: ServicesDep) -> list[SnapshotInfo]:
    """The machine's snapshots, oldest first (the newest 8 are kept in the store, and a class
    seat's start)."""
    return services.snapshots.list(machine.id)


@router.post(
    "",
    status_code=CREATED,
    dependencies=[permit(Action.SIMULATE)],
    responses=responses(Forbidden, NotFound, why=WORKER_GONE),
)
def take(
    req: SnapshotCreate, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> SnapshotInfo:
    """Save the machine's state at the end of its current cycle: every axis and spindle,
    the channel and its program, the PLC and its handshakes, the faults, simulated time."""
    info = services.snapshots.take(actor, machine, req.label)
    services.audit.record(
        Entry(
            actor.name,
            actor.session,
            "training",
            f"snapshot {info.id} at {info.t_s:.3f} s",
            machine.id,
            info.model_dump(),
        )
    )
    return info


@router.post(
    "/{sid}/restore",
    dependencies=[permit(Action.SIMULATE)],
    responses=responses(Forbidden, NotFound, Invalid, why=WORKER_GONE),
)
def restore(
    sid: SnapshotId, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> SnapshotInfo:
    """Put the machine back to the snapshot: its lists as they were (written back, audited)
    and its state; it goes on from the snapshot's cycle with the same pacing mode."""
    info = services.snapshots.restore(actor, machine, sid)
    services.audit.record(
        Entry(
            actor.name,
            actor.session,
            "training",
            f"restored snapshot {sid} ({info.t_s:.3f} s)",
            machine.id,
        )
    )
    machine.notices.add("restored", f"{actor.name} restored the machine to {info.t_s:.1f} s")
    return info
