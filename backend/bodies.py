"""Big bodies (parameter lists, CSV traces, NC programs): read with a size limit while they
stream in, decoded strictly, documented in the schema.

The limit is enforced chunk by chunk, so a too large body is refused with 413 after at most
`max_bytes` were held in memory, whatever its Content-Length claims.
"""

from __future__ import annotations

from typing import Any, TypeVar

from fastapi import Request
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel, ValidationError

from backend.errors import ApiError


async def read_text(request: Request, max_bytes: int, what: str) -> str:
    """The body as UTF-8 text (a byte order mark is dropped); 413 beyond `max_bytes`,
    422 when it is not UTF-8."""
    declared = request.headers.get("content-length", "")
    if declared.isascii() and declared.isdigit() and int(declared) > max_bytes:
        raise _too_large(max_bytes, what)
    chunks: list[bytes] = []
    size = 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > max_bytes:
            raise _too_large(max_bytes, what)
        chunks.append(chunk)
    try:
        return b"".join(chunks).decode("utf-8-sig")
    except UnicodeDecodeError as e:
        msg = f"{what}: not UTF-8 text (byte {e.start} is {e.object[e.start]:#04x})"
        raise ApiError(422, {"message": msg}) from None


M = TypeVar("M", bound=BaseModel)


async def read_model(request: Request, model: type[M], max_bytes: int, what: str) -> M:
    """The JSON body as `model`: 413 beyond `max_bytes` (before it is all in memory), 422
    with the usual validation issues when it is no such JSON."""
    raw = await read_text(request, max_bytes, what)
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


def _too_large(max_bytes: int, what: str) -> ApiError:
    return ApiError(413, {"message": f"{what} larger than {max_bytes} bytes"})


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
    return {200: {"content": content, "description": description}}
