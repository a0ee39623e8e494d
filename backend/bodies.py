"""Request bodies: every route's size limit, and the big ones (parameter lists, CSV traces,
NC programs) read while they stream in, decoded strictly, documented in the schema.

Every route has a body limit (FastAPI's `max_body_size`: the default for every router, more
where a route takes uploads), enforced while the body streams in and before it is parsed: a
declared Content-Length over it is refused before a byte is read, an undeclared or false one
after at most the limit was held. The routes open without credentials take a small one.
"""

from __future__ import annotations

import re
import time
from typing import Any, TypeVar

from fastapi import Request, Response
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel, ValidationError
from starlette.middleware.body_limit import MAX_BODY_SIZE_SCOPE_KEY
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from api.commands import PROGRAM_MAX_CHARS
from api.common import ErrorBody, Refusal
from backend.errors import OK, Invalid, TooLarge, body_too_large, http_status

DEFAULT_BODY_BYTES = 64 * 1024  # every route that says nothing else: commands, settings, …
OPEN_BODY_BYTES = 4 * 1024  # the routes open without credentials (logging in)
# a program's characters take up to 4 bytes in UTF-8, and JSON escapes some (newline: 2 bytes)
PROGRAM_BODY_BYTES = 4 * PROGRAM_MAX_CHARS + 1024
LISTS_BODY_BYTES = 8 * 1024 * 1024  # a machine's native parameter lists (a class's too)
LIST_BODY_BYTES = 1_000_000  # one parameter list in the native format
CHANGES_BODY_BYTES = 2 * 1024 * 1024  # up to 5000 parameter changes at once
EXERCISE_BODY_BYTES = 4 * 100_000 + 1024  # an exercise file (TOML)
CSV_BODY_BYTES = 64 * 1024 * 1024  # a trace as CSV


class BodyLimitAnswer:
    """ASGI middleware: Starlette refuses a declared Content-Length over the route's limit
    with a bare text 413 (an undeclared one reaches `errors`); this answers it with the usual
    error body, the limit named."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        replaced = False

        async def answer(message: Message) -> None:
            nonlocal replaced
            if message["type"] == "http.response.start" and _bare_413(message):
                replaced = True
                text = body_too_large(scope.get(MAX_BODY_SIZE_SCOPE_KEY, 0))
                body = ErrorBody(detail=Refusal(message=text)).model_dump_json().encode()
                headers = [(b"content-type", b"application/json")]
                headers.append((b"content-length", str(len(body)).encode()))
                status = http_status(TooLarge)
                await send({"type": "http.response.start", "status": status, "headers": headers})
                await send({"type": "http.response.body", "body": body})
            elif not replaced:  # the bare answer's body goes nowhere
                await send(message)

        await self.app(scope, receive, answer)


def _bare_413(start: Message) -> bool:
    headers = dict(start.get("headers", []))
    plain = headers.get(b"content-type", b"").startswith(b"text/")
    return bool(start["status"] == http_status(TooLarge) and plain)


async def read_text(request: Request, what: str) -> str:
    """The body as UTF-8 text (a byte order mark is dropped), 422 when it is not UTF-8 (its
    size is the route's limit: 413 beyond it)."""
    chunks = [chunk async for chunk in request.stream()]
    try:
        return b"".join(chunks).decode("utf-8-sig")
    except UnicodeDecodeError as e:
        msg = f"{what}: not UTF-8 text (byte {e.start} is {e.object[e.start]:#04x})"
        raise Invalid(msg) from None


M = TypeVar("M", bound=BaseModel)


async def read_model(request: Request, model: type[M], what: str) -> M:
    """The JSON body as `model` (parsed by pydantic straight from the text, cheaper than
    through Python objects): 422 with the usual validation issues when it is no such JSON."""
    raw = await read_text(request, what)
    try:
        return model.model_validate_json(raw)
    except ValidationError as e:
        issues = [{**i, "loc": ("body", *i["loc"])} for i in e.errors(include_url=False)]
        raise RequestValidationError(issues) from None


def json_body(model: type[BaseModel], max_bytes: int) -> dict[str, Any]:
    """`openapi_extra` documenting a required JSON body of `model` read by `read_model`."""
    schema = model.model_json_schema()
    schema["description"] = f"{schema.get('description', '')} (at most {max_bytes} bytes)".strip()
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": schema}}}}


def text_body(media_type: str, max_bytes: int, description: str) -> dict[str, Any]:
    """`openapi_extra` documenting a required text body of this media type."""
    schema = {"type": "string", "maxLength": max_bytes}
    return {
        "requestBody": {
            "required": True,
            "description": description,
            "content": {media_type: {"schema": schema}},
        }
    }


def text_answer(media_type: str, description: str) -> dict[int | str, Any]:
    """`responses=` entry documenting a 200 answer of text in this media type."""
    content = {media_type: {"schema": {"type": "string"}}}
    return {OK: {"content": content, "description": description}}


def dated_download(
    body: str | bytes, media_type: str, machine: str, what: str, ext: str
) -> Response:
    """A file to download named after the machine, what it is and when (UTC):
    `Demo-lathe_history_20261129-081203.csv`."""
    safe = re.sub(r"[^A-Za-z0-9._-]+", "-", machine).strip("-") or "machine"
    name = f"{safe}_{what}_{time.strftime('%Y%m%d-%H%M%S', time.gmtime())}.{ext}"
    disposition = {"Content-Disposition": f'attachment; filename="{name}"'}
    return Response(body, media_type=media_type, headers=disposition)
