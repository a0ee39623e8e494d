"""The README's tour: three screenshots of the HMI at 1280×800. With TOUR=1 they are written to
docs/tour/ (committed, referenced by the README): `TOUR=1 .venv/bin/python -m pytest
tests/e2e/test_tour.py`; otherwise to tests/e2e/screenshots/ like every other screenshot."""

from __future__ import annotations

import os
from pathlib import Path

from playwright.sync_api import Browser, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import SHOTS, open_hmi, panel, poll
from tests.e2e.test_scope import capture_m19

OWN_SERVICE = True  # its capture goes to the trace library the scope tests list

TOUR = Path(__file__).resolve().parents[2] / "docs" / "tour"
MAX_BYTES = 200_000  # small enough to keep in the repository


def tour_shot(page: Page, name: str) -> None:
    folder = TOUR if os.environ.get("TOUR") == "1" else SHOTS
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.png"
    page.mouse.move(0, 0)  # no hover effects in the picture
    page.screenshot(path=str(path))
    assert path.stat().st_size < MAX_BYTES, f"{path} is {path.stat().st_size} bytes"


def test_the_tour(browser: Browser, srv: Server, mid: str) -> None:
    page = open_hmi(browser, srv.base, mid, "tour")
    try:
        # 1. Operate: the spindle turning at S1200, its live plot, the machine view beside it
        spindle = panel(page, "spindle")
        spindle.get_by_test_id("s-input").fill("1200")
        spindle.get_by_test_id("m3").click()
        poll(
            lambda: any(a["name"] == "S1" and a["vel_act"] > 1190 for a in srv.status(mid)["axes"]),
            "S1 at speed",
        )
        page.wait_for_timeout(1500)
        tour_shot(page, "operate")
        spindle.get_by_test_id("m5").click()
        # 2. the scope: a capture triggered by M19, with its marker, cursors and measurements
        capture_m19(page)
        page.get_by_test_id("capture-chart").scroll_into_view_if_needed()
        tour_shot(page, "scope")
        # 3. the Service view: each axis' expected lag and measured gain, with their sources
        page.get_by_test_id("tab-Service").click()
        expect(panel(page, "service")).to_be_visible()
        page.wait_for_timeout(500)
        tour_shot(page, "service")
    finally:
        page.close()
