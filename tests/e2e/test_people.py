"""People in the browser: one operator per machine (the control strip, request and grant),
a parameter written by someone else meanwhile (both values, then the user's choice), and the
audit trail of the machine (who did what, filters, CSV)."""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterator

import pytest
from playwright.sync_api import Browser, Page, expect

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD as PASSWORD
from tests.backend.server import Server, add_users
from tests.e2e.browser import open_hmi, panel, poll

OWN_SERVICE = True  # adds operators and observers

ANA, BEN, OLE = "ana", "ben", "ole"  # two operators and an observer
KV = "getriebe[0].kv"  # P-AXIS-00099, position loop gain of gear 1 [002]


@pytest.fixture(scope="module", autouse=True)
def people(srv: Server) -> None:
    add_users(srv.db, {ANA: Role.OPERATOR, BEN: Role.OPERATOR, OLE: Role.OBSERVER})


@pytest.fixture
def two(browser: Browser, srv: Server, mid: str) -> Iterator[tuple[Page, Page]]:
    """Ana's and Ben's HMI on the same machine, each in a context of its own."""
    a = open_hmi(browser, srv.base, mid, user=ANA, password=PASSWORD)
    b = open_hmi(browser, srv.base, mid, user=BEN, password=PASSWORD)
    for p in (a, b):
        panel(p, "jog").get_by_test_id("jog-axis-X").check()
    yield a, b
    a.close()
    b.close()


def test_control_passes_from_one_operator_to_another_on_request(
    two: tuple[Page, Page], srv: Server, mid: str
) -> None:
    a, b = two
    strip_a, strip_b = a.get_by_test_id("control-strip"), b.get_by_test_id("control-strip")
    expect(strip_b.get_by_test_id("control-holder")).to_have_text("Free")
    expect(panel(b, "jog").get_by_test_id("jog-step-plus")).to_be_enabled()  # the first takes it
    panel(a, "jog").get_by_test_id("jog-step-plus").click()  # Ana's first command takes control
    expect(strip_a.get_by_test_id("control-holder")).to_have_text("You have control")
    expect(strip_b.get_by_test_id("control-holder")).to_have_text("ana (operator) has control")
    jog_b = panel(b, "jog").get_by_test_id("jog-plus")
    expect(jog_b).to_be_disabled()
    expect(jog_b).to_have_attribute("title", re.compile(r"ana \(operator\) has control"))
    expect(panel(b, "mdi").get_by_test_id("mdi-input")).to_be_disabled()
    expect(b.get_by_test_id("estop")).to_be_enabled()  # a stop needs no control
    expect(strip_b.get_by_test_id("control-take")).to_have_count(0)  # operators ask

    strip_b.get_by_test_id("control-request").click()
    strip_b.get_by_test_id("control-request-message").fill("to check the X feed, 5 min")
    strip_b.get_by_test_id("control-request-send").click()
    expect(strip_b.get_by_test_id("control-requested")).to_be_visible()
    incoming = strip_a.get_by_test_id("control-incoming")
    expect(incoming).to_contain_text("ben (operator) asks for control")
    expect(incoming.get_by_test_id("control-request-said")).to_have_text(
        "to check the X feed, 5 min"
    )
    incoming.get_by_test_id("control-grant").click()

    expect(strip_b.get_by_test_id("control-holder")).to_have_text("You have control")
    expect(strip_a.get_by_test_id("control-holder")).to_have_text("ben (operator) has control")
    expect(jog_b).to_be_enabled()
    expect(panel(a, "jog").get_by_test_id("jog-plus")).to_be_disabled()
    x0 = srv.axis("X", mid)["pos_cmd"]
    panel(b, "jog").get_by_test_id("jog-step-plus").click()  # Ben commands now: 1 mm step
    poll(lambda: abs(srv.axis("X", mid)["pos_cmd"] - (x0 + 1.0)) < 1e-6, "Ben's 1 mm step")
    expect(panel(b, "jog").get_by_test_id("jog-refusal")).to_be_hidden()


def test_an_observer_never_gets_a_command_button(browser: Browser, srv: Server, mid: str) -> None:
    p = open_hmi(browser, srv.base, mid, user=OLE, password=PASSWORD)
    try:
        strip = p.get_by_test_id("control-strip")
        expect(strip.get_by_test_id("control-holder")).to_have_text("Free")
        jog = panel(p, "jog")
        jog.get_by_test_id("jog-axis-X").check()
        for key in ("jog-plus", "jog-step-plus", "jog-home", "feed-override"):
            expect(jog.get_by_test_id(key)).to_be_disabled()
        expect(jog.get_by_test_id("jog-plus")).to_have_attribute(
            "title", re.compile("observer may not command")
        )
        expect(p.get_by_test_id("estop")).to_be_disabled()  # observers only watch
        expect(strip.get_by_role("button")).to_have_count(0)  # nothing to take
        # the scope's recording is an operator's: disabled with the reason, before it is tried
        p.get_by_test_id("tab-Scope").click()
        record = panel(p, "scope-setup").get_by_test_id("recording-start")
        expect(record).to_be_disabled()
        expect(record).to_have_attribute("title", re.compile("takes the role operator"))
    finally:
        p.close()


