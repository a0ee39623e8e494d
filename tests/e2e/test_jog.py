"""Press-and-hold jog in the browser: moves while held, stops on release, on a lost network
(the service's dead-man lease) and when the service goes away (banner, no more jog requests).

This module stops its own service, so it has one to itself.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from playwright.sync_api import Browser, Page, Request, expect

from tests.backend.server import Server
from tests.e2e.browser import number, open_hmi, poll, shot

OWN_SERVICE = True  # stops and restarts the service

HOLD_S = 0.5  # the UI's dead-man lease (frontend/src/state/jog.ts)


@pytest.fixture
def page(browser: Browser, srv: Server, mid: str) -> Iterator[Page]:
    p = open_hmi(browser, srv.base, mid)
    p.get_by_test_id("jog-axis-X").check()
    yield p
    p.close()


def x_state(srv: Server, mid: str) -> str:
    return str(srv.axis("X", mid)["state"])


def test_hold_moves_x_and_release_stops_it(page: Page, srv: Server, mid: str) -> None:
    x0 = number(page, "pos-X")
    key = page.get_by_test_id("jog-plus")
    key.hover()
    page.mouse.down()
    expect(page.get_by_test_id("state-X")).to_have_text("JOG")
    time.sleep(3 * HOLD_S)  # held longer than one lease: the UI keeps renewing it
    assert x_state(srv, mid) == "JOG"
    assert key.get_attribute("aria-pressed") == "true"
    assert page.get_by_test_id("jog-minus").get_attribute("aria-pressed") == "false"
    shot(page, "jog-held-desktop")
    page.mouse.up()
    poll(lambda: x_state(srv, mid) == "STANDSTILL", "X stopped after release")
    x1 = srv.axis("X", mid)["pos_cmd"]
    assert x1 > x0 + 0.1
    time.sleep(2 * HOLD_S)
    assert srv.axis("X", mid)["pos_cmd"] == x1  # nothing moves after the release


def test_pressing_the_other_key_with_the_mouse_jogs_the_other_way(
    page: Page, srv: Server, mid: str
) -> None:
    """The focus moves from + to − as − is pressed: the blur of + must not release −."""
    page.get_by_test_id("jog-plus").hover()
    page.mouse.down()
    poll(lambda: x_state(srv, mid) == "JOG", "jogging +")
    page.mouse.up()
    poll(lambda: x_state(srv, mid) == "STANDSTILL", "stopped")
    page.get_by_test_id("jog-minus").hover()
    page.mouse.down()
    try:
        poll(lambda: x_state(srv, mid) == "JOG", "jogging −")
        time.sleep(3 * HOLD_S)  # longer than a lease: still held, still renewed
        x1 = srv.axis("X", mid)["pos_cmd"]
        time.sleep(HOLD_S)
        assert x_state(srv, mid) == "JOG" and srv.axis("X", mid)["pos_cmd"] < x1
        assert page.get_by_test_id("jog-minus").get_attribute("aria-pressed") == "true"
    finally:
        page.mouse.up()
    poll(lambda: x_state(srv, mid) == "STANDSTILL", "stopped after release")


def test_lost_network_stops_the_jog_by_the_dead_man(page: Page, srv: Server, mid: str) -> None:
    page.get_by_test_id("jog-plus").hover()
    page.mouse.down()
    poll(lambda: x_state(srv, mid) == "JOG", "jogging")
    page.context.set_offline(True)  # renewals stop reaching the service; the key stays down
    try:
        poll(lambda: x_state(srv, mid) == "STANDSTILL", "dead-man stop", timeout_s=5 + HOLD_S)
        # the UI noticed too: banner up, key released, controls locked
        expect(page.get_by_test_id("banner-connection")).to_be_visible()
        assert page.get_by_test_id("jog-plus").get_attribute("aria-pressed") == "false"
    finally:
        page.mouse.up()
        page.context.set_offline(False)
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")


def test_stopping_the_service_shows_the_banner_and_no_jog_continues(
    page: Page, srv: Server, mid: str
) -> None:
    page.get_by_test_id("jog-plus").hover()
    page.mouse.down()
    poll(lambda: x_state(srv, mid) == "JOG", "jogging")
    jog_requests: list[float] = []

    def on_request(r: Request) -> None:
        if r.url.endswith("/commands") and r.method == "POST" and '"jog"' in (r.post_data or ""):
            jog_requests.append(time.monotonic())

    page.on("request", on_request)
    srv.stop()
    banner = page.get_by_test_id("banner-connection")
    expect(banner).to_be_visible()
    shot(page, "connection-lost-desktop")
    assert page.get_by_test_id("jog-plus").get_attribute("aria-pressed") == "false"
    expect(page.get_by_test_id("jog-plus")).to_be_disabled()
    seen = time.monotonic()
    time.sleep(1.0)
    # after the banner, at most the one release request; no renewals
    late = [t for t in jog_requests if t > seen]
    assert late == []
    page.mouse.up()
    srv.start()  # the same port and store: the page reconnects by itself
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    expect(banner).to_be_hidden()
    time.sleep(2 * HOLD_S)
    assert x_state(srv, mid) == "STANDSTILL"
