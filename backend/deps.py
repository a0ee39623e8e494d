"""The service's parts and typed dependencies for the routes."""

from __future__ import annotations

import asyncio
import sys
import time
from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import Depends, WebSocketException
from fastapi.requests import HTTPConnection

from api.audit import AuditKind
from api.auth import HELD, Action
from backend.errors import ApiError, NotLoggedIn
from backend.security import SAFE_METHODS, is_loopback
from backend.services.accounts import Accounts
from backend.services.assist import Assistants
from backend.services.assist_runs import AssistRuns
from backend.services.audit import Audit
from backend.services.audit_log import Entry
from backend.services.auth import Actor, authorize
from backend.services.bundle import Bundles
from backend.services.classes import Classes
from backend.services.console import ConsoleHub
from backend.services.control import Control
from backend.services.exercises import Exercises
from backend.services.flight import FlightRecorder
from backend.services.history import History
from backend.services.machines import MachineProxy, MachineService
from backend.services.metrics import Metrics, Sources
from backend.services.recorder import Recorders
from backend.services.replay import SeatRecorder
from backend.services.report import Reports
from backend.services.roster import Roster
from backend.services.sessions import SessionWatch
from backend.services.shares import Shares
from backend.services.store import Store
from backend.services.telemetry import TelemetryHub
from backend.services.traces import TraceService
from backend.services.training import Snapshots, StandingFaults
from backend.services.versions import Versions
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
    audit: Audit
    control: Control
    machines: MachineService
    pool: WorkerPool
    hub: TelemetryHub
    traces: TraceService
    recorders: Recorders
    viewer: RerunViewer
    sessions: SessionWatch
    assistants: Assistants
    versions: Versions
    started: float
    assist_runs: AssistRuns
    reports: Reports
    exercises: Exercises
    classes: Classes
    console: ConsoleHub
    snapshots: Snapshots
    faults: StandingFaults
    history: History
    flight: FlightRecorder
    bundles: Bundles
    shares: Shares
    roster: Roster
    metrics: Metrics

    @classmethod
    async def start(cls, settings: Settings) -> Services:
        # Python hands the GIL to a waiting thread only every 5 ms by default: a request
        # handled on the thread pool would wait that long behind the telemetry hub
        sys.setswitchinterval(GIL_SWITCH_S)
        store = Store(settings.db_path)
        accounts = Accounts(store)
        accounts.ensure_admin()
        shares = Shares(store, accounts)
        shares.start()
        loop = asyncio.get_running_loop()  # reads the local workers' replies and pushes
        pool = WorkerPool(settings.workers, settings.loop_period_s, settings.cluster, loop=loop)
        flight_s = (settings.flight_before_s, settings.flight_after_s)
        machines = MachineService(store, pool, flight_s)
        history = History(store, settings.history_days, settings.history_rows)
        history.attach(machines)
        audit = Audit(store)
        control = Control(machines, audit, settings.control_grace_s)
        exercises = Exercises(store, settings.exercises_dir)
        faults = StandingFaults(store, machines)
        snapshots = Snapshots(store, machines, faults)
        # before the machines load: the seats' exercises
        classes = Classes(store, accounts, machines, exercises, audit, faults, snapshots)
        # both wait for workers' replies, which this loop reads: off it
        await asyncio.to_thread(pool.start, machines.on_push, machines.on_death)
        await asyncio.to_thread(machines.load, create_demo=settings.demo)
        await asyncio.to_thread(classes.refreeze)
        history.service_started(machines.proxies())
        hub = TelemetryHub(
            settings.frame_s, settings.max_frame_samples, settings.client_stall_s, history
        )
        tdir = settings.traces_path
        traces = TraceService(
            store, tdir, machines, settings.library_quota_mb, settings.library_user_quota_mb
        )
        recorders = Recorders(tdir / "recordings", settings.recordings_quota_mb)
        flight = FlightRecorder(
            machines,
            traces,
            history,
            settings.flight_minutes,
            settings.flight_decimation,
            settings.flight_keep,
        )
        flight.start()
        traces.notes_of = history.notes_in
        viewer = RerunViewer(tdir / "rerun-viewer.log")
        hub.start()
        recorders.start()
        hub.on_connect, hub.on_disconnect = control.connected, control.disconnected
        control.start()
        sessions = SessionWatch(accounts, hub, control)
        sessions.start()
        assist_runs = AssistRuns(store)
        versions = Versions(store, machines)
        console = ConsoleHub(classes, SeatRecorder(store, history))
        console.start()
        services = cls(
            settings,
            store,
            accounts,
            audit,
            control,
            machines,
            pool,
            hub,
            traces,
            recorders,
            viewer,
            sessions,
            Assistants(),
            versions,
            time.time(),
            assist_runs,
            Reports(store, audit, assist_runs, traces, versions),
            exercises,
            classes,
            console,
            snapshots,
            faults,
            history,
            flight,
            Bundles(store, tdir / "bundles", traces),
            shares,
            Roster(store, classes),
            Metrics(),
        )
        transport = "ray" if settings.cluster else "local"
        sources = Sources(transport, services.started, machines, hub, console, audit)
        services.metrics.attach(sources)
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
        scheme = "https" if self.settings.https else "http"
        link = f"{scheme}://{host}:{self.settings.port}/auth/once?token={token}"
        print(f"Log in as {admin} (once, within an hour): {link}", flush=True)

    async def stop(self) -> None:
        await self.console.stop()
        await self.sessions.stop()
        await self.control.stop()
        await self.hub.stop()
        self.recorders.stop()
        self.viewer.stop()
        self.assistants.stop()
        self.flight.stop()
        self.shares.stop()
        self.history.service_stopping(self.machines.proxies())
        self.history.stop()
        self.pool.stop()
        self.audit.stop()
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
        raise NotLoggedIn("not logged in")
    return actor


