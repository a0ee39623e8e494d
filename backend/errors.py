"""Errors the service turns into HTTP answers (the only place that knows status codes)."""

from __future__ import annotations

from typing import Any


class ApiError(Exception):
    """A refused request: HTTP status and a JSON-able `detail`."""

    def __init__(self, status: int, detail: Any) -> None:
        super().__init__(str(detail))
        self.status = status
        self.detail = detail


def not_found(what: str) -> ApiError:
    return ApiError(404, {"message": f"{what} not found"})
