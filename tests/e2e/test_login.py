"""Logging in and out in a real browser: nothing of the HMI without a session, a wrong
password refused on the form, the user and role in the top bar, logout back to the form."""

from __future__ import annotations

from playwright.sync_api import Browser, expect

from tests.backend.server import PASSWORD, USER, Server
from tests.e2e.browser import SIZES, panel, shot


def test_log_in_and_out(browser: Browser, srv: Server, mid: str) -> None:
    w, h = SIZES["desktop"]
    page = browser.new_page(viewport={"width": w, "height": h})
    page.set_default_timeout(15_000)
    sockets: list[str] = []
    page.on("websocket", lambda ws: sockets.append(ws.url))
    page.goto(f"{srv.base}/#{mid}")
    form = panel(page, "login")
    expect(form.get_by_test_id("login-form")).to_be_visible()
    expect(page.get_by_test_id("lamp-connection")).to_have_count(0)  # no HMI without a session
    shot(page, "login-desktop")
    form.get_by_test_id("login-name").fill(USER)
    form.get_by_test_id("login-password").fill("not the password")
    form.get_by_test_id("login-password").press("Enter")
    expect(form.get_by_test_id("login-error")).to_contain_text("wrong name or password")
    assert sockets == []  # nothing was watched meanwhile
    form.get_by_test_id("login-password").fill(PASSWORD)
    form.get_by_test_id("login-submit").click()
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    expect(page.get_by_test_id("user-name")).to_have_text(USER)
    expect(page.get_by_test_id("user-role")).to_contain_text("admin")
    page.get_by_test_id("logout").click()
    expect(panel(page, "login").get_by_test_id("login-form")).to_be_visible()
    assert page.request.get(f"{srv.base}/api/auth/me").status == 401  # the session ended
    page.set_viewport_size({"width": SIZES["tablet"][0], "height": SIZES["tablet"][1]})
    shot(page, "login-tablet")
    page.close()
