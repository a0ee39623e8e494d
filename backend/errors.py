"""Errors the service turns into HTTP answers (the only place that knows status codes).

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

WHY: dict[int, str] = {
    400: "malformed request",
    401: "not logged in: no session, or an unknown or expired token",
    403: "not allowed for this role, or a missing CSRF token",
    404: "no such machine, trace or recording",
    409: "conflicts with the current state",
    413: "body too large",
    422: "bad input: which value, its range or why (nothing was applied)",
    502: "the Rerun viewer did not answer",
    503: "the Rerun viewer did not start",
    507: "a disk quota is used up (which, how much, and what to delete)",
}


class ApiError(Exception):
    """A refused request: HTTP status and a `Refusal`-shaped `detail`."""

    def __init__(self, status: int, detail: Any) -> None:
        super().__init__(str(detail))
        self.status = status
        self.detail = detail


def refusal_text(e: ApiError) -> str:
    """The refusal's message (for the audit trail)."""
    message = e.detail.get("message") if isinstance(e.detail, dict) else None
    return str(message if message is not None else e.detail)


def body_too_large(limit: int) -> str:
    """Why a request body was refused (413)."""
    return f"request body larger than this route's limit of {limit} bytes"


def not_found(what: str) -> ApiError:
    return ApiError(404, {"message": f"{what} not found"})


WORKER_GONE = {503: "the machine's worker stopped: the machine is being rebuilt, try again"}


def responses(*codes: int, why: Mapping[int, str] | None = None) -> dict[int | str, Any]:
    """OpenAPI `responses=` for error answers: each code with the shared body and a reason
    (`why` overrides or adds reasons, e.g. `{409: "the NC refused the command"}`)."""
    reasons = {c: WHY[c] for c in codes} | dict(why or {})
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


def install(app: FastAPI) -> None:
    """Register the handlers that give every error answer the shared body."""

    @app.exception_handler(ApiError)
    async def api_error(_request: Request, exc: ApiError) -> JSONResponse:
        return _answer(exc.status, Refusal.model_validate(exc.detail))

    fields: list[FieldTexts] = []  # from the schema on first use (routes are all added then)

    @app.exception_handler(RequestValidationError)
    async def invalid(_request: Request, exc: RequestValidationError) -> JSONResponse:
        if not fields:
            fields.append(FieldTexts(app.openapi()))
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
                    )
                ),
            )
            for e in exc.errors()[:20]  # the first few tell what is wrong
        ]
        return _answer(422, issues)

    @app.exception_handler(HTTPException)
    async def http_error(request: Request, exc: HTTPException) -> JSONResponse:
        limit = request.scope.get(MAX_BODY_SIZE_SCOPE_KEY)
        if exc.status_code == 413 and limit is not None:  # a body over its route's limit
            return _answer(413, Refusal(message=body_too_large(limit)))
        return _answer(exc.status_code, Refusal(message=str(exc.detail)), headers=exc.headers)
