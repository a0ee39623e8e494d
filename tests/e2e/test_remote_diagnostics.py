"""Remote diagnostics in the browser: an operator causes two job errors, the service restarts,
and an observer logged in from afar still finds both in the machine's history, with their
wall clock, the stop, the start and the power-on marked and announced; the flight recorder's
trace of the first error opens from its entry in the scope (by a link that names it) and in
Rerun."""

from __future__ import annotations

import re
import time
from pathlib import Path
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
            # the wall clock it happened, as the browser's locale (en-US: 12 hours) writes it
            wall = time.strftime("%I:%M:%S", time.localtime(entry["time_unix"]))
            expect(row).to_contain_text(re.sub(r"^0", "", wall))
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
        o.reload()  # the address names the trace: a ticket's link opens it again
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


def test_a_guest_link_shows_the_live_machine_until_it_is_revoked(
    browser: Browser, srv: Server, mid: str
) -> None:
    """The operator makes a link in the HMI; a guest with no account opens it and watches the
    live machine (the operator sees one guest watching); revoked, the guest's page loses the
    machine and the link opens nothing any more."""
    a = open_hmi(browser, srv.base, f"{mid}/history")
    guest = browser.new_page(viewport={"width": 1024, "height": 768})
    try:
        share = panel(a, "share")
        share.get_by_test_id("share-label").fill("drive maker")
        share.get_by_test_id("share-create").click()
        url = share.get_by_test_id("share-url").input_value()
        assert url.startswith(f"{srv.base}/share/")
        guest.goto(url)
        expect(guest.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
        expect(guest.get_by_test_id("control-strip")).to_contain_text("view only (share link)")
        expect(guest.get_by_test_id("guest-link")).to_contain_text("drive maker")  # and until when
        assert guest.evaluate("location.hash").startswith(f"#{mid}/")
        expect(panel(guest, "jog").get_by_test_id("jog-plus")).to_be_disabled()
        # a guest watches: the live machine, parameters, traces, history; nothing to set up
        for hidden in ("tab-Service", "tab-Commissioning", "open-machines"):
            expect(guest.get_by_test_id(hidden)).to_have_count(0)
        guest.get_by_test_id("tab-Scope").click()
        expect(panel(guest, "scope-setup").get_by_test_id("scope-arm")).to_be_disabled()
        guest.get_by_test_id("tab-Operate").click()
        viewers = a.get_by_test_id("control-strip").get_by_test_id("control-viewers")
        expect(viewers).to_contain_text("1 by share link")
        expect(share.get_by_test_id("share-watching")).to_have_text("1")
        shot(guest, "guest-link-tablet")
        share.get_by_test_id("share-revoke").click()
        expect(guest.get_by_test_id("share-ended")).to_contain_text("expired or was revoked")
        expect(guest.get_by_test_id("login-name")).to_have_count(0)  # a guest has no account
        ended = guest.request.get(url)
        assert ended.status == 401 and "expired or was revoked" in ended.text()
    finally:
        a.close()
        guest.close()


def test_a_bundle_opens_on_another_service_as_the_offline_machine(
    browser: Browser, srv: Server, mid: str, tmp_path: Path
) -> None:
    """The bundle downloads from the machine's History; on a second service the expert opens
    it on a page of its own and sees the same difference to the baseline, the same history,
    read-only, and the alarm's trace drawn for the axis that raised it."""
    srv.http.post(f"/api/machines/{mid}/versions", json={"name": "delivered", "baseline": True})
    change = {"scope": "axis", "target": "X", "name": "getriebe[0].kv", "value": 1500}
    srv.http.patch(f"/api/machines/{mid}/parameters", json={"changes": [change]})
    note = {"text": "replaced the encoder cable of X"}
    srv.http.post(f"/api/machines/{mid}/history/notes", json=note).raise_for_status()
    srv.pace(mid, mode="pause")  # queued behind M3 S1500, M3 S20000 raises 90017 on S1
    for block in ("M3 S1500", "M3 S20000"):
        srv.http.post(f"/api/machines/{mid}/commands", json={"type": "mdi", "block": block})
    srv.pace(mid, mode="run")  # real pace: fast, a loaded machine may lap the window
    _until_traced(srv, mid, {90017})
    a = open_hmi(browser, srv.base, f"{mid}/history")
    try:
        with a.expect_download() as got:
            panel(a, "history").get_by_test_id("history-bundle").click()
        zip_path = tmp_path / got.value.suggested_filename
        got.value.save_as(zip_path)
        assert zip_path.name.startswith(f"{mid}_bundle_")
    finally:
        a.close()
    other = Server(tmp_path / "other.sqlite").start()
    e = open_hmi(browser, other.base, "demo/history")
    try:
        panel(e, "bundles").get_by_test_id("bundle-file").set_input_files(str(zip_path))
        expect(e.get_by_test_id("offline-strip")).to_contain_text("read-only")
        assert re.fullmatch(r"#bundle/[0-9a-f]{12}", e.evaluate("location.hash"))
        expect(panel(e, "bundle")).to_contain_text(mid)
        diff = panel(e, "bundle-diff-panel")
        expect(diff.get_by_test_id("diff-row-X-getriebe[0].kv")).to_contain_text("1500")
        rows = panel(e, "bundle-history").get_by_test_id("history-row")
        expect(rows.filter(has_text=note["text"])).to_have_count(1)
        expect(panel(e, "bundle-history").get_by_test_id("history-note-input")).to_have_count(0)
        alarm = panel(e, "bundle-alarm-traces").get_by_test_id("capture-view")
        expect(alarm.get_by_test_id("capture-trigger")).to_contain_text("job error 90017 S1")
        drawn = alarm.locator('[data-testid="channel-toggle"][aria-pressed="true"]')
        expect(drawn.first).to_be_visible()
        names = drawn.evaluate_all("l => l.map(b => b.dataset.channel)")
        assert {n.split(".")[0] for n in names} == {"S1"}  # of every axis kept, the one 90017 names
        shot(e, "bundle-offline-desktop")
        e.set_viewport_size({"width": 1024, "height": 768})
        shot(e, "bundle-offline-tablet")
        e.get_by_test_id("bundle-back").click()
        expect(e.get_by_test_id("tab-History")).to_be_visible()
    finally:
        e.close()
        other.close()
