"""What a user is told about other people's doings: a job error only while it is active (an
emergency stop cleared by Reset leaves no banner, for anyone), who stopped the machine and who
resets it, a refused request or control taken away, a role that only watches; the audit
filters applying while typing."""

from __future__ import annotations

import pytest
from playwright.sync_api import Browser, Page, expect

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD as PASSWORD
from tests.backend.server import USER, Server, add_users
from tests.e2e.browser import SIZES, open_hmi, panel, poll, shot

OWN_SERVICE = True  # adds operators and observers

ANA, BEN, IDA, OLE = "ana", "ben", "ida", "ole"  # two operators, an instructor, an observer
KV = "getriebe[0].kv"  # P-AXIS-00099, position loop gain of gear 1 [002]


@pytest.fixture(scope="module", autouse=True)
def people(srv: Server) -> None:
    add_users(
        srv.db, {ANA: Role.OPERATOR, BEN: Role.OPERATOR, IDA: Role.INSTRUCTOR, OLE: Role.OBSERVER}
    )


def as_user(browser: Browser, srv: Server, mid: str, user: str) -> Page:
    return open_hmi(browser, srv.base, mid, user=user, password=PASSWORD)


def both_sizes(page: Page, name: str) -> None:
    for size, (w, h) in SIZES.items():
        page.set_viewport_size({"width": w, "height": h})
        page.wait_for_timeout(200)
        shot(page, f"{name}-{size}")


def test_a_reset_emergency_stop_leaves_no_banner_now_or_for_the_next_login(
    browser: Browser, srv: Server, mid: str
) -> None:
    a = as_user(browser, srv, mid, ANA)
    try:
        strip = a.get_by_test_id("control-strip")
        strip.get_by_test_id("control-take").click()
        expect(strip.get_by_test_id("control-holder")).to_have_text("You have control")
        r = srv.http.post(f"/api/machines/{mid}/emergency-stop")  # the test admin stops it
        assert r.is_success, r.text
        banner = a.get_by_test_id("banner-error")
        expect(banner).to_contain_text("90005")  # emergency stop [job error table]
        a.get_by_test_id("reset").click()  # Ana holds control: she resets
        expect(banner).to_be_hidden()
        both_sizes(a, "estop-reset-no-banner")
        a.get_by_test_id("tab-History").click()  # the history stays
        expect(panel(a, "history").get_by_test_id("history-table")).to_contain_text("90005")
    finally:
        a.close()
    b = as_user(browser, srv, mid, BEN)  # a login afterwards gets the newest events ...
    try:
        b.get_by_test_id("tab-History").click()
        expect(panel(b, "history").get_by_test_id("history-table")).to_contain_text("90005")
        expect(b.get_by_test_id("banner-error")).to_have_count(0)  # ... but no banner
    finally:
        b.close()


def test_an_emergency_stop_names_who_stopped_and_who_resets(
    browser: Browser, srv: Server, mid: str
) -> None:
    a = as_user(browser, srv, mid, ANA)
    try:
        a.get_by_test_id("control-strip").get_by_test_id("control-take").click()
        hint = a.get_by_test_id("estop-hint")
        expect(hint).to_have_count(0)
        assert srv.http.post(f"/api/machines/{mid}/emergency-stop").is_success  # the test admin
        expect(hint).to_have_text(f"Emergency stop by {USER}: the control holder resets (Reset)")
        both_sizes(a, "estop-hint-and-banner")
        a.get_by_test_id("reset").click()
        expect(hint).to_have_count(0)
    finally:
        a.close()


