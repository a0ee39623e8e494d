"""Issue 20: every workspace at 1920×1080 and 1024×768 (screenshots in tests/e2e/screenshots/,
looked at by a person), and the layout facts a screenshot shows: on a small screen the top bar
is one line and the machine view, condensed, stays on screen while the workspace scrolls;
nothing is wider than the window; numbers that grow do not move what stands beside them."""

from __future__ import annotations

import pytest
from playwright.sync_api import Browser, FloatRect, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import SIZES, WORKSPACES, open_hmi, panel, poll, shot


def slug(name: str) -> str:
    return name.lower().replace(" / ", "-").replace(" ", "-")


def box(page: Page, selector: str) -> FloatRect:
    b = page.locator(selector).first.bounding_box()
    assert b is not None, selector
    return b


@pytest.mark.parametrize("size", ["desktop", "tablet"])
def test_every_workspace_fits_its_screen(
    browser: Browser, srv: Server, mid: str, size: str
) -> None:
    w, h = SIZES[size]
    page = open_hmi(browser, srv.base, mid, size)
    try:
        for name in WORKSPACES:
            page.get_by_test_id(f"tab-{name}").click()
            expect(page.get_by_test_id(f"tab-{name}")).to_have_attribute("aria-selected", "true")
            page.wait_for_timeout(300)
            shot(page, f"screen-{size}-{slug(name)}")
            overflow = page.evaluate(
                "() => document.documentElement.scrollWidth - window.innerWidth"
            )
            assert overflow <= 0, (
                f"{name} at {size}: the page is {overflow} px wider than the window"
            )
            # the emergency stop is fully on screen whatever the workspace
            e = box(page, "[data-testid=estop]")
            assert (
                e["x"] >= 0
                and e["y"] >= 0
                and e["x"] + e["width"] <= w
                and e["y"] + e["height"] <= h
            )
        if size == "tablet":
            # the top bar is one line: no taller than the emergency stop and its margins
            assert box(page, "header.topbar")["height"] <= 48
            # the workspace gets most of the screen: its tabs start in the upper third
            tabs = box(page, "[role=tablist]")
            assert tabs["y"] < h / 3, f"the tabs start at {tabs['y']} px of {h}"
            # the parameter table fits its panel: the last column is on screen
            page.get_by_test_id("tab-Parameters").click()
            last = panel(page, "parameters").locator("table.params thead th").last
            lb = last.bounding_box()
            assert lb is not None and lb["x"] + lb["width"] <= w
            # scrolled down the Operate workspace, the machine view stays under the head
            page.get_by_test_id("tab-Operate").click()
            panel(page, "plot").scroll_into_view_if_needed()
            page.mouse.move(w / 2, h - 100)
            page.mouse.wheel(0, 3000)
            page.wait_for_timeout(300)
            assert page.evaluate("window.scrollY") > 200
            head = box(page, ".head")
            machine = box(page, "[data-testid=panel-machine]")
            assert head["y"] + head["height"] - 0.5 <= machine["y"] < head["height"] + 20
            expect(page.get_by_test_id("pos-X")).to_be_in_viewport()
            shot(page, f"screen-{size}-operate-scrolled")
    finally:
        page.close()


def s1_speed(srv: Server, mid: str) -> float:
    (s1,) = [a for a in srv.status(mid)["axes"] if a["name"] == "S1"]
    return abs(float(s1["vel_act"]))


@pytest.mark.parametrize("size", ["desktop", "tablet"])
def test_growing_numbers_do_not_move_their_neighbours(
    browser: Browser, srv: Server, mid: str, size: str
) -> None:
    """The spindle from 0 to 1000 rpm (n act "0.0" → "1000.0") and simulated time past 10 s
    ("9.99 s" → "10.00 s"): the columns and labels after them stay where they were."""
    page = open_hmi(browser, srv.base, mid, size)
    try:
        spindle = panel(page, "spindle")

        def places() -> list[float]:
            return [
                box(page, "[data-testid=gear-S1]")[
                    "x"
                ],  # after v cmd and v act in the machine view
                box(page, "[data-testid=health] .h-pace")["x"],  # after the simulated time
                spindle.locator(".readouts > span").nth(2).bounding_box()["x"],  # type: ignore[index]
                spindle.locator(".readouts > span").nth(3).bounding_box()["x"],  # type: ignore[index]
            ]

        poll(lambda: srv.status(mid)["simulation"]["t_s"] > 0.5, "the machine runs")
        assert srv.status(mid)["simulation"]["t_s"] < 9.0, "too late to see 10 s come"
        before = places()
        text_before = spindle.locator(".readouts").inner_text()
        spindle.get_by_test_id("s-input").fill("1000")
        spindle.get_by_test_id("m3").click()
        poll(lambda: srv.status(mid)["simulation"]["t_s"] > 10.5, "simulated time past 10 s")
        poll(lambda: s1_speed(srv, mid) > 990, "the spindle at speed")
        page.wait_for_timeout(300)
        after = places()
        assert after == before, (text_before, spindle.locator(".readouts").inner_text())
    finally:
        page.close()
