"""Headless Debian Chromium through Playwright, and the screenshots the browser tests keep."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING, cast

from playwright.sync_api import (
    Browser,
    Cookie,
    Locator,
    Page,
    Request,
    expect,
    sync_playwright,
)
from playwright.sync_api import Error as PlaywrightError

from tests.backend.server import PASSWORD, USER

if TYPE_CHECKING:  # what add_cookies takes: a Cookie's fields (Playwright names it privately)
    from playwright._impl._api_structures import SetCookieParam

CHROMIUM = "/usr/bin/chromium"  # Debian's package; Playwright never downloads a browser here
ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
SIZES = {"desktop": (1920, 1080), "tablet": (1024, 768), "tour": (1280, 800)}
# the HMI's workspace tabs (App.tsx TABS; "Exercise" only on a class seat)
WORKSPACES = [
    "Operate",
    "Program",
    "Plots",
    "Scope",
    "Parameters",
    "Commissioning",
    "Drive tuning",
    "Service",
    "HLI / PLC",
    "History",
    "Fleet",
]
SHOTS = Path(__file__).resolve().parent / "screenshots"
# The tests' pages redraw their live plots 10 times a second (the HMI's "Refresh" choice, kept in
# the browser), not the default 50: a test watches values, not motion, and 50 redraws a second
# of a full-HD page would cost Chromium a fifth of a core per page. A test may choose another;
# bench/ui.py measures the default.
TEST_PLOT_RATE = 10


def _plot_rate(per_s: int) -> str:
    """A page script: the Refresh choice `per_s` unless the page's user chose one."""
    return f"""if (localStorage.getItem("inbetrieb.plotRate") === null)
  localStorage.setItem("inbetrieb.plotRate", "{per_s}");"""


DIST = Path(__file__).resolve().parents[2] / "frontend" / "dist" / "index.html"


@contextmanager
def chromium() -> Iterator[Browser]:
    """A headless browser (for the whole run in the browser tests)."""
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS, headless=True)
        try:
            yield browser
        finally:
            browser.close()


class _Sessions:
    """Login sessions kept for the next tests: a password login costs the service an argon2
    hash, a third of opening a page. A test's first page of a user takes that user's kept
    session (when it still works: a test may have logged it out); any further page of the
    same user in the same test logs in anew, so a test's pages never share a session unless
    it says so (one context)."""

    def __init__(self) -> None:
        self.kept: dict[tuple[str, str, str], list[Cookie]] = {}
        self.taken: set[tuple[str, str, str]] = set()  # by the running test

    def sign_in(self, page: Page, base: str, user: str, password: str) -> None:
        key = (base, user, password)
        cookies = self.kept.get(key) if key not in self.taken else None
        self.taken.add(key)
        if cookies:
            page.context.add_cookies(cast("list[SetCookieParam]", cookies))
            if page.request.get(f"{base}/api/auth/me").ok:
                return
            page.context.clear_cookies()
        r = page.request.post(f"{base}/api/auth/login", data={"name": user, "password": password})
        assert r.ok, r.text()
        if cookies is not None or key not in self.kept:
            self.kept[key] = page.context.cookies(base)


SESSIONS = _Sessions()  # tests/e2e/conftest.py starts each test with none taken


def signed_in_page(
    browser: Browser,
    base: str,
    size: str = "desktop",
    user: str = USER,
    password: str = PASSWORD,
    plot_rate: int = TEST_PLOT_RATE,
) -> Page:
    """A fresh page (its own browser context) logged in as `user` (the test admin unless
    told): the session cookie is set through the context's request API, as the login form
    would set it, or is a session of the user kept from an earlier test (`_Sessions`). Its
    live plots redraw `plot_rate` times a second."""
    w, h = SIZES[size]
    page = browser.new_page(viewport={"width": w, "height": h})
    page.add_init_script(_plot_rate(plot_rate))
    page.set_default_timeout(15_000)
    SESSIONS.sign_in(page, base, user, password)
    return page


def open_hmi(
    browser: Browser,
    base: str,
    machine: str,
    size: str = "desktop",
    user: str = USER,
    password: str = PASSWORD,
    plot_rate: int = TEST_PLOT_RATE,
) -> Page:
    """A page on the HMI showing `machine` (the test's own), connected to the service, logged
    in as `user` (the test admin unless told), its live plots at `plot_rate` per s: one of the
    worker's kept pages made as good as new (`KEPT_PAGES`), or a fresh one at another rate."""
    if plot_rate == TEST_PLOT_RATE:
        return KEPT_PAGES.take(browser, base, machine, size, user, password)
    page = signed_in_page(browser, base, size, user, password, plot_rate)
    _show(page, base, machine)
    return page


def _show(page: Page, base: str, machine: str) -> None:
    """The HMI on `machine`, connected to the service."""
    page.goto(f"{base}/#{machine}")
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")