def test_a_remote_observer_asks_for_control_and_writes_in_the_logbook(
    browser: Browser, srv: Server, mid: str
) -> None:
    """Ole watches from afar while Ana works: his request with a message reaches her (she can
    only answer it: an observer is never granted control), and his logbook entry appears in
    her history as he writes it, under his name."""
    a = open_hmi(browser, srv.base, mid, user=ANA, password=PASSWORD)
    o = open_hmi(browser, srv.base, mid, user=OLE, password=PASSWORD)
    try:
        a.get_by_test_id("control-strip").get_by_test_id("control-take").click()
        a.get_by_test_id("tab-History").click()
        strip_o = o.get_by_test_id("control-strip")
        expect(strip_o.get_by_test_id("control-holder")).to_have_text("ana (operator) has control")
        strip_o.get_by_test_id("control-request").click()
        strip_o.get_by_test_id("control-request-message").fill("may I see S1 at 3000 rpm?")
        strip_o.get_by_test_id("control-request-send").click()
        expect(strip_o.get_by_test_id("control-requested")).to_be_visible()
        incoming = a.get_by_test_id("control-strip").get_by_test_id("control-incoming")
        expect(incoming).to_contain_text("ole (observer) asks for control")
        expect(incoming.get_by_test_id("control-request-said")).to_have_text(
            "may I see S1 at 3000 rpm?"
        )
        expect(incoming.get_by_test_id("control-grant")).to_have_count(0)
        incoming.get_by_test_id("control-refuse").click()  # "Answered"
        expect(incoming).to_have_count(0)

        o.get_by_test_id("tab-History").click()
        logbook = panel(o, "history")
        logbook.get_by_test_id("history-note-input").fill("replaced the encoder cable of X")
        logbook.get_by_test_id("history-note-add").click()
        rows = panel(a, "history").get_by_test_id("history-row")
        note = rows.filter(has_text="replaced the encoder cable of X")
        expect(note.get_by_test_id("history-actor-cell")).to_have_text(OLE)  # live, no reload
        asked = rows.filter(has_text="may I see S1 at 3000 rpm?")
        expect(asked.get_by_test_id("history-actor-cell")).to_have_text(OLE)
    finally:
        a.close()
        o.close()


def open_kv(p: Page) -> None:
    p.get_by_test_id("tab-Parameters").click()
    params = panel(p, "parameters")
    params.get_by_test_id("param-search").fill("P-AXIS-00099")
    expect(params.get_by_test_id(f"param-input-{KV}")).to_be_visible()


def test_a_value_written_meanwhile_shows_both_and_mine_can_still_be_written(
    two: tuple[Page, Page], srv: Server, mid: str
) -> None:
    a, b = two
    open_kv(a)
    open_kv(b)  # Ben reads the list now: the version before Ana's write
    pa, pb = panel(a, "parameters"), panel(b, "parameters")
    pa.get_by_test_id(f"param-input-{KV}").fill("1500")
    pa.get_by_test_id("param-apply").click()  # Ana's write takes the free machine
    a.get_by_test_id("trial-bar").get_by_test_id("param-keep").click()
    a.get_by_test_id("control-strip").get_by_test_id("control-release").click()
    expect(b.get_by_test_id("control-strip").get_by_test_id("control-holder")).to_have_text("Free")

    pb.get_by_test_id(f"param-input-{KV}").fill("1800")
    pb.get_by_test_id("param-apply").click()
    stale = pb.get_by_test_id(f"param-stale-{KV}")
    expect(stale).to_contain_text(re.compile(rf"ana changed {re.escape(KV)} to 1500 at \d"))
    expect(stale).to_contain_text("yours: 1800")
    assert value(srv, mid) == 1500  # nothing of Ben's was written

    pb.get_by_test_id("param-write-anyway").click()
    expect(pb.get_by_test_id("param-conflict")).to_be_hidden()
    expect(b.get_by_test_id("trial-bar").get_by_test_id("param-trial")).to_contain_text(
        f"{KV} 1500 → 1800"
    )
    assert value(srv, mid) == 1800


