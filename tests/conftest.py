"""Fixtures shared by the service and browser tests: each test gets a machine of its own."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

from tests.backend.server import Server

if TYPE_CHECKING:  # ray is imported only by the tests that start a cluster
    from tests.backend.raycluster import LocalCluster

_serial = itertools.count(1)


@pytest.fixture
def mid(srv: Server) -> Iterator[str]:
    """A fresh demo lathe on the module's server (`srv`), powered on and running in real
    time; deleted afterwards.

    No test sees what another wrote (parameters, pacing, errors, pending M functions)."""
    name = f"t{next(_serial)}"
    r = srv.http.post("/api/machines", json={"id": name, "name": name, "demo": True})
    assert r.status_code == 201, r.text
    srv.wait_powered(name)
    yield name
    srv.http.delete(f"/api/machines/{name}")


@pytest.fixture(scope="session")
def ray_cluster() -> Iterator[LocalCluster]:
    """One local Ray cluster (head + 2 nodes) for every Ray test of the run (≈10 s to start)."""
    from tests.backend.raycluster import local_cluster

    with local_cluster(2) as cluster:
        yield cluster
