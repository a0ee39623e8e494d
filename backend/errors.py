"""Errors the service turns into HTTP answers: the only place that knows status codes.

Services raise the error classes below (each refines a built-in exception); `STATUS` maps each
class to its status, and a class derived from one answers as its base. A worker's refusal
kinds map through `WORKER_FAILURE`.

Every error answer has one body, `api.common.ErrorBody`: `detail` is a `Refusal` (our own
refusals, unknown routes, wrong methods) or the list of schema violations of a request. Routes
document their error answers with `responses(...)`, so the schema lists every status code.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException
from starlette.middleware.body_limit import MAX_BODY_SIZE_SCOPE_KEY

from api.common import ErrorBody, Refusal, ValidationIssue
from backend.validation import FieldTexts, issue_text

# A refused request must not echo a 50 MB body back: each echoed input is cut to this.
MAX_ECHO_CHARS = 200


class ApiError(Exception):
    """A refused request. Its class decides the HTTP status (`STATUS`, the one table of
    them); `detail` is the `Refusal`-shaped body (a message alone, or with typed details)."""

    def __init__(self, detail: str | Mapping[str, Any]) -> None:
        body = {"message": detail} if isinstance(detail, str) else dict(detail)
        super().__init__(str(body.get("message", body)))
        self.detail = body

    @property
    def status(self) -> int:
        return http_status(type(self))


class BadRequest(ApiError, ValueError):
    """The request itself is malformed (not its values: those are `Invalid`)."""


class NotLoggedIn(ApiError, PermissionError):
    """No session, or an unknown or expired token."""


class Forbidden(ApiError, PermissionError):
    """Not allowed for this role or seat, or a missing CSRF token."""


class NotFound(ApiError, LookupError):
    """No such machine, trace, recording, user …"""


class Conflict(ApiError, RuntimeError):
    """Cannot be done in the current state (exists already, ended, held by another …)."""


class TooLarge(ApiError, ValueError):
    """A request body over its route's limit."""


class Invalid(ApiError, ValueError):
    """Bad input: which value, its range or why; nothing was applied."""


class TooManyAttempts(ApiError, PermissionError):
    """Too many failed logins from one place: wait."""


class ViewerSilent(ApiError, ConnectionError):
    """The Rerun viewer did not answer."""


class Unavailable(ApiError, ConnectionError):
    """A part the request needs is not there now (a worker being rebuilt, the viewer or the
    PDF renderer not started): try again."""


class TimedOut(ApiError, TimeoutError):
    """The work did not end in time."""


class QuotaUsedUp(ApiError, OSError):
    """A disk quota is used up (which, how much, and what to delete)."""


class WorkerFault(ApiError, RuntimeError):
    """The machine's worker failed on the request: a bug (its log has the trace)."""


# The one table of error statuses, with the reason the schema gives for each.
STATUS: dict[type[ApiError], tuple[int, str]] = {
    BadRequest: (400, "malformed request"),
    NotLoggedIn: (401, "not logged in: no session, or an unknown or expired token"),
    Forbidden: (403, "not allowed for this role, or a missing CSRF token"),
    NotFound: (404, "no such machine, trace or recording"),
    Conflict: (409, "conflicts with the current state"),
    TooLarge: (413, "body too large"),
    Invalid: (422, "bad input: which value, its range or why (nothing was applied)"),
    TooManyAttempts: (429, "too many failed attempts: wait"),
    ViewerSilent: (502, "the Rerun viewer did not answer"),
    Unavailable: (503, "a part the request needs is not running now: try again"),
    TimedOut: (504, "the work did not end in time"),
    QuotaUsedUp: (507, "a disk quota is used up (which, how much, and what to delete)"),
    WorkerFault: (500, "the machine's worker failed on the request (a bug)"),
}
# Answers written below the application (the HTTP protocol layer, before any route).
REQUEST_TIMEOUT, URI_TOO_LONG, HEADERS_TOO_LARGE = 408, 414, 431
# Success statuses of the routes that answer other than 200.
OK, CREATED, NO_CONTENT, SEE_OTHER, TEMPORARY_REDIRECT = 200, 201, 204, 303, 307


