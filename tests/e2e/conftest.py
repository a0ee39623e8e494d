"""Browser tests: one real service and one headless Chromium (each page its own context) for
the whole run; each test works on a machine of its own.

A module whose tests change what all machines share (users, classes, the trace library, the
service itself) gets a service of its own: `OWN_SERVICE = True`, or `SERVE_ARGS` for one started
with other arguments."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from playwright.sync_api import Browser, Page

from tests.backend.server import Server
from tests.e2e.browser import DIST, chromium, open_hmi
from tests.e2e.plant import DRIVE_GAIN, KV_RAW, MULTI_GAIN, set_up


def _service(tmp_path_factory: pytest.TempPathFactory, *args: str) -> Server:
    if not DIST.is_file():
        pytest.fail("the frontend is not built: run `make test`, which builds it")
    return Server(tmp_path_factory.mktemp("e2e") / "e2e.sqlite", *args).start()


@pytest.fixture(scope="session")
def shared_srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = _service(tmp_path_factory)
    yield s
    s.close()


@pytest.fixture(scope="module")
def srv(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Server]:
    args: tuple[str, ...] | None = getattr(request.module, "SERVE_ARGS", None)
    if args is None and not getattr(request.module, "OWN_SERVICE", False):
        yield request.getfixturevalue("shared_srv")
        return
    s = _service(tmp_path_factory, *(args or ()))
    yield s
    s.close()


@pytest.fixture(scope="session")
def browser() -> Iterator[Browser]:
    with chromium() as b:
        yield b


@pytest.fixture
def page(browser: Browser, srv: Server, mid: str) -> Iterator[Page]:
    """The HMI at 1920×1080 on the test's own machine."""
    p = open_hmi(browser, srv.base, mid)
    yield p
    p.close()


@pytest.fixture
def wrong_drive(srv: Server, mid: str) -> str:
    """The test's machine with the X drive's gain 2.2857 times what the NC assumes (the demo's
    X list: multi_gain 10000, kv 20/s) [004 §3.6.2]."""
    set_up(srv, mid, "X", {"sim.drive_gain": DRIVE_GAIN})
    rows = srv.http.get(f"/api/machines/{mid}/parameters?scope=axis&target=X").json()
    x = {p["name"]: p["value"] for p in rows}
    assert x["getriebe[0].multi_gain_z"] / x["getriebe[0].multi_gain_n"] == MULTI_GAIN
    assert x["getriebe[0].kv"] == KV_RAW
    return mid
