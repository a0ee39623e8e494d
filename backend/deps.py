"""The service's parts and typed dependencies for the routes."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends
from fastapi.requests import HTTPConnection

from backend.services.auth import Actor
from backend.services.host import MachineHost
from backend.services.loop import RealtimeLoop
from backend.services.machines import MachineService
from backend.services.recorder import Recorders
from backend.services.store import Store
from backend.services.telemetry import TelemetryHub
from backend.services.traces import TraceService
from backend.services.viewer import RerunViewer
from backend.services.warmup import warm_up
from backend.settings import Settings


@dataclass
class Services:
    """Everything a request may need; built at start-up, stopped at shutdown."""

    settings: Settings
    store: Store
    machines: MachineService
    loop: RealtimeLoop
    hub: TelemetryHub
    traces: TraceService
    recorders: Recorders
    viewer: RerunViewer
    started: float

    @classmethod
    def start(cls, settings: Settings) -> Services:
        store = Store(settings.db_path)
        machines = MachineService(store)
        machines.load(create_demo=settings.demo)
        warm_up()
        for host in machines.hosts():  # start every clock from now
            host.set_mode(host.pacing.mode, host.pacing.until_cycle)
        loop = RealtimeLoop(machines.hosts, settings.loop_period_s)
        hub = TelemetryHub(settings.frame_s, settings.max_frame_samples, settings.client_stall_s)
        tdir = settings.traces_path
        traces = TraceService(store, tdir, machines)
        recorders = Recorders(tdir / "recordings")
        viewer = RerunViewer(tdir / "rerun-viewer.log")
        loop.start()
        hub.start()
        recorders.start()
        return cls(settings, store, machines, loop, hub, traces, recorders, viewer, time.time())

    async def stop(self) -> None:
        await self.hub.stop()
        self.recorders.stop()
        self.viewer.stop()
        self.loop.stop()
        self.store.close()


def get_services(conn: HTTPConnection) -> Services:
    services: Services = conn.app.state.services
    return services


def get_actor(conn: HTTPConnection) -> Actor:
    """Who sends this request. Authentication will set it from the session."""
    s = get_services(conn).settings
    return Actor(s.user, s.role)


ServicesDep = Annotated[Services, Depends(get_services)]
ActorDep = Annotated[Actor, Depends(get_actor)]


def get_host(mid: str, services: ServicesDep) -> MachineHost:
    return services.machines.get(mid)


HostDep = Annotated[MachineHost, Depends(get_host)]
