"""The service's log: lines of text (default) or one JSON object per line for a log
collector (`INBETRIEB_LOG_FORMAT=json`). Every line written while a request is served names
that request (`request_id`, also sent back as `X-Request-ID` and kept in the audit rows it
made) and who sent it (`actor`); each request ends with an access line (method, path without
its query — links carry tokens there —, status, duration).
"""

from __future__ import annotations

import json
import logging
import os
import re
import secrets
import sys
import time
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, Literal

from starlette.types import ASGIApp, Message, Receive, Scope, Send

LogFormat = Literal["text", "json"]
# an id a proxy or a client sent along: kept when it is short and plain, else a new one
_GIVEN_ID = re.compile(r"[A-Za-z0-9._-]{1,64}")
access = logging.getLogger("inbetrieb.access")


@dataclass
class _Request:
    """The request being served in this context (its scope's state holds the actor once the
    authentication middleware found one)."""

    request_id: str
    state: dict[str, Any]
    arrived: float  # perf_counter() when its first byte had been read (ASGI's call)

    @property
    def actor(self) -> str:
        found = self.state.get("actor")
        return str(getattr(found, "name", "")) if found is not None else ""


_current: ContextVar[_Request | None] = ContextVar("inbetrieb_request", default=None)


def request_id() -> str:
    """The id of the request being served here ('' outside a request)."""
    found = _current.get()
    return found.request_id if found is not None else ""


def request_arrived() -> float:
    """perf_counter() when the request being served arrived (now outside a request)."""
    found = _current.get()
    return found.arrived if found is not None else time.perf_counter()


class _RequestFields(logging.Filter):
    """Every record gets the request's id and actor (empty outside a request)."""

    def filter(self, record: logging.LogRecord) -> bool:
        found = _current.get()
        record.request_id = found.request_id if found is not None else ""
        record.actor = found.actor if found is not None else ""
        return True


# the access line's fields, besides the message
_ACCESS_FIELDS = ("method", "path", "status", "duration_ms", "client")


class JsonLines(logging.Formatter):
    """One JSON object per record: time (UTC, ISO 8601), level, logger, message, request_id,
    actor, the access line's fields, and the exception's text if there is one."""

    def format(self, record: logging.LogRecord) -> str:
        out: dict[str, Any] = {
            "time": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(record.created))
            + f".{int(record.msecs):03d}Z",
            "level": record.levelname.lower(),
            "logger": record.name,
            "message": record.getMessage(),
            "request_id": getattr(record, "request_id", ""),
            "actor": getattr(record, "actor", ""),
        }
        for name in _ACCESS_FIELDS:
            if hasattr(record, name):
                out[name] = getattr(record, name)
        if record.exc_info:
            out["exception"] = self.formatException(record.exc_info)
        return json.dumps(out, ensure_ascii=False)


_TEXT = "%(asctime)s %(levelname)s %(name)s %(process)d [%(request_id)s %(actor)s] %(message)s"
LEVELS = ("debug", "info", "warning", "error")


def configure(log_format: LogFormat, level: str) -> None:
    """Send the service's records (ours, uvicorn's) to stderr in the format asked for. The
    worker processes take the same from the environment they start with."""
    os.environ["INBETRIEB_LOG_FORMAT"], os.environ["INBETRIEB_LOG_LEVEL"] = log_format, level
    _install(log_format, level)


def configure_worker() -> None:
    """A worker process: the gateway's format and level (text, warning when started alone)."""
    log_format = os.environ.get("INBETRIEB_LOG_FORMAT", "text")
    level = os.environ.get("INBETRIEB_LOG_LEVEL", "warning")
    _install("json" if log_format == "json" else "text", level if level in LEVELS else "warning")


def _install(log_format: LogFormat, level: str) -> None:
    handler = logging.StreamHandler(sys.stderr)
    handler.addFilter(_RequestFields())
    handler.setFormatter(JsonLines() if log_format == "json" else logging.Formatter(_TEXT))
    root = logging.getLogger()
    root.handlers[:] = [handler]
    root.setLevel(level.upper())
    for name in ("uvicorn", "uvicorn.error"):  # through ours, not uvicorn's own handlers
        logging.getLogger(name).handlers[:] = []
        logging.getLogger(name).propagate = True


class RequestLog:
    """ASGI middleware (outermost): a request id for each request and websocket, the
    `X-Request-ID` header on the answer, and the access line when it ends."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        given = dict(scope["headers"]).get(b"x-request-id", b"").decode("latin-1")
        rid = given if _GIVEN_ID.fullmatch(given) else secrets.token_hex(8)
        t0 = time.perf_counter()
        token = _current.set(_Request(rid, scope.setdefault("state", {}), t0))
        status = 0

        async def sending(message: Message) -> None:
            nonlocal status
            if message["type"] == "http.response.start":
                status = message["status"]
                message.setdefault("headers", [])
                message["headers"] = [*message["headers"], (b"x-request-id", rid.encode())]
            elif message["type"] == "websocket.accept":
                status = 101
            elif message["type"] == "websocket.close" and not status:
                status = 403  # refused before it was accepted
            await send(message)

        try:
            await self.app(scope, receive, sending)
        finally:
            if access.isEnabledFor(logging.INFO):  # nothing built for a line not written
                _access_line(scope, status, time.perf_counter() - t0)
            _current.reset(token)


def _access_line(scope: Scope, status: int, duration_s: float) -> None:
    client = scope.get("client")
    access.info(
        "%s %s %s",
        scope.get("method", "WS"),
        scope["path"],
        status,
        extra={
            "method": scope.get("method", "WEBSOCKET"),
            "path": scope["path"],
            "status": status,
            "duration_ms": round(duration_s * 1000, 1),
            "client": client[0] if client else "",
        },
    )