_KIND: dict[Action, AuditKind] = {  # what a refused attempt of each action is recorded as
    Action.OBSERVE: "command",  # never refused by role (every role observes): for the type
    Action.NOTE: "machine",
    Action.ASK: "control",
    Action.TOKENS: "token",
    Action.SHARE: "machine",
    Action.CAPTURE: "trace",
    Action.RECORD: "recording",
    Action.DELETE_TRACE: "trace",
    Action.PROGRAMS: "program",
    Action.CONTROL: "control",
    Action.STOP: "command",
    Action.COMMAND: "command",
    Action.CONFIGURE: "parameter",
    Action.VERSIONS: "version",
    Action.ASSIST: "parameter",  # assistants propose parameters
    Action.SIGN_OFF: "report",
    Action.EXERCISE: "training",
    Action.TEACH: "training",
    Action.TAKE_CONTROL: "control",
    Action.SIMULATE: "simulation",  # (snapshots too)
    Action.MACHINES: "machine",
    Action.USERS: "user",
}
ServicesDep = Annotated[Services, Depends(get_services)]
ActorDep = Annotated[Actor, Depends(get_actor)]


def permit(action: Action) -> Any:
    """A route's rule in the authorization matrix (api/auth.py): the actor's role must allow
    the action; an action only a control holder may do also needs control of the machine in
    the path (a free machine is taken). Every guarded route declares one (backend/main.py
    refuses to start otherwise)."""

    async def check(conn: HTTPConnection, services: ServicesDep) -> None:
        actor = await get_actor(conn)
        mid: str | None = conn.path_params.get("mid")
        try:
            authorize(actor, action, mid)
            if action in HELD and mid is not None:
                services.control.hold(actor, services.machines.get(mid))
        except ApiError as e:
            if conn.scope["type"] == "websocket":  # refused before the accept: HTTP 403
                raise WebSocketException(1008, str(e)[:120]) from None
            if conn.scope["method"] not in SAFE_METHODS:  # an attempt to change something
                services.audit.record_later(
                    Entry(
                        actor.name,
                        actor.session,
                        _KIND[action],
                        f"{conn.scope['method']} {conn.scope['path']}",
                        mid or "",
                        outcome=f"refused ({e.status}): {e}",
                    )
                )
            raise

    check.action = action  # type: ignore[attr-defined]  # the rule, for the start-up check
    return Depends(check)


def rule_of(route: object) -> Action | None:
    """The action a route declared with `permit`, None without one."""
    dependant = getattr(route, "dependant", None)
    for dep in dependant.dependencies if dependant else []:
        action = getattr(dep.call, "action", None)
        if isinstance(action, Action):
            return action
    return None


async def get_machine(mid: str, services: ServicesDep) -> MachineProxy:
    return services.machines.get(mid)


MachineDep = Annotated[MachineProxy, Depends(get_machine)]