def test_a_trial_ends_with_the_session(two: tuple[Page, Page]) -> None:
    """The next user of the browser must not get the last one's Keep/Revert."""
    a, _ = two
    open_kv(a)
    params = panel(a, "parameters")
    params.get_by_test_id(f"param-input-{KV}").fill("1600")
    params.get_by_test_id("param-apply").click()
    expect(a.get_by_test_id("trial-bar").get_by_test_id("param-trial")).to_be_visible()
    a.get_by_test_id("logout").click()
    form = panel(a, "login")
    form.get_by_test_id("login-name").fill(BEN)
    form.get_by_test_id("login-password").fill(PASSWORD)
    form.get_by_test_id("login-submit").click()
    expect(a.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    expect(a.get_by_test_id("trial-bar")).to_have_count(0)


def value(srv: Server, mid: str) -> float:
    rows = srv.http.get(f"/api/machines/{mid}/parameters", params={"target": "X"}).json()
    return float(next(p["value"] for p in rows if p["name"] == KV))


def test_the_audit_panel_shows_who_commanded_filters_and_exports(
    two: tuple[Page, Page], srv: Server, mid: str
) -> None:
    a, _ = two
    panel(a, "jog").get_by_test_id("jog-step-plus").click()
    strip = a.get_by_test_id("control-strip")
    expect(strip.get_by_test_id("control-holder")).to_have_text("You have control")
    mdi = panel(a, "mdi")
    mdi.get_by_test_id("mdi-input").fill("M3 S20000")  # above the spindle's maximum: 90017
    mdi.get_by_test_id("mdi-send").click()
    expect(mdi.get_by_test_id("mdi-refusal")).to_contain_text("90017")
    a.get_by_test_id("tab-History").click()
    history = panel(a, "history")
    step = history.get_by_test_id("history-row").filter(has_text="jog axis=X action=step")
    expect(step).to_have_count(1)
    expect(step.get_by_test_id("history-actor-cell")).to_have_text(ANA)
    expect(step.get_by_test_id("history-kind-cell")).to_have_text("command")
    expect(step.get_by_test_id("history-outcome-cell")).to_have_text("ok")
    refused = history.get_by_test_id("history-row").filter(has_text="mdi block=M3 S20000")
    expect(refused).to_have_class(re.compile(r"\bwarning\b"))  # marked, with the reason
    expect(refused.get_by_test_id("history-outcome-cell")).to_contain_text("✗ refused (409)")
    # the NC's own entry of the same moment: the job error the refused block raised
    raised = history.get_by_test_id("history-row").filter(has_text="90017")
    expect(raised.filter(has_text="spindle speed out of reach").first).to_have_class(
        re.compile(r"\berror\b")
    )
    took = history.get_by_test_id("history-row").filter(has_text="took control")
    expect(took).to_have_count(1)  # the step took the free machine first

    history.get_by_test_id("history-kind").select_option("control")
    expect(step).to_have_count(0)
    expect(took).to_have_count(1)
    kinds = history.get_by_test_id("history-kind-cell").all_inner_texts()
    assert kinds and set(kinds) == {"control"}

    history.get_by_test_id("history-kind").select_option("commands")
    expect(step).to_have_count(1)
    href = history.get_by_test_id("history-csv").get_attribute("href")
    assert href and "kind=command" in href
    r = a.request.get(srv.base + href)  # with Ana's session, as the link would be followed
    assert r.ok and r.headers["content-type"].startswith("text/csv")
    assert f'filename="{mid}_history_' in r.headers["content-disposition"]
    rows = list(csv.DictReader(io.StringIO(r.text())))
    assert {row["kind"] for row in rows} == {"command"}
    mine = [row for row in rows if row["text"].startswith("jog axis=X action=step")]
    assert len(mine) == 1 and mine[0]["actor"] == ANA and mine[0]["outcome"] == "ok"


def test_the_same_user_in_another_tab_takes_over_here(
    browser: Browser, srv: Server, mid: str
) -> None:
    ctx = browser.new_context(viewport={"width": 1920, "height": 1080})  # one session
    try:
        assert ctx.request.post(
            f"{srv.base}/api/auth/login", data={"name": ANA, "password": PASSWORD}
        ).ok
        first, second = ctx.new_page(), ctx.new_page()  # two tabs: a client id each
        for p in (first, second):
            p.goto(f"{srv.base}/#{mid}")
            panel(p, "jog").get_by_test_id("jog-axis-X").check()
        panel(first, "jog").get_by_test_id("jog-step-plus").click()
        s1, s2 = first.get_by_test_id("control-strip"), second.get_by_test_id("control-strip")
        expect(s1.get_by_test_id("control-holder")).to_have_text("You have control")
        expect(s2.get_by_test_id("control-holder")).to_have_text("You have control in another tab")
        expect(panel(second, "jog").get_by_test_id("jog-step-plus")).to_be_disabled()
        s2.get_by_test_id("control-take-here").click()
        expect(s2.get_by_test_id("control-holder")).to_have_text("You have control")
        expect(panel(second, "jog").get_by_test_id("jog-step-plus")).to_be_enabled()
        expect(panel(first, "jog").get_by_test_id("jog-step-plus")).to_be_disabled()
    finally:
        ctx.close()
