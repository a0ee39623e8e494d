"""Browser tests: one real service and one headless Chromium per test module."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from playwright.sync_api import Browser, Page

from tests.backend.server import Server
from tests.e2e.browser import DIST, chromium, open_hmi


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    if not DIST.is_file():
        pytest.fail("the frontend is not built: run `make test`, which builds it")
    s = Server(tmp_path_factory.mktemp("e2e") / "e2e.sqlite").start()
    yield s
    s.close()


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    with chromium() as b:
        yield b


@pytest.fixture
def page(browser: Browser, srv: Server, mid: str) -> Iterator[Page]:
    """The HMI at 1920×1080 on the test's own machine."""
    p = open_hmi(browser, srv.base, mid)
    yield p
    p.close()