class _KeptPages:
    """The HMI pages of a test (the `page` fixture's and `open_hmi`'s) are pages kept for the
    worker's run: a fresh context, page and HMI load cost Chromium about a core-second, taking
    a kept page back a quarter of that. Taken, a page is made as good as new: its other pages
    (pop-ups) closed, the network, viewport, timeout and media as at the start, no cookies, the
    service's storage (local and session) empty; then it signs in as the test's user
    (`_Sessions`) and opens the test's machine. After the test (tests/e2e/conftest.py, before
    its fixtures end), or when the test closes it, a page is given back: the listeners and
    routes the test added (`on`, `once`, `route`) removed, it leaves the HMI (about:blank), so
    nothing runs between tests and the HMI's socket closes before the test's machine goes."""

    def __init__(self) -> None:
        self.idle: list[Page] = []
        self.taken: list[Page] = []
        self.added: dict[Page, list[tuple[str, Callable[..., object]]]] = {}

    def take(
        self,
        browser: Browser,
        base: str,
        machine: str,
        size: str = "desktop",
        user: str = USER,
        password: str = PASSWORD,
    ) -> Page:
        page: Page | None = None
        while page is None and self.idle:
            page = self.idle.pop()
            try:
                self._renew(page, base, size, user, password)
            except PlaywrightError:  # crashed: a fresh one
                self._drop(page)
                page = None
        if page is None:
            page = signed_in_page(browser, base, size, user, password)
            self._track(page)
        self.taken.append(page)
        _show(page, base, machine)
        return page

    def give_back_all(self) -> None:
        """The test is over: every page it took comes back."""
        for page in list(self.taken):
            self.give_back(page)

    def forget(self) -> None:
        """The browser is closing: the next test starts with fresh pages."""
        self.idle.clear()
        self.taken.clear()
        self.added.clear()

    def give_back(self, page: Page) -> None:
        if page not in self.taken:
            return  # given back already (a test's fixture closing it after the test)
        self.taken.remove(page)
        for event, f in self.added.get(page, []):
            page.remove_listener(event, f)  # (a `once` that fired is gone already: no-op)
        self.added[page] = []
        try:
            page.unroute_all(behavior="ignoreErrors")
            page.context.unroute_all(behavior="ignoreErrors")
            page.goto("about:blank")
        except PlaywrightError:  # its context closed by the test, or crashed
            self._drop(page)
            return
        self.idle.append(page)

    def _drop(self, page: Page) -> None:
        self.added.pop(page, None)
        with suppress(PlaywrightError):
            page.context.close()

    def _renew(self, page: Page, base: str, size: str, user: str, password: str) -> None:
        for other in page.context.pages:
            if other != page:
                other.close()
        page.context.set_offline(False)
        w, h = SIZES[size]
        page.set_viewport_size({"width": w, "height": h})
        page.set_default_timeout(15_000)
        page.emulate_media(media="screen")
        page.context.clear_cookies()
        page.goto(f"{base}/api/health")  # the service's origin, without the HMI
        page.evaluate("() => { localStorage.clear(); sessionStorage.clear(); }")
        SESSIONS.sign_in(page, base, user, password)

    def _track(self, page: Page) -> None:
        """Keep what listeners a test adds (`on`, `once`), to remove them after it; a test's
        `close` gives the page back (it leaves the HMI, as a closed tab does)."""
        self.added[page] = []
        for name in ("on", "once"):
            add = getattr(page, name)

            def add_and_keep(
                event: str, f: Callable[..., object], add: Callable[..., None] = add
            ) -> None:
                self.added[page].append((event, f))
                add(event, f)

            setattr(page, name, add_and_keep)

        def close_as_given_back(**_: object) -> None:
            self.give_back(page)

        page.close = close_as_given_back  # type: ignore[method-assign]


KEPT_PAGES = _KeptPages()


def shot(page: Page, name: str) -> Path:
    SHOTS.mkdir(exist_ok=True)
    path = SHOTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def number(page: Page, test_id: str) -> float:
    """A numeric readout as shown (the HMI writes − for minus)."""
    text = page.get_by_test_id(test_id).inner_text().replace("−", "-").strip()
    return float(text) if text not in ("", "—") else float("nan")


def poll(fn: Callable[[], bool], what: str, timeout_s: float = 15.0) -> None:
    """Wait for a condition of the live UI (a machine running in real time)."""
    deadline = time.monotonic() + timeout_s
    while not fn():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


def panel(page: Page, name: str) -> Locator:
    """A panel of the HMI by name: the scope every e2e locator starts from."""
    return page.get_by_test_id(f"panel-{name}")


def commands_sent(page: Page) -> list[str]:
    """The bodies of the commands the page posts from now on."""
    sent: list[str] = []

    def on_request(r: Request) -> None:
        if r.url.endswith("/commands") and r.method == "POST":
            sent.append(r.post_data or "")

    page.on("request", on_request)
    return sent