def http_status(kind: type[ApiError]) -> int:
    """The HTTP status of an error class (its nearest class in the table)."""
    for cls in kind.__mro__:
        entry = STATUS.get(cls)
        if entry is not None:
            return entry[0]
    raise TypeError(f"{kind.__name__} has no status in the error table")


# A worker's refusal kinds (backend.workers) as the API answers them.
WORKER_FAILURE: dict[str, type[ApiError]] = {
    "not_found": NotFound,
    "invalid": Invalid,
    "conflict": Conflict,
    "internal": WorkerFault,
}


def body_too_large(limit: int) -> str:
    """Why a request body was refused (413)."""
    return f"request body larger than this route's limit of {limit} bytes"


def not_found(what: str) -> NotFound:
    return NotFound(f"{what} not found")


Why = dict[type[ApiError], str]  # reasons of error answers by class (for `responses`)
WORKER_GONE: Why = {
    Unavailable: "the machine's worker stopped: the machine is being rebuilt, try again"
}


def responses(*errors: type[ApiError], why: Why | None = None) -> dict[int | str, Any]:
    """OpenAPI `responses=` for error answers: each error's status with the shared body and
    a reason (`why` overrides or adds reasons, e.g. `{Conflict: "the NC refused the
    command"}`)."""
    reasons = {http_status(e): STATUS[e][1] for e in errors}
    reasons |= {http_status(e): text for e, text in (why or {}).items()}
    return {c: {"model": ErrorBody, "description": text} for c, text in sorted(reasons.items())}


def clip(value: Any, limit: int = MAX_ECHO_CHARS) -> Any:
    """`value` itself when short, else the start of its text ending in '…'."""
    if isinstance(value, bytes):
        value = value[: limit * 4].decode("utf-8", "replace")
    if isinstance(value, str):
        return value if len(value) <= limit else value[:limit] + "…"
    text = json.dumps(value, default=str, ensure_ascii=False)
    return value if len(text) <= limit else text[:limit] + "…"


def _answer(status: int, detail: Refusal | list[ValidationIssue], **kw: Any) -> JSONResponse:
    body = ErrorBody(detail=detail).model_dump(mode="json")
    return JSONResponse(status_code=status, content=body, **kw)


def answer(e: ApiError, headers: Mapping[str, str] | None = None) -> JSONResponse:
    """The error's answer (for middleware that refuses before any route)."""
    return _answer(e.status, Refusal.model_validate(e.detail), headers=headers)


def install(app: FastAPI) -> None:
    """Register the handlers that give every error answer the shared body."""

    @app.exception_handler(ApiError)
    async def api_error(_request: Request, exc: ApiError) -> JSONResponse:
        return answer(exc)

    fields: list[FieldTexts] = []  # from the schema on first use (routes are all added then)

    @app.exception_handler(RequestValidationError)
    async def invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        if not fields:
            fields.append(FieldTexts(app.openapi()))
        # the route's body model: a field name several models use means what this one says
        body = getattr(request.scope.get("route"), "body_field", None)
        model = getattr(
            getattr(getattr(body, "field_info", None), "annotation", None), "__name__", None
        )
        issues = [
            ValidationIssue(
                loc=list(e.get("loc", ())),
                msg=clip(str(e.get("msg", ""))),
                type=str(e.get("type", "")),
                input=clip(e.get("input")),
                text=clip(
                    issue_text(
                        fields[0],
                        list(e.get("loc", ())),
                        str(e.get("type", "")),
                        e.get("ctx") or {},
                        str(e.get("msg", "")),
                        model,
                    )
                ),
            )
            for e in exc.errors()[:20]  # the first few tell what is wrong
        ]
        return _answer(http_status(Invalid), issues)

    @app.exception_handler(HTTPException)
    async def http_error(request: Request, exc: HTTPException) -> JSONResponse:
        limit = request.scope.get(MAX_BODY_SIZE_SCOPE_KEY)
        too_large = http_status(TooLarge)
        if exc.status_code == too_large and limit is not None:  # a body over its limit
            return _answer(too_large, Refusal(message=body_too_large(limit)))
        return _answer(exc.status_code, Refusal(message=str(exc.detail)), headers=exc.headers)
