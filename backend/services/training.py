"""Faults and snapshots of a machine, as the gateway handles them for instructors: the API's
fault models to nc_sim's and back, the faults as they stand and the snapshots kept per
machine in the store (a restart of the service loses neither)."""

from __future__ import annotations

import json
import threading
import time
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
    ParamSnapshot,
    ReadStatus,
    RemoveFault,
    Snapshot,
    StatusRead,
    TakeSnapshot,
)
from nc_sim.faults import CATALOGUE, NOW, Fault, FaultState, Trigger
from nc_sim.params import Scope

SNAPSHOTS_PER_MACHINE = 8  # the oldest goes (a snapshot is a few hundred kB)
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


# --- kept in the store: a restart loses neither ----------------------------------------------
SCHEMA = """
CREATE TABLE IF NOT EXISTS machine_faults (
    machine TEXT PRIMARY KEY,
    faults TEXT NOT NULL,  -- JSON: the FaultInfos as they stood after the last change
    saved REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS snapshots (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    machine TEXT NOT NULL,
    info TEXT NOT NULL,    -- JSON: SnapshotInfo
    cycle INTEGER NOT NULL,
    t_s REAL NOT NULL,
    data BLOB NOT NULL,    -- the machine's state as nc_sim pickled it
    params TEXT NOT NULL,  -- JSON: [[scope, target, {name: value}], ...]
    pinned INTEGER NOT NULL DEFAULT 0  -- a class seat's start: never pruned
);
CREATE INDEX IF NOT EXISTS snapshots_machine ON snapshots (machine, id);
"""


class StandingFaults:
    """Every machine's training faults as they stood after their last change (injected,
    removed, a snapshot restored), in the store: a restart builds the machine with them
    again (an active one at once, an armed one armed again), not with the exercise's alone."""

    def __init__(self, store: Store, machines: MachineService) -> None:
        self.store = store
        store.script(SCHEMA)
        machines.kept_faults = self.kept
        machines.on_deleted.append(self.forget)

    def keep(self, m: MachineProxy) -> list[FaultInfo]:
        """Read the machine's faults from its worker and keep them; the faults."""
        infos = faults_of(m)
        text = json.dumps([f.model_dump(mode="json") for f in infos])
        self.store.run(
            "INSERT OR REPLACE INTO machine_faults (machine, faults, saved) VALUES (?, ?, ?)",
            (m.id, text, time.time()),
        )
        return infos

    def kept(self, mid: str) -> list[tuple[Fault, Trigger]] | None:
        """The machine's faults to build it with (None: none kept, the machine's own apply)."""
        rows = self.store.query("SELECT faults FROM machine_faults WHERE machine = ?", (mid,))
        if not rows:
            return None
        infos = [FaultInfo.model_validate(f) for f in json.loads(rows[0]["faults"])]
        return [
            (
                to_fault(f.fault),
                NOW if f.active else Trigger(f.trigger.after_s, f.trigger.on_motion),
            )
            for f in infos
        ]

    def count(self, mid: str) -> int:
        """How many faults are kept for the machine."""
        faults = self.kept(mid)
        return len(faults) if faults is not None else 0

    def forget(self, mid: str) -> None:
        self.store.run("DELETE FROM machine_faults WHERE machine = ?", (mid,))


@dataclass(frozen=True)
class Kept:
    info: SnapshotInfo
    snap: Snapshot


def _params_json(params: ParamSnapshot) -> str:
    return json.dumps([[scope, target, values] for (scope, target), values in params.items()])


def _params_of(text: str) -> ParamSnapshot:
    return {(scope, target): values for scope, target, values in json.loads(text)}


class Snapshots:
    """Snapshots of machines in the store (the newest SNAPSHOTS_PER_MACHINE of each): a
    class's saved states outlive a restart of the service."""

    def __init__(self, store: Store, machines: MachineService, faults: StandingFaults) -> None:
        self.store = store
        store.script(SCHEMA)
        self.machines = machines
        self.faults = faults
        self._lock = threading.Lock()
        machines.on_deleted.append(self.forget)

    def list(self, mid: str) -> list[SnapshotInfo]:
        rows = self.store.query("SELECT info FROM snapshots WHERE machine = ? ORDER BY id", (mid,))
        return [SnapshotInfo.model_validate_json(r["info"]) for r in rows]

    def count(self, mid: str) -> int:
        """How many snapshots the machine has."""
        return len(self.list(mid))

    def take(self, actor: Actor, m: MachineProxy, label: str, pinned: bool = False) -> SnapshotInfo:
        """The machine's state now, kept; the oldest beyond SNAPSHOTS_PER_MACHINE goes (a
        `pinned` one, a class seat's start, never does)."""
        snap = m.link.call(TakeSnapshot(m.id))
        assert isinstance(snap, Snapshot)
        with self._lock:  # its id is the row's: one insert at a time
            self.store.run(
                "INSERT INTO snapshots (machine, info, cycle, t_s, data, params, pinned) "
                "VALUES (?, '', ?, ?, ?, ?, ?)",
                (m.id, snap.cycle, snap.t_s, snap.data, _params_json(snap.params), int(pinned)),
            )
            sid = int(self.store.query("SELECT max(id) AS id FROM snapshots")[0]["id"])
            info = SnapshotInfo(
                id=sid,
                machine=m.id,
                label=label,
                cycle=snap.cycle,
                t_s=snap.t_s,
                created_unix=time.time(),
                by=actor.name,
                size_bytes=len(snap.data),
            )
            self.store.run(
                "UPDATE snapshots SET info = ? WHERE id = ?", (info.model_dump_json(), sid)
            )
            self.store.run(
                "DELETE FROM snapshots WHERE machine = ? AND pinned = 0 AND id NOT IN "
                "(SELECT id FROM snapshots WHERE machine = ? AND pinned = 0 "
                "ORDER BY id DESC LIMIT ?)",
                (m.id, m.id, SNAPSHOTS_PER_MACHINE),
            )
        return info

    def get(self, mid: str, sid: int) -> Kept:
        rows = self.store.query(
            "SELECT info, cycle, t_s, data, params FROM snapshots WHERE machine = ? AND id = ?",
            (mid, sid),
        )
        if not rows:
            raise not_found(f"snapshot {sid} of machine '{mid}'")
        r = rows[0]
        snap = Snapshot(r["cycle"], r["t_s"], bytes(r["data"]), _params_of(r["params"]))
        return Kept(SnapshotInfo.model_validate_json(r["info"]), snap)

    def restore(self, actor: Actor, m: MachineProxy, sid: int) -> SnapshotInfo:
        """The machine as it was: its lists written back as they were (audited, the
        gateway's store agreeing with the machine), then its whole state, faults and all
        (kept as they stand now)."""
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
        self.faults.keep(m)
        return kept.info

    def start_of(self, mid: str) -> int:
        """The id of the machine's pinned start snapshot; 404 when it has none."""
        rows = self.store.query(
            "SELECT id FROM snapshots WHERE machine = ? AND pinned = 1 ORDER BY id LIMIT 1", (mid,)
        )
        if not rows:
            raise not_found(f"start snapshot of machine '{mid}'")
        return int(rows[0]["id"])

    def forget(self, mid: str) -> None:
        self.store.run("DELETE FROM snapshots WHERE machine = ?", (mid,))
