"""The instructor console in the browser: a class made in the console, two students logged in
by their seats' one-time links, a sign fault injected into one seat from the fault form. The
student's X runs away and trips lag monitoring (90002), the grid shows it on that seat's tile
only, and the instructor opens the seat's live view."""

from __future__ import annotations

import io
import re
from collections.abc import Iterator

import pytest
import zxingcpp
from PIL import Image
from playwright.sync_api import Browser, FilePayload, Locator, Page, expect
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from api.auth import Role
from nc_sim.config import demo_lists
from tests.backend.server import OTHERS_PASSWORD, Server, add_users
from tests.e2e.browser import SIZES, panel, shot, signed_in_page

OWN_SERVICE = True  # adds an instructor and runs classes

TRAINER = "trainer"
CLASS = "drill"
# accel-curve's one fault at start is the spindle's (a torque-limited drive): X is as the demo's
EXERCISE = "accel-curve"
LAG_MONITORING = 90002  # job error: following error above its limit [002]


@pytest.fixture(scope="module", autouse=True)
def instructor(srv: Server) -> None:
    add_users(srv.db, {TRAINER: Role.INSTRUCTOR})


@pytest.fixture
def console(browser: Browser, srv: Server) -> Iterator[Page]:
    """The instructor's console (Classes in the top bar)."""
    p = signed_in_page(browser, srv.base, user=TRAINER, password=OTHERS_PASSWORD)
    p.goto(f"{srv.base}/")
    expect(p.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    p.get_by_test_id("open-classes").click()
    expect(p.get_by_test_id("console")).to_be_visible()
    yield p
    p.close()


def student(browser: Browser, url: str) -> Page:
    """A student's own browser, logged in by their seat's one-time link."""
    w, h = SIZES["desktop"]
    p = browser.new_page(viewport={"width": w, "height": h})
    p.set_default_timeout(15_000)
    p.goto(url)
    expect(p.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    return p


def has_class(name: str) -> re.Pattern[str]:
    """A class attribute with `name` among its classes."""
    return re.compile(rf"(^|\s){re.escape(name)}(\s|$)")


def resize(p: Page, size: str) -> None:
    w, h = SIZES[size]
    p.set_viewport_size({"width": w, "height": h})


def tile(p: Page, n: int) -> Locator:
    return panel(p, "grid").get_by_test_id(f"seat-{n}")


def test_a_sign_fault_in_one_seat_shows_on_its_tile_and_in_its_live_view(
    console: Page, browser: Browser, srv: Server
) -> None:
    c = console
    # the console shows no machine: no machine select, health or emergency stop in its bar
    expect(c.locator(".topbar")).to_be_visible()
    expect(c.get_by_test_id("estop")).to_have_count(0)
    expect(c.locator(".machine-select")).to_have_count(0)
    c.get_by_test_id("class-new").click()
    form = panel(c, "class-create")
    form.get_by_test_id("class-exercise").select_option(EXERCISE)
    expect(form.get_by_test_id("exercise-info-0")).to_contain_text("1 fault at start")
    form.get_by_test_id("class-id").fill(CLASS)
    form.get_by_test_id("class-link-hours").select_option("24")  # prepared the day before
    form.get_by_test_id("class-seats").fill("2")
    form.get_by_test_id("class-students").fill("Anna\nBert")
    form.get_by_test_id("class-create").click()

    links = panel(c, "seat-links")
    expect(links).to_contain_text("Shown this once", timeout=60_000)  # two machines start
    urls = [
        links.get_by_test_id(f"seat-link-{n}").get_by_test_id("link-url").input_value()
        for n in (1, 2)
    ]
    assert all("/auth/once?token=" in u for u in urls), urls
    # the field is tall enough for its font's descenders (underscores): inner height ≥ 1.4 em
    first = links.get_by_test_id("link-url").first
    inner, em = first.evaluate("e => [e.clientHeight, parseFloat(getComputedStyle(e).fontSize)]")
    assert inner >= 1.4 * em, (inner, em)
    shot(c, "class-console-links")
    # the printed sheet: a card per seat with the student's name and a QR code that reads
    # back as the seat's link (decoded by zxing-cpp from the page as printed)
    c.emulate_media(media="print")
    for n, name in ((1, "Anna"), (2, "Bert")):
        card = links.get_by_test_id(f"link-card-{n}")
        expect(card.locator("h2")).to_have_text(name)
        qr = Image.open(io.BytesIO(card.locator("svg.qr").screenshot()))
        assert [r.text for r in zxingcpp.read_barcodes(qr)] == [urls[n - 1]]
    shot(c, "class-console-link-sheet")
    c.emulate_media(media="screen")
    expect(links.get_by_test_id("link-sheet")).to_be_hidden()
    links.get_by_test_id("links-done").click()
    expect(links).to_be_hidden()  # shown once: gone for good

    # nobody has joined: the seats wait, their clocks stand
    grid = panel(c, "grid")
    expect(grid.get_by_test_id("grid-joined")).to_have_text("0")
    expect(tile(c, 2).get_by_test_id("seat-mode")).to_have_text("not joined")
    anna = student(browser, urls[0])
    expect(grid.get_by_test_id("grid-joined")).to_have_text("1")
    grid.get_by_test_id("grid-show-waiting").click()  # the counter filters: Bert's seat only
    expect(grid.locator(".seat-tile")).to_have_count(1)
    expect(tile(c, 2)).to_be_visible()
    grid.get_by_test_id("grid-show-all").click()
    bert = student(browser, urls[1])
    try:
        expect(grid.get_by_test_id("grid-joined")).to_have_text("2")
        expect(tile(c, 1).get_by_test_id("seat-student")).to_have_text("Anna")
        expect(tile(c, 2).get_by_test_id("seat-student")).to_have_text("Bert")
        expect(panel(c, "grid").get_by_test_id("grid-link")).to_have_text("live")
        for n in (1, 2):
            expect(tile(c, n).get_by_test_id("seat-error")).to_have_text("no job error")
            expect(tile(c, n).get_by_test_id("seat-faults")).to_have_text("⚡1")  # S1's
        for size in ("desktop", "tablet"):
            resize(c, size)
            shot(c, f"class-console-grid-{size}")

        tile(c, 1).get_by_test_id("seat-fault").click()
        fault = panel(c, "fault-form")
        expect(fault).to_contain_text("seat 1 (Anna)")
        fault.get_by_test_id("fault-kind").select_option("motor_inverted")
        # the kinds in the instructor's words (the schema's titles), not identifiers
        expect(fault.get_by_test_id("fault-kind").locator("option:checked")).to_have_text(
            "Motor wired inverted"
        )
        expect(fault.get_by_test_id("fault-description")).to_contain_text("wired inverted")
        fault.get_by_test_id("fault-field-axis").select_option("X")
        for size in ("tablet", "desktop"):
            resize(c, size)
            shot(c, f"class-console-fault-{size}")
        fault.get_by_test_id("fault-inject").click()
        expect(fault).to_be_hidden()
        expect(tile(c, 1).get_by_test_id("seat-faults")).to_have_text("⚡2")
        expect(tile(c, 2).get_by_test_id("seat-faults")).to_have_text("⚡1")

        # Anna moves X by a 1 mm jog step: with the motor inverted the loop pushes X away
        # from its command until lag monitoring stops it (a seat opens on its Exercise tab)
        anna.get_by_test_id("tab-Operate").click()
        jog = panel(anna, "jog")
        jog.get_by_test_id("jog-axis-X").check()
        jog.get_by_test_id("jog-step-plus").click()
        expect(tile(c, 1).get_by_test_id("seat-error")).to_contain_text(
            str(LAG_MONITORING), timeout=20_000
        )
        expect(tile(c, 1)).to_have_class(has_class("in-error"))
        expect(tile(c, 1).get_by_test_id("seat-control")).to_have_text("◉ Anna")  # her jog took it
        expect(tile(c, 2).get_by_test_id("seat-error")).to_have_text("no job error")
        expect(tile(c, 2)).not_to_have_class(has_class("in-error"))
        expect(anna.get_by_test_id("banner-error")).to_contain_text(str(LAG_MONITORING))
        # the console shows what was injected; the student's screen does not
        expect(anna.get_by_text("motor_inverted")).to_have_count(0)
        expect(anna.get_by_text("inverted")).to_have_count(0)
        shot(c, "class-console-seat-error")
        # the seat's detail: what was injected, and Anna's jog in its commands
        tile(c, 1).get_by_test_id("seat-detail").click()
        detail = panel(c, "seat-detail")
        expect(detail.get_by_test_id("detail-faults")).to_contain_text("X: motor wired inverted")
        expect(detail.get_by_test_id("detail-history")).to_contain_text("inject fault")
        shot(c, "class-console-seat-detail")

        mid = f"{CLASS}-s01"
        tile(c, 1).get_by_test_id("seat-live").click()
        expect(c.get_by_test_id("console")).to_be_hidden()
        expect(c.locator(".machine-select select")).to_have_value(mid)
        expect(c.get_by_test_id("banner-error")).to_contain_text(str(LAG_MONITORING))
        expect(c.get_by_test_id("control-strip")).to_be_visible()  # the instructor can take over
        shot(c, "class-console-live-view")
        expect(c.get_by_test_id("estop")).to_be_visible()  # a machine is shown: its E-stop
        c.get_by_test_id("open-classes").click()
        expect(tile(c, 1).get_by_test_id("seat-error")).to_contain_text(str(LAG_MONITORING))

        # Bert holds his seat, then it is frozen: his strip says so, offers no control, and
        # what would only be refused is disabled, with the reason
        strip = bert.get_by_test_id("control-strip")
        strip.get_by_test_id("control-take").click()
        expect(strip.get_by_test_id("control-holder")).to_have_text("You have control")
        expect(bert.get_by_test_id("reset")).to_be_enabled()
        r = srv.http.post(f"/api/classes/{CLASS}/freeze", json={"seats": [2], "frozen": True})
        assert r.status_code == 200, r.text
        expect(strip.get_by_test_id("control-frozen")).to_contain_text(
            "wait until the instructor resumes"
        )
        expect(strip.get_by_test_id("control-holder")).to_contain_text("frozen by the instructor")
        expect(strip.get_by_test_id("control-take")).to_have_count(0)
        expect(bert.get_by_test_id("reset")).to_be_disabled()
        expect(bert.get_by_test_id("reset")).to_have_attribute("title", re.compile("frozen"))
        shot(bert, "class-seat-frozen-control")
    finally:
        anna.close()
        bert.close()


def lis(name: str, text: str) -> FilePayload:
    """A parameter list file as the browser's file input takes it."""
    return {"name": name, "mimeType": "text/plain", "buffer": text.encode()}


def test_a_class_from_uploaded_parameter_lists(console: Page, srv: Server) -> None:
    """New class with "Upload parameter lists": the demo's own .lis files with X's kv 33 1/s
    (getriebe[0].kv 3300); each axis list's number is read from its kopf.achs_nr. The seat's
    machine has the uploaded kv, and lists without X are refused naming X."""
    channel, axes = demo_lists()
    kv = "getriebe[0].kv                     "
    axes[1] = axes[1].replace(kv + "2000", kv + "3300")
    files = [lis(f"slide{nr}.lis", text) for nr, text in sorted(axes.items())]
    c = console
    c.get_by_test_id("class-new").click()
    form = panel(c, "class-create")
    form.get_by_test_id("class-exercise").select_option("sign-error")
    form.get_by_test_id("template-lists").check()
    no_x = channel.replace("achse[0].bezeichnung       X", "achse[0].bezeichnung       Y")
    form.get_by_test_id("lists-channel").set_input_files(lis("channel.lis", no_x))
    form.get_by_test_id("lists-axes").set_input_files(files)
    numbers = form.get_by_test_id("lists-axis-numbers")
    for i, nr in enumerate(sorted(axes)):
        expect(numbers.get_by_test_id(f"lists-axis-nr-{i}")).to_have_value(str(nr))
    form.get_by_test_id("class-id").fill("lists")
    form.get_by_test_id("class-seats").fill("1")
    form.get_by_test_id("class-create").click()
    expect(form.get_by_test_id("class-create-refusal")).to_contain_text("faults[0].axis = 'X'")
    shot(c, "class-create-lists-refused")

    form.get_by_test_id("lists-channel").set_input_files(lis("channel.lis", channel))
    form.get_by_test_id("class-create").click()
    expect(panel(c, "seat-links")).to_contain_text("Shown this once", timeout=60_000)
    r = srv.http.get("/api/machines/lists-s01/parameters", params={"scope": "axis", "target": "X"})
    assert {p["name"]: p["value"] for p in r.json()}["getriebe[0].kv"] == 3300


def test_a_second_class_shows_its_own_login_links(console: Page) -> None:
    """Two classes made one after the other, the first's links not yet taken: the panel
    shows the second class's seats and links (it kept the first's: Clara got Anna's link)."""
    c = console

    def make(cid: str, seats: int) -> list[str]:
        c.get_by_test_id("class-new").click()
        form = panel(c, "class-create")
        form.get_by_test_id("class-exercise").select_option("sign-error")
        form.get_by_test_id("class-id").fill(cid)
        form.get_by_test_id("class-seats").fill(str(seats))
        form.get_by_test_id("class-create").click()
        links = panel(c, "seat-links")
        expect(links).to_contain_text(f"({cid})", timeout=60_000)
        rows = links.get_by_test_id("link-url")
        expect(rows).to_have_count(seats)
        return [rows.nth(i).input_value() for i in range(seats)]

    first = make("twice-a", 2)
    second = make("twice-b", 1)
    assert not set(second) & set(first)
    panel(c, "seat-links").get_by_test_id("links-done").click()
    expect(c.locator("ul.class-list").first).to_contain_text("1 seat ·")


WIDER = """() => [...document.querySelectorAll('*')]
  .filter((e) => e.getBoundingClientRect().right > innerWidth + 1)
  .slice(0, 8)
  .map((e) => `${e.tagName}.${e.className} ${Math.round(e.getBoundingClientRect().right)}`)"""


def no_sideways_scroll(p: Page) -> None:
    """The page fits its viewport's width (nothing runs past the right edge) once its layout
    has followed the new size (its charts resize on the next animation frame)."""
    # a function, not an expression: Playwright polls an expression by eval(), which the
    # page's Content-Security-Policy refuses (only when the first look fails: a flaky error)
    try:
        p.wait_for_function(
            "() => document.documentElement.scrollWidth <= innerWidth", timeout=3000
        )
    except PlaywrightTimeout:
        width = p.evaluate("document.documentElement.scrollWidth")
        raise AssertionError((width, p.evaluate(WIDER))) from None


def test_watching_a_seat_then_ending_the_class(
    console: Page, browser: Browser, srv: Server
) -> None:
    """The instructor watches Anna's seat live: her hints read-only (no button: a hint
    costs her points), her control named as hers. Ended with the page's own confirmation,
    Anna's page shows her result; the debrief keeps the seat's faults."""
    c = console
    r = srv.http.post(
        "/api/classes",
        json={"id": "watch", "exercises": ["sign-error"], "seats": 1, "students": ["Anna"]},
    )
    assert r.status_code == 201, r.text
    anna = student(browser, r.json()["links"][0]["url"])
    try:
        c.reload()  # the console lists the class made over the API
        expect(c.get_by_test_id("console")).to_be_visible()
        panel(c, "classes").get_by_test_id("class-watch").click()
        grid = panel(c, "grid")
        expect(tile(c, 1).get_by_test_id("seat-student")).to_have_text("Anna")
        # a message says whom it reached
        grid.get_by_test_id("broadcast-text").fill("Five minutes left")
        grid.get_by_test_id("broadcast-send").click()
        expect(grid.get_by_test_id("broadcast-sent")).to_have_text("sent to 1 seat")
        # the fault form: the catalogue read ahead, descriptions as text (no markdown ticks)
        tile(c, 1).get_by_test_id("seat-fault").click()
        fault = panel(c, "fault-form")
        fault.get_by_test_id("fault-kind").select_option("drive_gain_wrong")
        expect(fault.get_by_test_id("fault-loading")).to_have_count(0)
        what = fault.get_by_test_id("fault-description")
        expect(what).not_to_contain_text("`")
        expect(what.locator("code")).to_have_text("factor")
        fault.get_by_test_id("fault-cancel").click()

        anna.get_by_test_id("tab-Operate").click()
        panel(anna, "jog").get_by_test_id("jog-axis-X").check()
        panel(anna, "jog").get_by_test_id("jog-step-plus").click()  # takes control
        expect(tile(c, 1).get_by_test_id("seat-control")).to_have_text("◉ Anna")
        resize(c, "tablet")
        no_sideways_scroll(c)
        resize(c, "desktop")
        anna.get_by_test_id("tab-Exercise").click()
        hints = panel(anna, "exercise-hints")
        hints.get_by_test_id("hint-1").get_by_test_id("hint-show").click()
        hints.get_by_test_id("hint-1").get_by_test_id("hint-confirm").click()
        expect(hints.get_by_test_id("hint-1").get_by_test_id("hint-text")).to_be_visible()

        tile(c, 1).get_by_test_id("seat-live").click()
        expect(c.get_by_test_id("control-holder")).to_have_text("Anna (seat 1) has control")
        c.get_by_test_id("tab-Exercise").click()
        watched = panel(c, "exercise-hints")
        expect(watched.get_by_test_id("hints-read-only")).to_contain_text("only the student")
        expect(watched.get_by_test_id("hint-show")).to_have_count(0)
        expect(watched.get_by_test_id("hint-1").get_by_test_id("hint-text")).to_be_visible()
        expect(watched.get_by_test_id("hint-2").get_by_test_id("hint-not-taken")).to_be_visible()
        for size in ("desktop", "tablet"):
            resize(c, size)
            shot(c, f"class-live-view-hints-{size}")
        resize(c, "desktop")

        c.get_by_test_id("open-classes").click()
        tile(c, 1).get_by_test_id("seat-detail").click()
        detail = panel(c, "seat-detail")
        expect(detail.get_by_test_id("detail-history")).to_contain_text("took hint 1")
        for size in ("desktop", "tablet"):
            resize(c, size)
            no_sideways_scroll(c)
            shot(c, f"class-console-seat-detail-{size}")
        resize(c, "desktop")

        grid.get_by_test_id("class-end").click()
        expect(grid.get_by_test_id("class-end-confirm")).to_be_visible()  # asked in the page
        grid.get_by_test_id("class-end-confirm").click()
        ended = panel(anna, "class-ended")
        expect(ended).to_contain_text("The class has ended", timeout=20_000)
        expect(ended.get_by_test_id("result-checks")).to_have_text("0")
        expect(ended).to_contain_text("of 3")
        expect(ended.get_by_test_id("result-hints")).to_have_text("1")
        for size in ("desktop", "tablet"):
            resize(anna, size)
            shot(anna, f"class-ended-student-{size}")
        with anna.expect_download() as kept:  # hers to keep after Done
            ended.get_by_test_id("class-result-save").click()
        page = kept.value.path().read_text(encoding="utf-8")
        assert "Hints taken</th><td>1</td>" in page and "Checks passed</th><td>0 of 3" in page
        ended.get_by_test_id("class-ended-done").click()
        help_line = panel(anna, "login").get_by_test_id("login-help")
        expect(help_line).to_contain_text("instructor")
        expect(help_line).not_to_contain_text("make run")

        debrief = panel(c, "ended-seats")
        debrief.get_by_test_id("ended-seat-1").get_by_test_id("seat-detail").click()
        detail = panel(c, "seat-detail")
        expect(detail.get_by_test_id("detail-faults")).to_contain_text("X: motor wired inverted")
        expect(detail.get_by_test_id("detail-checks")).to_contain_text("last measured, at the end")
        shot(c, "class-console-debrief")
    finally:
        anna.close()
