"""Browser tests: one headless Chromium for a run of them (each page its own context; the HMI
pages are kept pages made as good as new for each test); the service is the run's shared one
unless a module asks for its own (tests/conftest.py)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import ExitStack
from pathlib import Path

import pytest
from playwright.sync_api import Browser, Page

from tests.backend.server import Server
from tests.e2e.browser import DIST, KEPT_PAGES, SESSIONS, chromium
from tests.e2e.plant import DRIVE_GAIN, KV_RAW, MULTI_GAIN, set_up


class _Chromium:
    """The worker's browser: started by the first browser test, closed after the last of a
    run of them (`pytest_runtest_teardown`). While a browser is open, Playwright's sync API
    holds an event loop on this thread, and `asyncio.run` in a later test on the same worker
    (a backend test after the browser tests) would be refused."""

    def __init__(self) -> None:
        self.stack: ExitStack | None = None
        self.browser: Browser | None = None

    def start(self) -> Browser:
        if self.browser is None:
            self.stack = ExitStack()
            self.browser = self.stack.enter_context(chromium())
        return self.browser

    def stop(self) -> None:
        KEPT_PAGES.forget()
        if self.stack is not None:
            self.stack.close()
        self.stack = self.browser = None


_CHROMIUM = _Chromium()
E2E = Path(__file__).resolve().parent


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item: pytest.Item, nextitem: pytest.Item | None) -> Iterator[None]:
    KEPT_PAGES.give_back_all()  # before the test's fixtures end (its machine among them)
    yield
    if nextitem is None or E2E not in nextitem.path.parents:
        _CHROMIUM.stop()


@pytest.fixture
def browser() -> Browser:
    if not DIST.is_file():
        pytest.fail("the frontend is not built: run `make test`, which builds it")
    return _CHROMIUM.start()


@pytest.fixture(autouse=True)
def _own_sessions() -> None:
    """No login session taken yet by this test (tests/e2e/browser.py `_Sessions`)."""
    SESSIONS.taken.clear()


@pytest.fixture
def page(browser: Browser, srv: Server, mid: str) -> Page:
    """The HMI at 1920×1080 on the test's own machine, as the test admin: a kept page, made
    as good as new (tests/e2e/browser.py `_KeptPages`)."""
    return KEPT_PAGES.take(browser, srv.base, mid)


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
