"""The student's side of a class in the browser: a seat's login link opens the HMI on the
seat's machine with its exercise (task, checks, score, hints), the instructor's broadcast as
a banner, a freeze as a banner and a paused simulation the student cannot resume."""

from __future__ import annotations

import itertools
import re
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from playwright.sync_api import Browser, Page, expect

from api.auth import Role
from tests.backend.server import Server, add_users, bearer
from tests.e2e.browser import SIZES, open_hmi, panel, shot

OWN_SERVICE = True  # adds an instructor and runs a class

TRAINER = "trainer"
EXERCISE = tomllib.loads(
    (Path(__file__).resolve().parents[2] / "exercises" / "multi-gain.toml").read_text()
)
_classes = itertools.count(1)


@pytest.fixture(scope="module")
def trainer(srv: Server) -> Iterator[httpx.Client]:
    """The instructor, over the API (classes, broadcasts, freezing)."""
    tokens = add_users(srv.db, {TRAINER: Role.INSTRUCTOR})
    with httpx.Client(base_url=srv.base, headers=bearer(tokens[TRAINER]), timeout=30) as c:
        yield c


@pytest.fixture
def seat(trainer: httpx.Client) -> Iterator[dict[str, Any]]:
    """A class of one seat on the multi-gain exercise: its id, machine and login link."""
    cid = f"ex{next(_classes)}"
    r = trainer.post("/api/classes", json={"id": cid, "exercises": ["multi-gain"], "seats": 1})
    assert r.status_code == 201, r.text
    created = r.json()
    yield {
        "class": cid,
        "machine": created["info"]["seats"][0]["machine"],
        "link": created["links"][0]["url"],
    }
    trainer.post(f"/api/classes/{cid}/end")


@pytest.fixture
def student(browser: Browser, seat: dict[str, Any]) -> Iterator[Page]:
    """The seat's student: a fresh browser context logged in by opening the seat's link."""
    w, h = SIZES["desktop"]
    context = browser.new_context(viewport={"width": w, "height": h})
    page = context.new_page()
    page.set_default_timeout(15_000)
    page.goto(seat["link"])
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    yield page
    context.close()


def test_the_student_reads_the_task_and_checks_and_takes_a_hint(
    student: Page, seat: dict[str, Any]
) -> None:
    p = student
    expect(p.get_by_test_id("tab-Exercise")).to_have_attribute("aria-selected", "true")
    ex = panel(p, "exercise")
    expect(ex).to_contain_text(EXERCISE["title"])
    expect(ex.get_by_test_id("exercise-summary")).to_have_text(EXERCISE["summary"])
    # the task flows as paragraphs: its formula reads whole
    expect(ex.get_by_test_id("exercise-task")).to_contain_text("multi_gain_new = multi_gain · f")
    (check,) = EXERCISE["checks"]
    row = panel(p, "exercise-checks").get_by_test_id(f"check-{check['id']}")
    expect(row).to_contain_text(check["text"])
    expect(row).to_contain_text(f"{check['points']} points")
    # the drive is wrong (the exercise's fault): the gain check cannot pass yet
    expect(row).to_have_attribute("data-state", "open")
    expect(row).to_contain_text("not yet")
    expect(row.get_by_test_id("check-detail")).not_to_be_empty()
    score = panel(p, "exercise-score")
    expect(score.get_by_test_id("exercise-progress")).to_have_text("0")
    expect(score).to_contain_text("of 1 checks")
    expect(score).to_contain_text(f"par {EXERCISE['par_time_s'] // 60}:00")
    # the fault is the student's to find: nothing on the screen names it
    body = p.locator("body").inner_text()
    assert "drive_gain_wrong" not in body and "0.4375" not in body

    hints = panel(p, "exercise-hints")
    first, second = EXERCISE["hints"]
    h1 = hints.get_by_test_id("hint-1")
    expect(h1.get_by_test_id("hint-text")).to_have_count(0)
    h1.get_by_role("button", name=f"Show hint (costs {first['cost']} points)").click()
    expect(h1).to_contain_text(f"Hint 1 takes {first['cost']} points off your score")
    h1.get_by_test_id("hint-cancel").click()  # thought better of it: nothing taken
    expect(h1.get_by_test_id("hint-text")).to_have_count(0)
    expect(score.get_by_test_id("exercise-hint-cost")).to_have_text("0")
    h1.get_by_test_id("hint-show").click()
    h1.get_by_test_id("hint-confirm").click()
    expect(h1.get_by_test_id("hint-text")).to_have_text(first["text"])
    expect(score.get_by_test_id("exercise-hint-cost")).to_have_text(f"−{first['cost']}")
    expect(score.get_by_test_id("exercise-score")).to_have_text("0")  # never below 0
    h2 = hints.get_by_test_id("hint-2")  # the other hint stays hidden
    expect(h2.get_by_test_id("hint-text")).to_have_count(0)
    expect(h2.get_by_test_id("hint-show")).to_have_text(
        f"Show hint (costs {second['cost']} points)"
    )

    shot(p, "exercise-desktop")
    p.set_viewport_size({"width": SIZES["tablet"][0], "height": SIZES["tablet"][1]})
    expect(h1.get_by_test_id("hint-text")).to_be_visible()
    shot(p, "exercise-tablet")
    h1.scroll_into_view_if_needed()  # the checks and hints, below the task on a small screen
    shot(p, "exercise-tablet-hints")


