"""The machines of the service: created from the demo or from lists, kept in SQLite, rebuilt
with their stored parameter values at start-up and restart."""

from __future__ import annotations

import threading

from api.auth import Action
from api.machines import MachineCreate
from backend.errors import ApiError, not_found
from backend.services.auth import Actor, authorize
from backend.services.host import MachineHost
from backend.services.parameters import apply_stored
from backend.services.store import Store, StoredMachine
from nc_sim.errors import NcUsageError
from nc_sim.machine.config import MachineConfig, demo_machine, machine_from_lists
from nc_sim.params import ParamListError


class MachineService:
    """Owns the hosts; the real-time loop reads `hosts()`."""

    def __init__(self, store: Store) -> None:
        self.store = store
        self._hosts: dict[str, MachineHost] = {}
        self._lock = threading.Lock()

    def hosts(self) -> list[MachineHost]:
        with self._lock:
            return list(self._hosts.values())

    def get(self, mid: str) -> MachineHost:
        host = self._hosts.get(mid)
        if host is None:
            raise not_found(f"machine '{mid}'")
        return host

    def _config(self, sm: StoredMachine) -> MachineConfig:
        if sm.source == "demo":
            cfg = demo_machine()
        else:
            cfg = machine_from_lists(sm.name, sm.channel_list, sm.axis_lists or {}, sm.tool_list)
        apply_stored(cfg, self.store.values(sm.id))
        return cfg

    def load(self, create_demo: bool) -> None:
        """Bring back every stored machine; a fresh store gets the demo lathe."""
        stored = self.store.machines()
        if not stored and create_demo:
            sm = StoredMachine("demo", "Demo lathe", "demo")
            self.store.add_machine(sm)
            stored = [sm]
        for sm in stored:
            self._hosts[sm.id] = MachineHost(sm.id, sm.name, sm.source, self._config(sm))

    def create(self, actor: Actor, req: MachineCreate) -> MachineHost:
        authorize(actor, Action.ADMINISTER)
        if req.id in self._hosts:
            raise ApiError(409, {"message": f"machine '{req.id}' exists"})
        sm = StoredMachine(
            req.id,
            req.name or req.id,
            "demo" if req.demo else "lists",
            req.channel_list,
            req.axis_lists,
            req.tool_list,
        )
        try:
            cfg = self._config(sm)
        except ParamListError as e:
            raise ApiError(
                422,
                {
                    "message": f"parameter list rejected: {e}",
                    "problems": [
                        {"parameter": p.name, "line": p.line, "message": p.detail} for p in e.errors
                    ],
                },
            ) from None
        except NcUsageError as e:
            raise ApiError(422, {"message": str(e)}) from None
        host = MachineHost(sm.id, sm.name, sm.source, cfg)
        self.store.add_machine(sm)
        with self._lock:
            self._hosts[sm.id] = host
        return host

    def restart(self, actor: Actor, mid: str) -> MachineHost:
        """Power the machine off and on: all stored values apply, pending ones included."""
        authorize(actor, Action.ADMINISTER, mid)
        host = self.get(mid)
        sm = next(s for s in self.store.machines() if s.id == mid)
        cfg = self._config(sm)
        with host.lock:
            host.build(cfg)
            host.pending.clear()
        return host

    def delete(self, actor: Actor, mid: str) -> None:
        authorize(actor, Action.ADMINISTER, mid)
        host = self.get(mid)
        with self._lock:
            del self._hosts[mid]
        host.deleted = True
        host.interrupt_steps()  # a step in progress ends with the machine
        self.store.delete_machine(mid)
