"""The OpenAPI schema, completed with the websocket messages so the browser's types come from
one place (`inbetrieb openapi` writes it; the frontend generates its types from the file)."""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi
from pydantic import BaseModel
from pydantic.json_schema import models_json_schema

from api.classes import GridFrame
from api.common import ErrorBody
from api.telemetry import (
    ErrorMessage,
    EventMessage,
    FrameHeader,
    Hello,
    HistoryMessage,
    NoticeMessage,
    SignalInfo,
    StatusMessage,
    Subscribe,
    Subscribed,
)
from backend.errors import STATUS, URI_TOO_LONG, BadRequest
from backend.http_limits import MAX_URL_BYTES

WEBSOCKET_MODELS: tuple[type[BaseModel], ...] = (
    Subscribe,
    Hello,
    Subscribed,
    EventMessage,
    StatusMessage,
    NoticeMessage,
    HistoryMessage,
    ErrorMessage,
    FrameHeader,
    SignalInfo,
    GridFrame,  # the instructor console's grid
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
            _one_error_body(doc)
            app.openapi_schema = doc
        return app.openapi_schema

    app.openapi = schema  # type: ignore[method-assign]


def _one_error_body(doc: dict[str, Any]) -> None:
    """FastAPI documents request validation as its `HTTPValidationError`; the service answers
    every error with `ErrorBody` (backend/errors.py), so the schema says that. FastAPI also
    answers 400 to a JSON body it cannot decode, which every operation with a body documents;
    every operation documents the server's 414 for a URL over its limit."""
    content = {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorBody"}}}
    too_long = {
        "description": f"the URL is longer than {MAX_URL_BYTES} bytes (answered as text)",
        "content": {"text/plain": {"schema": {"type": "string"}}},
    }
    for operations in doc.get("paths", {}).values():
        for op in operations.values():
            answers = op.setdefault("responses", {})
            answer = answers.get("422")
            if answer and "HTTPValidationError" in str(answer.get("content")):
                answer["content"] = content
            # the server's own limit, before any route: a plain-text answer (http_limits.py)
            answers.setdefault(str(URI_TOO_LONG), too_long)
            if "application/json" in op.get("requestBody", {}).get("content", {}):
                answers.setdefault(
                    str(STATUS[BadRequest][0]),
                    {"description": STATUS[BadRequest][1], "content": content},
                )
    schemas = doc["components"]["schemas"]
    if "ErrorBody" not in schemas:
        _, defs = models_json_schema(
            [(ErrorBody, "serialization")], ref_template="#/components/schemas/{model}"
        )
        schemas.update(defs["$defs"])
    for unused in ("HTTPValidationError", "ValidationError"):
        schemas.pop(unused, None)
