"""The service's parts and typed dependencies for the routes."""

from __future__ import annotations

import asyncio
import sys
import time
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends
from fastapi.requests import HTTPConnection

from backend.errors import ApiError
from backend.security import is_loopback
from backend.services.accounts import Accounts
from backend.services.auth import Actor
from backend.services.machines import MachineProxy, MachineService
from backend.services.recorder import Recorders
from backend.services.store import Store
from backend.services.telemetry import TelemetryHub
from backend.services.traces import TraceService
from backend.services.viewer import RerunViewer
from backend.settings import Settings
from backend.workers.pool import WorkerPool

GIL_SWITCH_S = 0.0005


@dataclass
class Services:
    """Everything a request may need; built at start-up, stopped at shutdown."""

    settings: Settings
    store: Store
    accounts: Accounts
    machines: MachineService
    pool: WorkerPool
    hub: TelemetryHub
    traces: TraceService
    recorders: Recorders
    viewer: RerunViewer
    started: float

    @classmethod
    async def start(cls, settings: Settings) -> Services:
        # Python hands the GIL to a waiting thread only every 5 ms by default: a request
        # handled on the thread pool would wait that long behind the telemetry hub
        sys.setswitchinterval(GIL_SWITCH_S)
        store = Store(settings.db_path)
        accounts = Accounts(store)
        accounts.ensure_admin()
        loop = asyncio.get_running_loop()  # reads the local workers' replies and pushes
        pool = WorkerPool(settings.workers, settings.loop_period_s, settings.cluster, loop=loop)
        machines = MachineService(store, pool)
        # both wait for workers' replies, which this loop reads: off it
        await asyncio.to_thread(pool.start, machines.on_push, machines.on_death)
        await asyncio.to_thread(machines.load, create_demo=settings.demo)
        hub = TelemetryHub(settings.frame_s, settings.max_frame_samples, settings.client_stall_s)
        tdir = settings.traces_path
        traces = TraceService(store, tdir, machines)
        recorders = Recorders(tdir / "recordings")
        viewer = RerunViewer(tdir / "rerun-viewer.log")
        hub.start()
        recorders.start()
        services = cls(
            settings, store, accounts, machines, pool, hub, traces, recorders, viewer, time.time()
        )
        services.print_login_link()
        return services

    def print_login_link(self) -> None:
        """On loopback, a one-time login link for the first admin (as Jupyter prints one):
        `make run` opens the HMI without a password, and nobody else gets one."""
        admin = self.accounts.first_admin()
        if admin is None or not is_loopback(self.settings.host):
            return
        token = self.accounts.new_token(admin, "printed at start", once=True)
        host = "localhost" if ":" in self.settings.host else self.settings.host
        link = f"http://{host}:{self.settings.port}/auth/once?token={token}"
        print(f"Log in as {admin} (once, within an hour): {link}", flush=True)

    async def stop(self) -> None:
        await self.hub.stop()
        self.recorders.stop()
        self.viewer.stop()
        self.pool.stop()
        self.store.close()


# The dependencies are coroutines: FastAPI would run plain functions on its thread pool, a
# thread hand-over per request for a dictionary lookup.
async def get_services(conn: HTTPConnection) -> Services:
    services: Services = conn.app.state.services
    return services


async def get_actor(conn: HTTPConnection) -> Actor:
    """Who sends this request, as the authentication middleware found (backend/authn.py)."""
    actor: Actor | None = conn.scope.get("state", {}).get("actor")
    if actor is None:  # a route outside the guarded paths asked: nobody
        raise ApiError(401, {"message": "not logged in"})
    return actor


ServicesDep = Annotated[Services, Depends(get_services)]
ActorDep = Annotated[Actor, Depends(get_actor)]


async def get_machine(mid: str, services: ServicesDep) -> MachineProxy:
    return services.machines.get(mid)


MachineDep = Annotated[MachineProxy, Depends(get_machine)]
