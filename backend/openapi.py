"""The OpenAPI schema, completed with the websocket messages so the browser's types come from
one place (`inbetrieb openapi` writes it; the frontend generates its types from the file)."""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi
from pydantic import BaseModel
from pydantic.json_schema import models_json_schema

from api.telemetry import (
    ErrorMessage,
    EventMessage,
    FrameHeader,
    Hello,
    SignalInfo,
    Subscribe,
    Subscribed,
)

WEBSOCKET_MODELS: tuple[type[BaseModel], ...] = (
    Subscribe,
    Hello,
    Subscribed,
    EventMessage,
    ErrorMessage,
    FrameHeader,
    SignalInfo,
)


def install(app: FastAPI) -> None:
    """Replace `app.openapi` by one that also lists the websocket message models."""

    def schema() -> dict[str, Any]:
        if app.openapi_schema is None:
            doc = get_openapi(
                title=app.title,
                version=app.version,
                description=app.description,
                routes=app.routes,
            )
            _, defs = models_json_schema(
                [(m, "serialization") for m in WEBSOCKET_MODELS],
                ref_template="#/components/schemas/{model}",
            )
            doc.setdefault("components", {}).setdefault("schemas", {}).update(defs["$defs"])
            app.openapi_schema = doc
        return app.openapi_schema

    app.openapi = schema  # type: ignore[method-assign]
