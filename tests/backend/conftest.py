"""Fixtures shared by the service tests (each module starts its own `srv`)."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from tests.backend.server import Server


@pytest.fixture
def lathe(srv: Server) -> Iterator[str]:
    """A demo lathe of its own on the module's service, powered, removed afterwards."""
    name = f"lathe{time.monotonic_ns()}"
    r = srv.http.post("/api/machines", json={"id": name, "demo": True})
    assert r.status_code == 201, r.text
    srv.wait_powered(name)
    yield name
    srv.http.delete(f"/api/machines/{name}")
