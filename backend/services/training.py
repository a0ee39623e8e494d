"""Faults and snapshots of a machine, as the gateway handles them for instructors: the API's
fault models to nc_sim's and back, the snapshots kept per machine."""

from __future__ import annotations

import itertools
import threading
import time
from collections import deque
from dataclasses import dataclass

from pydantic import TypeAdapter

from api.classes import SnapshotInfo
from api.faults import FaultInfo, FaultInject, FaultModel, TriggerModel
from api.parameters import ParameterChange
from backend.errors import not_found
from backend.services import parameters as params
from backend.services.auth import Actor
from backend.services.machines import MachineProxy, MachineService
from backend.services.store import Store
from backend.workers.protocol import (
    InjectFault,
    ReadStatus,
    RemoveFault,
    Snapshot,
    StatusRead,
    TakeSnapshot,
)
from nc_sim.faults import CATALOGUE, Fault, FaultState, Trigger
from nc_sim.params import Scope

SNAPSHOTS_PER_MACHINE = 8  # the oldest goes (a snapshot is a few hundred kB in memory)
_BY_KIND = {cls.kind: cls for cls in CATALOGUE}
_MODEL: TypeAdapter[FaultModel] = TypeAdapter(FaultModel)


def to_fault(model: FaultModel) -> Fault:
    """nc_sim's fault for the API's model."""
    fields = model.model_dump(exclude={"kind"})
    return _BY_KIND[model.kind](**fields)


def to_model(fault: Fault) -> FaultModel:
    """The API's model of nc_sim's fault."""
    return _MODEL.validate_python({"kind": fault.kind, **vars(fault)})


def describe(fault: Fault) -> str:
    """The fault in the instructor's words."""
    axis = getattr(fault, "axis", "")
    where = f"{axis}: " if axis else "PLC: "
    match fault.kind:
        case "motor_inverted":
            what = "motor wired inverted"
        case "encoder_inverted":
            what = "encoder counts inverted"
        case "drive_gain_wrong":
            what = f"drive gain × {fault.factor:g}"  # type: ignore[union-attr]
        case "encoder_resolution_wrong":
            what = f"encoder resolution × {fault.factor:g}"  # type: ignore[union-attr]
        case "encoder_noise":
            what = f"encoder noise {fault.rms:g} rms"  # type: ignore[union-attr]
        case "gear_ratio_wrong":
            g, f = fault.gear, fault.factor  # type: ignore[union-attr]
            what = f"gear {g} (M{39 + g}, getriebe[{g - 1}]) ratio × {f:g}"
        case "friction":
            what = f"friction: loses {fault.v_loss:g}/s"  # type: ignore[union-attr]
        case "backlash":
            what = f"backlash {fault.width:g}"  # type: ignore[union-attr]
        case "coupling_soft":
            what = f"coupling stiffness × {fault.factor:g}"  # type: ignore[union-attr]
        case "friction_rising":
            what = f"friction × {fault.factor:g}"  # type: ignore[union-attr]
        case "notch_mistuned":
            what = f"current filters at × {fault.factor:g} their frequency"  # type: ignore[union-attr]
        case "drive_accel_limit":
            what = f"drive accelerates at most {fault.a_max:g}/s²"  # type: ignore[union-attr]
        case "plc_no_ack":
            what = "never acknowledges"
        case "plc_slow_ack":
            what = f"acknowledges after {fault.delay_s:g} s"  # type: ignore[union-attr]
        case "drive_not_ready":
            what = "drive drops ready"
        case _:
            what = "enable drops during motion"
    return where + what


def fault_info(state: FaultState, cycle_s: float) -> FaultInfo:
    since = state.active_since
    return FaultInfo(
        id=state.id,
        fault=to_model(state.fault),
        trigger=TriggerModel(after_s=state.trigger.after_s, on_motion=state.trigger.on_motion),
        injected_s=state.injected_cycle * cycle_s,
        active=since is not None,
        active_since_s=since * cycle_s if since is not None else None,
        text=describe(state.fault),
    )


def faults_of(m: MachineProxy) -> list[FaultInfo]:
    """The machine's injected faults, as its worker has them now (the pushed status may not
    have come yet for a machine just built)."""
    read = m.link.call(ReadStatus(m.id))
    assert isinstance(read, StatusRead)
    m.link.faults = {f.id: f for f in read.faults}
    return [
        fault_info(f, m.link.cycle_s) for f in sorted(m.link.faults.values(), key=lambda f: f.id)
    ]


def inject(m: MachineProxy, req: FaultInject) -> FaultInfo:
    """Inject a fault (422 in the NC's words for an axis or gear the machine lacks)."""
    trigger = Trigger(req.trigger.after_s, req.trigger.on_motion)
    state = m.link.call(InjectFault(m.id, to_fault(req.fault), trigger))
    assert isinstance(state, FaultState)
    m.link.faults[state.id] = state
    return fault_info(state, m.link.cycle_s)


def remove(m: MachineProxy, fid: int) -> None:
    m.link.call(RemoveFault(m.id, fid))
    m.link.faults.pop(fid, None)


@dataclass(frozen=True)
class Kept:
    info: SnapshotInfo
    snap: Snapshot


class Snapshots:
    """Snapshots of machines, in memory (the newest SNAPSHOTS_PER_MACHINE of each)."""

    def __init__(self, store: Store, machines: MachineService) -> None:
        self.store = store
        self.machines = machines
        self._kept: dict[str, deque[Kept]] = {}
        self._ids = itertools.count(1)
        self._lock = threading.Lock()

    def list(self, mid: str) -> list[SnapshotInfo]:
        with self._lock:
            return [k.info for k in self._kept.get(mid, ())]

    def take(self, actor: Actor, m: MachineProxy, label: str) -> SnapshotInfo:
        snap = m.link.call(TakeSnapshot(m.id))
        assert isinstance(snap, Snapshot)
        info = SnapshotInfo(
            id=next(self._ids),
            machine=m.id,
            label=label,
            cycle=snap.cycle,
            t_s=snap.t_s,
            created_unix=time.time(),
            by=actor.name,
            size_bytes=len(snap.data),
        )
        with self._lock:
            self._kept.setdefault(m.id, deque(maxlen=SNAPSHOTS_PER_MACHINE)).append(
                Kept(info, snap)
            )
        return info

    def get(self, mid: str, sid: int) -> Kept:
        with self._lock:
            for k in self._kept.get(mid, ()):
                if k.info.id == sid:
                    return k
        raise not_found(f"snapshot {sid} of machine '{mid}'")

    def restore(self, actor: Actor, m: MachineProxy, sid: int) -> SnapshotInfo:
        """The machine as it was: its lists written back as they were (audited, the
        gateway's store agreeing with the machine), then its whole state."""
        kept = self.get(m.id, sid)
        changes = []
        for (scope, target), values in kept.snap.params.items():
            now = m.cfg.list_values(Scope(scope), target)
            changes += [
                ParameterChange(scope=scope, target=target or None, name=name, value=v)
                for name, v in values.items()
                if now.get(name) != v
            ]
        if changes:
            why = f"restored snapshot {sid} ({kept.info.label or 'no label'})"
            params.write(actor, m, self.store, changes, why)
        self.machines.restore(m.id, kept.snap.data, kept.snap.params, actor.name)
        return kept.info

    def forget(self, mid: str) -> None:
        with self._lock:
            self._kept.pop(mid, None)
