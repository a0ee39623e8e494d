"""Fixtures shared by the service and browser tests: each test gets a machine of its own, on
the run's shared service unless its module needs a service of its own."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from contextlib import ExitStack
from typing import TYPE_CHECKING

import pytest

from tests.backend.server import Server

if TYPE_CHECKING:  # ray is imported only by the tests that start a cluster
    from tests.backend.raycluster import LocalCluster

_serial = itertools.count(1)


@pytest.fixture(scope="session")
def shared_srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """The run's one plain service, for every module that has no reason for its own. Its
    demo machine stays paused: the HMI opens it by default, but no test moves it, and in
    real time it would cost a tenth of a core for the whole run."""
    s = Server(tmp_path_factory.mktemp("shared") / "shared.sqlite").start()
    s.pace("demo", mode="pause")
    yield s
    s.close()


@pytest.fixture(scope="module")
def srv(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Server]:
    """The module's service: the shared one, unless the module changes what all machines
    share (users, classes, the trace library, the service itself) and says so with
    `OWN_SERVICE = True`, or needs other arguments (`SERVE_ARGS`). A module may also define
    its own `srv` (settings of its own)."""
    args: tuple[str, ...] | None = getattr(request.module, "SERVE_ARGS", None)
    if args is None and not getattr(request.module, "OWN_SERVICE", False):
        yield request.getfixturevalue("shared_srv")
        return
    s = Server(tmp_path_factory.mktemp("own") / "own.sqlite", *(args or ())).start()
    yield s
    s.close()


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


class _RayCluster:
    """The run's one local Ray cluster: started by the first Ray test, shut down after the
    last (the Ray tests run one after another, see pytest_collection_modifyitems), so its
    dozen processes do not idle through the rest of the suite."""

    def __init__(self) -> None:
        self.stack: ExitStack | None = None
        self.cluster: LocalCluster | None = None

    def start(self) -> LocalCluster:
        if self.cluster is None:
            from tests.backend.raycluster import local_cluster

            self.stack = ExitStack()
            self.cluster = self.stack.enter_context(local_cluster(2))
        return self.cluster

    def stop(self) -> None:
        if self.stack is not None:
            self.stack.close()
        self.stack = self.cluster = None


_RAY = _RayCluster()


def _uses_ray(item: pytest.Item) -> bool:
    callspec = getattr(item, "callspec", None)
    return item.path.name in ("test_cluster.py", "test_cluster_restart.py") or (
        callspec is not None and callspec.params.get("transport") == "ray"
    )


@pytest.hookimpl(tryfirst=True)  # before `-m` selects by the mark
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The Ray tests marked `ray` and run one after the other, where the first of them was
    collected: their one cluster stops after the last."""
    ray = [i for i in items if _uses_ray(i)]
    if ray:
        first = items.index(ray[0])
        rest = [i for i in items if not _uses_ray(i)]
        items[:] = rest[:first] + ray + rest[first:]
    for item in ray:
        item.add_marker(pytest.mark.ray)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item: pytest.Item, nextitem: pytest.Item | None) -> Iterator[None]:
    yield  # the item's own fixtures (a service on the cluster among them) end first
    if _uses_ray(item) and (nextitem is None or not _uses_ray(nextitem)):
        _RAY.stop()


@pytest.fixture(scope="session")
def ray_cluster() -> LocalCluster:
    """The local Ray cluster (head + 2 nodes, ≈10 s to start) the Ray tests share."""
    return _RAY.start()
