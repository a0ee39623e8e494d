"""Issue 20, a new user's trial (commissioning engineer on the demo lathe).

A value that waits for a restart, on trial, through the restart: the demo's
lr_hw[0].vz_stellgr (sign of the drive's command value) takes effect at restart only. Applied,
it waits; after a restart (by this tab or by anyone) it is in force everywhere without a
reload; Revert then writes the old value back, which waits for a restart again. And a machine
that is no class seat is not asked for an exercise."""

from __future__ import annotations

import re

from playwright.sync_api import Browser, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import SIZES, open_hmi, panel, shot, signed_in_page

SIGN = "lr_hw[0].vz_stellgr"  # effect: restart [004]


def apply_sign(page: Page, value: str) -> None:
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("vz_stellgr")
    params.get_by_test_id(f"param-input-{SIGN}").fill(value)
    params.get_by_test_id("param-apply").click()


def test_a_restart_from_the_trial_bar_puts_the_value_in_force_and_revert_waits_again(
    browser: Browser, srv: Server, mid: str
) -> None:
    page = open_hmi(browser, srv.base, mid)
    apply_sign(page, "1")
    bar = page.get_by_test_id("trial-bar")
    params = panel(page, "parameters")
    expect(bar.get_by_test_id("param-trial")).to_contain_text(f"{SIGN} default → 1 (at restart)")
    expect(params.get_by_test_id(f"param-pending-{SIGN}")).to_have_text("pending 1 at restart")
    # a reload keeps the open trial (the session's, like the rest of the workspace)
    page.reload()
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    expect(bar.get_by_test_id("param-trial")).to_contain_text(f"{SIGN} default → 1 (at restart)")
    # a reload is another tab to the control lock: the restart says why until taken over
    restart = bar.get_by_test_id("machine-restart")
    expect(restart).to_be_disabled()
    expect(restart).to_have_attribute("title", re.compile("you have control in another tab"))
    page.get_by_test_id("control-strip").get_by_test_id("control-take-here").click()
    # the bar offers the restart, asking first
    bar.get_by_test_id("machine-restart").click()
    expect(bar).to_contain_text("Power off and on")
    shot(page, "trial-restart-confirm-desktop")
    bar.get_by_test_id("restart-confirm").click()
    expect(bar.get_by_test_id("trial-message")).to_contain_text(f"Restarted {mid} at")
    expect(bar.get_by_test_id("param-trial")).to_contain_text(
        f"{SIGN} default → 1 (in force since the restart)"
    )
    page.get_by_test_id("tab-Parameters").click()
    expect(params.get_by_test_id(f"param-pending-{SIGN}")).to_have_count(0)
    expect(params.get_by_test_id(f"param-input-{SIGN}")).to_have_value("1")
    page.get_by_test_id("open-machines").click()
    dialog = panel(page, "machines")
    expect(dialog.get_by_test_id("restart-pending-count")).to_have_text(
        "no value waits for a restart"
    )
    dialog.get_by_test_id("machines-close").click()
    # the restart took our value in: that is no change by someone else, Revert writes 0 back
    bar.get_by_test_id("param-revert").click()
    message = bar.get_by_test_id("trial-message")
    expect(message).to_contain_text("Reverted 1 value(s).")
    expect(message).to_contain_text(f"Back in force at the next restart: {SIGN} 0")
    expect(params.get_by_test_id(f"param-pending-{SIGN}")).to_have_text("pending 0 at restart")
    expect(bar.get_by_test_id("machine-restart")).to_be_visible()  # offered again
    shot(page, "trial-reverted-waits-for-restart-desktop")
    page.set_viewport_size({"width": SIZES["tablet"][0], "height": SIZES["tablet"][1]})
    shot(page, "trial-reverted-waits-for-restart-tablet")
    page.close()


def test_a_restart_by_someone_else_shows_without_a_reload(
    page: Page, srv: Server, mid: str
) -> None:
    apply_sign(page, "1")
    bar = page.get_by_test_id("trial-bar")
    params = panel(page, "parameters")
    expect(params.get_by_test_id(f"param-pending-{SIGN}")).to_have_text("pending 1 at restart")
    shot(page, "trial-waits-for-restart-desktop")
    # another client takes the machine and restarts it: nothing tells this tab but its status
    assert srv.http.post(f"/api/machines/{mid}/control", json={"action": "take"}).is_success
    assert srv.http.post(f"/api/machines/{mid}/restart").status_code == 200
    expect(params.get_by_test_id(f"param-pending-{SIGN}")).to_have_count(0)
    expect(params.get_by_test_id(f"param-input-{SIGN}")).to_have_value("1")
    expect(bar.get_by_test_id("param-trial")).to_contain_text("(in force since the restart)")
    expect(bar.get_by_test_id("machine-restart")).to_have_count(0)


def test_reverting_before_the_restart_leaves_nothing_waiting(page: Page) -> None:
    apply_sign(page, "1")
    bar = page.get_by_test_id("trial-bar")
    params = panel(page, "parameters")
    expect(params.get_by_test_id(f"param-pending-{SIGN}")).to_have_text("pending 1 at restart")
    bar.get_by_test_id("param-revert").click()
    expect(bar.get_by_test_id("trial-message")).to_have_text("Reverted 1 value(s).")
    expect(params.get_by_test_id(f"param-pending-{SIGN}")).to_have_count(0)
    expect(bar.get_by_test_id("machine-restart")).to_have_count(0)


def test_a_machine_that_is_no_class_seat_is_not_asked_for_its_exercise(
    browser: Browser, srv: Server, mid: str
) -> None:
    page = signed_in_page(browser, srv.base)
    asked: list[str] = []
    page.on("request", lambda r: asked.append(r.url) if "/exercise" in r.url else None)
    page.goto(f"{srv.base}/#{mid}")
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    expect(page.get_by_test_id("tab-Operate")).to_be_visible()
    expect(page.get_by_test_id("tab-Exercise")).to_have_count(0)
    assert asked == []  # before: GET …/exercise, answered 404, logged in the console
    page.close()


def test_another_machine_shows_its_own_capture_not_the_one_before(
    browser: Browser, srv: Server, mid: str
) -> None:
    other = f"{mid}-b"
    r = srv.http.post("/api/machines", json={"id": other, "name": other, "demo": True})
    assert r.status_code == 201, r.text
    page = open_hmi(browser, srv.base, mid)
    try:
        page.get_by_test_id("tab-Scope").click()
        scope = panel(page, "scope-setup")
        scope.get_by_test_id("scope-mode").select_option("single")
        scope.get_by_test_id("scope-arm").click()
        scope.get_by_test_id("scope-force").click()
        capture = panel(page, "capture")
        expect(capture.get_by_test_id("capture-view")).to_be_visible(timeout=15_000)
        ours = capture.get_by_test_id("capture-view").get_attribute("data-trace")
        page.locator(".machine-select select").select_option(other)
        expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
        page.get_by_test_id("tab-Scope").click()
        expect(capture.get_by_test_id("capture-view")).to_have_count(0)
        shot(page, "scope-other-machine-desktop")
        page.locator(".machine-select select").select_option(mid)  # back: its own again
        expect(capture.get_by_test_id("capture-view")).to_have_attribute("data-trace", ours or "")
    finally:
        page.close()
        srv.http.delete(f"/api/machines/{other}")
