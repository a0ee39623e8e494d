"""The FastAPI application: wiring only (routes in backend/routes, logic in backend/services)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import FastAPI
from fastapi.routing import APIRoute, APIWebSocketRoute

from backend import VERSION, errors, frontend, openapi
from backend.authn import Authentication, guarded
from backend.bodies import DEFAULT_BODY_BYTES, OPEN_BODY_BYTES, BodyLimitAnswer
from backend.deps import Services, rule_of
from backend.errors import Forbidden, NotLoggedIn, responses
from backend.logs import RequestLog
from backend.routes import (
    assist,
    audit,
    auth,
    bundles,
    classes,
    commands,
    control,
    exercise,
    exercises,
    faults,
    fleet,
    flight,
    history,
    machines,
    metrics,
    parameters,
    programs,
    report,
    roster,
    scope,
    service,
    share,
    snapshots,
    telemetry,
    tokens,
    traces,
    users,
    versions,
    viewer,
)
from backend.security import Perimeter, host_names
from backend.settings import Settings


def create_app(settings: Settings | None = None) -> FastAPI:
    """The service with its real-time loop and telemetry hub started by the lifespan."""
    cfg = settings or Settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        app.state.services = await Services.start(cfg)
        yield
        await app.state.services.stop()

    app = FastAPI(
        title="Inbetrieb",
        version=VERSION,
        description="Commissioning HMI for a simulated NC: machines, commands, parameters, "
        "live telemetry.",
        lifespan=lifespan,
        docs_url=None,  # ours (backend/frontend.py): Swagger UI from our build, not a CDN
        redoc_url=None,
    )
    app.add_middleware(Authentication)
    app.add_middleware(BodyLimitAnswer)
    app.add_middleware(Perimeter, hosts=host_names(cfg.host, cfg.allowed_hosts))
    app.add_middleware(RequestLog)  # outermost: a refused request is logged with its id too

    errors.install(app)
    app.include_router(auth.router, max_body_size=OPEN_BODY_BYTES)
    # every other route needs a token or a session (backend/authn.py)
    for module in (
        assist,
        service,
        machines,
        classes,
        exercises,
        exercise,
        roster,
        faults,
        snapshots,
        commands,
        control,
        parameters,
        programs,
        report,
        telemetry,
        scope,
        traces,
        audit,
        history,
        flight,
        bundles,
        share,
        fleet,
        tokens,
        users,
        versions,
        viewer,
        metrics,
    ):
        app.include_router(
            module.router,
            responses=responses(NotLoggedIn, Forbidden),
            max_body_size=DEFAULT_BODY_BYTES,
        )
    _every_route_has_a_rule(app)
    openapi.install(app)
    frontend.mount(app, cfg.frontend_dir)
    return app


def _every_route_has_a_rule(app: FastAPI) -> None:
    """A guarded route without its rule in the authorization matrix is a bug: refuse to
    start rather than serve it to every role."""
    for route in app.routes:
        path = getattr(route, "path", "")
        routed = isinstance(route, APIRoute | APIWebSocketRoute)
        if guarded(path) and routed and rule_of(route) is None:
            raise RuntimeError(f"{path} declares no rule: add dependencies=[permit(...)]")


app = create_app()