def test_a_refused_request_and_control_taken_away_are_told(
    browser: Browser, srv: Server, mid: str
) -> None:
    a, b = as_user(browser, srv, mid, ANA), as_user(browser, srv, mid, BEN)
    try:
        strip_a, strip_b = a.get_by_test_id("control-strip"), b.get_by_test_id("control-strip")
        strip_a.get_by_test_id("control-take").click()
        expect(strip_b.get_by_test_id("control-holder")).to_have_text("ana (operator) has control")
        strip_b.get_by_test_id("control-request").click()
        strip_b.get_by_test_id("control-request-send").click()
        strip_a.get_by_test_id("control-incoming").get_by_test_id("control-refuse").click()
        note_b = strip_b.get_by_test_id("control-note")
        expect(note_b).to_contain_text("ana (operator) refused your request")
        expect(note_b).not_to_contain_text("lapsed")  # answered, not timed out
        expect(strip_a.get_by_test_id("control-note")).to_have_count(0)  # Ana refused herself
        both_sizes(b, "control-note-refused")
        note_b.get_by_test_id("control-note-dismiss").click()
        expect(note_b).to_have_count(0)

        i = as_user(browser, srv, mid, IDA)
        try:
            i.get_by_test_id("control-strip").get_by_test_id("control-take").click()
            expect(strip_a.get_by_test_id("control-note")).to_contain_text(
                "ida (instructor) took control from you"
            )
            expect(strip_b.get_by_test_id("control-note")).to_have_count(0)  # not Ben's news
            both_sizes(a, "control-note-taken")
        finally:
            i.close()
    finally:
        a.close()
        b.close()


def test_releasing_or_granting_control_is_no_news_and_clears_old_news(
    browser: Browser, srv: Server, mid: str
) -> None:
    a, b = as_user(browser, srv, mid, ANA), as_user(browser, srv, mid, BEN)
    try:
        strip_a, strip_b = a.get_by_test_id("control-strip"), b.get_by_test_id("control-strip")
        a.get_by_test_id("tab-Parameters").click()
        params = panel(a, "parameters")
        params.get_by_test_id("param-search").fill("P-AXIS-00099")  # kv of gear 1 [002]
        params.get_by_test_id(f"param-input-{KV}").fill("1500")
        params.get_by_test_id("param-apply").click()  # takes the free machine
        bar = a.get_by_test_id("trial-bar")
        bar.get_by_test_id("param-keep").click()
        expect(bar.get_by_test_id("trial-message")).to_contain_text("✓ Kept 1 value")
        expect(strip_b.get_by_test_id("control-holder")).to_have_text("ana (operator) has control")
        strip_b.get_by_test_id("control-request").click()
        strip_b.get_by_test_id("control-request-send").click()
        strip_a.get_by_test_id("control-incoming").get_by_test_id("control-grant").click()
        expect(strip_b.get_by_test_id("control-holder")).to_have_text("You have control")
        expect(bar).to_have_count(0)  # "Kept" was news to the holder before
        strip_b.get_by_test_id("control-release").click()
        expect(strip_a.get_by_test_id("control-holder")).to_have_text("Free")
        expect(strip_b.get_by_test_id("control-holder")).to_have_text("Free")
        for strip in (strip_a, strip_b):
            expect(strip.get_by_test_id("control-note")).to_have_count(0)
    finally:
        a.close()
        b.close()


def test_an_observer_is_told_the_view_is_only_to_watch(
    browser: Browser, srv: Server, mid: str
) -> None:
    p = as_user(browser, srv, mid, OLE)
    try:
        strip = p.get_by_test_id("control-strip")
        expect(strip.get_by_test_id("control-view-only")).to_have_text("view only (observer)")
    finally:
        p.close()
    a = as_user(browser, srv, mid, ANA)
    try:
        expect(a.get_by_test_id("control-strip").get_by_test_id("control-view-only")).to_have_count(
            0
        )
    finally:
        a.close()


def test_the_audit_user_filter_applies_while_typing(
    browser: Browser, srv: Server, mid: str
) -> None:
    a = as_user(browser, srv, mid, ANA)
    try:
        a.get_by_test_id("control-strip").get_by_test_id("control-take").click()
        a.get_by_test_id("tab-History").click()
        history = panel(a, "history")
        actors = history.get_by_test_id("history-actor-cell")
        expect(actors.filter(has_text=USER).first).to_be_visible()  # the machine's creation
        history.get_by_test_id("history-actor").press_sequentially("an", delay=50)  # of "ana"
        poll(lambda: set(actors.all_inner_texts()) == {ANA}, "only Ana's rows")
        history.get_by_test_id("history-text").press_sequentially("took", delay=50)
        expect(history.get_by_test_id("history-row")).to_have_count(1)
        expect(history.get_by_test_id("history-text-cell")).to_contain_text("took control")
    finally:
        a.close()