def test_a_broadcast_and_a_freeze_reach_the_student(
    student: Page, seat: dict[str, Any], trainer: httpx.Client, srv: Server
) -> None:
    p, cid, mid = student, seat["class"], seat["machine"]
    text = "Stop jogging and measure the lag first."
    assert trainer.post(f"/api/classes/{cid}/broadcast", json={"text": text}).status_code == 204
    message = p.locator("[data-testid=banner-notice][data-kind=message]")
    expect(message).to_contain_text(f"Message from {TRAINER}: {text}")

    p.get_by_test_id("open-machines").click()  # pacing is in the Machines dialog
    controls = p.get_by_test_id("panel-machines").get_by_test_id("machine-pacing")
    run = controls.get_by_role("button", name="▶ run")
    pause = controls.get_by_role("button", name="❚❚ pause")
    expect(run).to_have_attribute("aria-pressed", "true")
    r = trainer.post(f"/api/classes/{cid}/freeze", json={"frozen": True})
    assert r.status_code == 200, r.text
    frozen = p.get_by_test_id("banner-frozen")
    expect(frozen).to_contain_text("Frozen by the instructor — the machine is paused")
    expect(pause).to_have_attribute("aria-pressed", "true")
    expect(run).to_be_disabled()
    expect(run).to_have_attribute("title", re.compile("only the instructor can resume"))
    expect(controls.get_by_test_id("pace-reason")).to_have_text("Frozen by the instructor")
    assert srv.status(mid)["simulation"]["mode"] == "pause"
    shot(p, "exercise-frozen")
    p.get_by_test_id("machines-close").click()
    expect(p.get_by_label("reset and simulation").get_by_test_id("pace-reason")).to_be_visible()
    expect(message).to_be_visible()  # the message stays until dismissed

    # a message after the freeze, then a reload: the socket repeats only the newest notice,
    # the seat's exercise says it is still frozen
    trainer.post(f"/api/classes/{cid}/broadcast", json={"text": "Think it over."})
    expect(p.locator("[data-kind=message]")).to_have_count(2)
    p.reload()
    expect(p.get_by_test_id("banner-frozen")).to_be_visible()
    expect(p.locator("[data-kind=message]")).to_contain_text("Think it over.")

    assert trainer.post(f"/api/classes/{cid}/freeze", json={"frozen": False}).status_code == 200
    expect(p.get_by_test_id("banner-frozen")).to_have_count(0)
    expect(p.locator("[data-testid=banner-notice][data-kind=resumed]")).to_contain_text(
        f"{TRAINER} resumed the machine"
    )
    expect(p.get_by_label("reset and simulation").get_by_test_id("pace-reason")).to_have_count(0)
    p.get_by_test_id("open-machines").click()
    expect(run).to_have_attribute("aria-pressed", "true")
    expect(controls.get_by_test_id("pace-reason")).to_have_count(0)


def test_a_machine_that_is_no_seat_has_no_exercise_tab(
    browser: Browser, srv: Server, mid: str
) -> None:
    p = open_hmi(browser, srv.base, mid)
    try:
        expect(p.get_by_test_id("tab-Operate")).to_have_attribute("aria-selected", "true")
        expect(p.get_by_test_id("tab-Exercise")).to_have_count(0)
    finally:
        p.close()


def test_the_student_answers_a_finding_in_the_panel(
    browser: Browser, trainer: httpx.Client
) -> None:
    """find-backlash (the seat's own 15..45 µm of play on X): the answer is typed in µm; a
    wrong axis is graded wrong at once with an attempt gone, the right axis and size passes
    the check with its points, and the form goes."""
    cid = f"ex{next(_classes)}"
    r = trainer.post("/api/classes", json={"id": cid, "exercises": ["find-backlash"], "seats": 1})
    assert r.status_code == 201, r.text
    play_um = trainer.get(f"/api/classes/{cid}/seats/1").json()["values"]["faults[0].width"] * 1e3
    answer_um = round(play_um * 0.96, 1)
    w, h = SIZES["desktop"]
    context = browser.new_context(viewport={"width": w, "height": h})
    p = context.new_page()
    p.set_default_timeout(15_000)
    try:
        p.goto(r.json()["links"][0]["url"])
        row = panel(p, "exercise-checks").get_by_test_id("check-play")
        finding = row.get_by_test_id("finding")
        submit = finding.get_by_test_id("finding-submit")
        expect(submit).to_have_text("Answer (2 attempts left)")
        expect(submit).to_be_disabled()  # nothing typed yet
        finding.get_by_test_id("finding-axis").select_option("Z")
        finding.get_by_test_id("finding-value").fill("30")
        submit.click()
        answers = finding.get_by_test_id("finding-answers")
        expect(answers).to_contain_text("✗ Z 30.0 µm")
        expect(submit).to_have_text("Answer (1 attempt left)")
        expect(row).to_have_attribute("data-state", "open")
        shot(p, "exercise-finding-desktop")
        finding.get_by_test_id("finding-axis").select_option("X")
        finding.get_by_test_id("finding-value").fill(f"{answer_um}")
        submit.click()
        expect(answers).to_contain_text(f"✓ X {answer_um:.1f} µm")
        expect(answers).to_contain_text(f"X has {play_um:.1f} µm of backlash")
        expect(row).to_have_attribute("data-state", "passed")
        expect(finding.get_by_test_id("finding-submit")).to_have_count(0)
        score = panel(p, "exercise-score")
        expect(score.get_by_test_id("exercise-score")).to_have_text("100")
        p.set_viewport_size({"width": SIZES["tablet"][0], "height": SIZES["tablet"][1]})
        row.scroll_into_view_if_needed()
        shot(p, "exercise-finding-tablet")
    finally:
        context.close()
        trainer.post(f"/api/classes/{cid}/end")
