"""Remote diagnostics in the browser: an operator causes two job errors, the service restarts,
and an observer logged in from afar still finds both in the machine's history, with their
wall clock, the stop, the start and the power-on marked and announced; the flight recorder's
trace of the first error opens from its entry in the scope (by a link that names it) and in
Rerun."""

from __future__ import annotations

import re
import time
from typing import Any

from playwright.sync_api import Browser, expect

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD, Server, add_users, bearer
from tests.e2e.browser import open_hmi, panel, shot

OWN_SERVICE = True  # it restarts the service
ANA, OLE = "ana", "ole"  # an operator on site, an observer from afar


def _history(srv: Server, mid: str, **params: Any) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = srv.http.get(f"/api/machines/{mid}/history", params=params).json()[
        "rows"
    ]
    return rows


def _until_traced(srv: Server, mid: str, codes: set[int]) -> list[dict[str, Any]]:
    """The job errors of these codes once each has its flight-recorder trace (a safety net,
    no measure)."""
    deadline = time.monotonic() + 40
    while True:
        rows = [r for r in _history(srv, mid, kind=["job_error"]) if r["code"] in codes]
        if {r["code"] for r in rows if r["trace"]} == codes:
            return rows
        assert time.monotonic() < deadline, rows
        time.sleep(0.1)


def test_an_observer_finds_the_errors_of_before_a_restart_and_their_traces(
    browser: Browser, srv: Server, mid: str
) -> None:
    tokens = add_users(srv.db, {ANA: Role.OPERATOR, OLE: Role.OBSERVER})
    ana = bearer(tokens[ANA])
    srv.pace(mid, mode="fast")  # 9 s of the lathe's life for the recorder's 8 s before
    while srv.status(mid)["simulation"]["cycle"] < 9000:
        time.sleep(0.05)
    srv.pace(mid, mode="pause")  # both blocks queue behind each other
    for block in ("M3 S1500", "M3 S20000"):  # the second is beyond M45's 7000 rpm: 90017
        r = srv.http.post(
            f"/api/machines/{mid}/commands", json={"type": "mdi", "block": block}, headers=ana
        )
        assert r.status_code == 200, r.text
    srv.pace(mid, mode="run")
    _until_traced(srv, mid, {90017})
    assert srv.http.post(f"/api/machines/{mid}/emergency-stop", headers=ana).status_code == 200
    before = {r["code"]: r for r in _until_traced(srv, mid, {90017, 90005})}

    srv.stop()
    srv.start()

    o = open_hmi(browser, srv.base, f"{mid}/history", user=OLE, password=OTHERS_PASSWORD)
    try:
        restarted = o.get_by_test_id("banner-notice").filter(has_text="service restarted")
        expect(restarted).to_contain_text("powered on again")
        history = panel(o, "history")
        rows = history.get_by_test_id("history-row")
        for code, entry in before.items():
            row = history.locator(f'tr[data-id="{entry["id"]}"]')
            expect(row).to_contain_text(str(code))
            wall = time.strftime("%H:%M:%S", time.localtime(entry["time_unix"]))
            expect(row).to_contain_text(re.sub(r"^0", "", wall))  # the wall clock it happened
        cause = rows.filter(has_text="90017").get_by_test_id("history-cause")
        expect(cause).to_have_text("raised by MDI block 'M3 S20000' sent by ana")
        for mark in ("service stopping", "powered on: the service started"):
            expect(rows.filter(has_text=mark).first).to_be_visible()
        shot(o, "history-after-restart-desktop")
        o.set_viewport_size({"width": 1024, "height": 768})
        shot(o, "history-after-restart-tablet")
        o.set_viewport_size({"width": 1920, "height": 1080})

        first = rows.filter(has_text="spindle speed out of reach")
        expect(first.get_by_test_id("history-trace-rerun")).to_have_attribute(
            "href", f"/api/traces/{before[90017]['trace']}/viewer"
        )
        first.get_by_test_id("history-trace-open").click()
        expect(o.get_by_test_id("tab-Scope")).to_have_attribute("aria-selected", "true")
        assert o.evaluate("location.hash") == f"#{mid}/scope/{before[90017]['trace']}"
        view = o.get_by_test_id("capture-view")
        expect(view).to_have_attribute("data-trace", before[90017]["trace"])
        expect(view.get_by_test_id("capture-trigger")).to_contain_text("job error 90017 S1")
        events = view.get_by_test_id("capture-events")
        events.locator("summary").click()
        expect(events).to_contain_text("90017")  # the error on the trace's timeline
        rrd = o.request.get(f"{srv.base}/api/traces/{before[90017]['trace']}/trace.rrd")
        assert rrd.ok and len(rrd.body()) > 10_000
    finally:
        o.close()
