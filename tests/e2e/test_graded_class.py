"""A graded class from start to debrief, in the browser: the instructor makes a class of a
two-exercise lesson plan for Anna, Ben and an empty third seat (on the roster); Anna passes
the first exercise and moves on by herself, the instructor moves Ben on; the service restarts
in the middle and the console says what the class kept; the class ends, Anna's debrief
replays what she did; the CSV and the printed grade list carry the scores they earned."""

from __future__ import annotations

import csv
import io
import re
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from playwright.sync_api import Browser, Page, expect
from pypdf import PdfReader

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD, Server, add_users, bearer
from tests.backend.test_graded_training import SOUND_X  # exercise 1: X follows its kv
from tests.e2e.browser import panel, shot, signed_in_page
from tests.e2e.test_class_console import student, tile

OWN_SERVICE = True  # restarts the service in the middle of the class

TRAINER = "trainer"
CLASS = "graded"


@pytest.fixture(scope="module")
def api(srv: Server) -> Iterator[httpx.Client]:
    """The instructor over the API: the exercise upload and the downloads."""
    tokens = add_users(srv.db, {TRAINER: Role.INSTRUCTOR})
    with httpx.Client(base_url=srv.base, headers=bearer(tokens[TRAINER]), timeout=60) as c:
        assert c.post("/api/exercises", json={"text": SOUND_X}).status_code == 201
        yield c


def _console(browser: Browser, srv: Server) -> Page:
    p = signed_in_page(browser, srv.base, user=TRAINER, password=OTHERS_PASSWORD)
    p.goto(f"{srv.base}/")
    p.get_by_test_id("open-classes").click()
    expect(p.get_by_test_id("console")).to_be_visible()
    return p


def _powered(srv: Server, api: httpx.Client, mid: str) -> None:
    """Wait for the seat's drives (its student's first command needs them)."""
    deadline = time.monotonic() + 30.0  # a safety net, no measure
    while time.monotonic() < deadline:
        if api.get(f"/api/machines/{mid}/status").json()["plc"]["drives_powered"]:
            return
        time.sleep(0.1)
    raise AssertionError(f"{mid}: drives never powered")


def test_a_graded_class_with_a_lesson_plan_a_restart_and_its_debrief(
    browser: Browser, srv: Server, api: httpx.Client
) -> None:
    c = _console(browser, srv)
    pages: list[Page] = [c]
    try:
        # the class: two exercises, three seats, two students on the roster
        c.get_by_test_id("class-new").click()
        form = panel(c, "class-create")
        form.get_by_test_id("class-exercise").select_option("sound-x")
        form.get_by_test_id("class-plan-add").click()
        form.get_by_test_id("class-plan-1").select_option("multi-gain")
        expect(form.get_by_test_id("exercise-info-1")).to_contain_text("each seat its own numbers")
        expect(form.get_by_test_id("exercise-info-1")).to_contain_text("locks the assistants")
        form.get_by_test_id("class-id").fill(CLASS)
        form.get_by_test_id("class-seats").fill("3")
        form.get_by_test_id("class-students").fill("Anna\nBen")
        form.get_by_test_id("class-roster").check()
        shot(c, "graded-create")
        form.get_by_test_id("class-create").click()
        links = panel(c, "seat-links")
        expect(links.get_by_test_id("link-url")).to_have_count(3, timeout=60_000)
        urls = [links.get_by_test_id("link-url").nth(i).input_value() for i in range(3)]
        links.get_by_test_id("links-done").click()
        info = api.get(f"/api/classes/{CLASS}").json()
        assert info["exercises"] == ["sound-x", "multi-gain"]
        mids = [s["machine"] for s in info["seats"]]

        anna, ben = student(browser, urls[0]), student(browser, urls[1])
        pages += [anna, ben]
        ex = panel(anna, "exercise")
        expect(ex).to_contain_text("Exercise 1 of 2: X follows")
        plan = panel(anna, "exercise-plan")
        expect(plan.get_by_test_id("plan-wait")).to_contain_text("Once every check has passed")

        # Anna passes exercise 1 with a move at constant feed, and moves on by herself
        _powered(srv, api, mids[0])
        anna.get_by_test_id("tab-Operate").click()
        mdi = panel(anna, "mdi")
        mdi.get_by_test_id("mdi-input").fill("G01 X130 F1000")
        mdi.get_by_test_id("mdi-send").click()
        anna.get_by_test_id("tab-Exercise").click()
        row = panel(anna, "exercise-checks").get_by_test_id("check-gain")
        expect(row).to_have_attribute("data-state", "passed", timeout=30_000)
        plan.get_by_test_id("plan-next").click()
        plan.get_by_test_id("plan-next-confirm").click()
        expect(ex).to_contain_text("Exercise 2 of 2: multi_gain by experiment")
        expect(plan.get_by_test_id("plan-list")).to_contain_text("X follows · 100 of 100 points")
        shot(anna, "graded-student-exercise-2")
        # the exercise locks the multi_gain assistant for her
        anna.get_by_test_id("tab-Commissioning").click()
        assist = panel(anna, "assist")
        assist.get_by_test_id("assist-pick-multi-gain").check()
        expect(assist.get_by_test_id("assist-locked")).to_contain_text("locks the multi_gain")
        expect(assist.get_by_test_id("assist-run")).to_be_disabled()

        # the grid: Anna at 2/2, Ben at 1/2, seat 3 not joined; the instructor moves Ben on
        grid = panel(c, "grid")
        expect(tile(c, 1).get_by_test_id("seat-stage")).to_have_text("2/2")
        expect(tile(c, 2).get_by_test_id("seat-stage")).to_have_text("1/2")
        expect(tile(c, 3).get_by_test_id("seat-mode")).to_have_text("not joined")
        tile(c, 2).get_by_test_id("seat-select").check()
        grid.get_by_test_id("grid-next").click()
        grid.get_by_test_id("grid-next-confirm").click()
        expect(tile(c, 2).get_by_test_id("seat-stage")).to_have_text("2/2")
        expect(panel(ben, "exercise")).to_contain_text("Exercise 2 of 2")
        # a snapshot of Anna's seat, then the service restarts
        r = api.post(f"/api/machines/{mids[0]}/snapshots", json={"label": "before the fix"})
        assert r.status_code == 201, r.text
        srv.stop()
        srv.start()
        resumed = c.get_by_test_id("class-resumed")
        c.reload()
        c.get_by_test_id(f"class-{CLASS}").click()
        # multi-gain's fault on seats 1 and 2, none in sound-x; each seat's start snapshot
        # and Anna's own: nothing lost
        expect(resumed).to_contain_text("3 seats built again with their 2 faults and 4 snapshots")
        shot(c, "graded-resumed")
        faults = api.get(f"/api/machines/{mids[0]}/faults").json()
        assert [f["fault"]["kind"] for f in faults] == ["drive_gain_wrong"]
        expect(tile(c, 1).get_by_test_id("seat-stage")).to_have_text("2/2")

        # the end and the debrief: Anna's exercise 1 replayed with her MDI line on it
        grid.get_by_test_id("class-end").click()
        grid.get_by_test_id("class-end-confirm").click()
        ended = panel(c, "ended-seats")
        ended.get_by_test_id("ended-seat-1").get_by_test_id("seat-detail").click()
        detail = panel(c, "seat-detail")
        expect(detail.get_by_test_id("detail-done")).to_contain_text("X follows")
        replay = detail.get_by_test_id("replay")
        replay.get_by_test_id("replay-stage").select_option("0")
        marks = replay.get_by_test_id("replay-marks")
        expect(marks).to_contain_text("G01 X130 F1000")
        replay.get_by_test_id("replay-what").select_option("speed")
        replay.get_by_test_id("replay-speed").select_option("60")
        replay.get_by_test_id("replay-play").click()
        expect(replay.get_by_test_id("replay-play")).to_have_text("▶ Play", timeout=30_000)
        expect(replay.locator("li.future")).to_have_count(0)  # played to the end
        shot(c, "graded-debrief-replay")

        # the results, against what each did: Anna 100 in exercise 1, Ben and seat 3 nothing
        rows = list(csv.DictReader(io.StringIO(api.get(f"/api/classes/{CLASS}/results.csv").text)))
        got = {(x["seat"], x["exercise"]): x for x in rows}
        assert sorted(got) == [(str(n), e) for n in (1, 2, 3) for e in ("multi-gain", "sound-x")]
        assert got[("3", "multi-gain")]["reached"] == "no"  # 0 of its 100: lines add up
        assert float(got[("1", "sound-x")]["sound-x.gain_points"]) == pytest.approx(100.0)
        assert float(got[("1", "multi-gain")]["score"]) == 0.0
        assert float(got[("2", "sound-x")]["score"]) == 0.0
        assert got[("3", "sound-x")]["joined_utc"] == ""
        pdf = api.get(f"/api/classes/{CLASS}/results.pdf")
        text = " ".join(page.extract_text() for page in PdfReader(io.BytesIO(pdf.content)).pages)
        assert "Exercise 1: X follows" in text and "Over the lesson plan" in text
        anna_row = _line_of(text, "Anna")
        assert "100.0 of 200" in anna_row, anna_row
        assert "0.0 of 200" in _line_of(text, "Ben")
        # the roster keeps Anna and Ben (seat 3 had no name)
        names = [p["name"] for p in api.get("/api/roster").json()]
        assert names == ["Anna", "Ben"]
    finally:
        for p in pages:
            p.close()


def _line_of(text: str, name: str) -> str:
    """The last line of the grade list naming `name` (the totals table comes last)."""
    lines: list[Any] = [line for line in text.splitlines() if name in line]
    assert lines, text
    return str(lines[-1])


def test_a_student_watches_the_machine_the_instructor_presents(
    browser: Browser, srv: Server, api: httpx.Client
) -> None:
    """The instructor presents the demo lathe from the grid: the student's strip offers it,
    they watch it with every command control off and go back to their seat; when the
    presentation stops the strip goes."""
    r = api.post("/api/classes", json={"id": "show", "exercises": ["sign-error"], "seats": 1})
    assert r.status_code == 201, r.text
    seat = r.json()["info"]["seats"][0]["machine"]
    c = _console(browser, srv)
    anna = student(browser, r.json()["links"][0]["url"])
    try:
        c.get_by_test_id("class-show").click()
        grid = panel(c, "grid")
        grid.get_by_test_id("grid-present-machine").select_option("demo")
        grid.get_by_test_id("grid-present").click()
        expect(grid.get_by_test_id("grid-presenting")).to_contain_text("presenting demo")
        strip = anna.get_by_test_id("present-strip")
        expect(strip).to_contain_text("Your instructor presents machine demo")
        strip.get_by_test_id("present-watch").click()
        expect(strip).to_contain_text("You are watching your instructor's machine demo")
        expect(anna.locator(".machine-select select")).to_have_value("demo")
        expect(anna.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
        expect(anna.get_by_test_id("tab-Exercise")).to_have_count(0)  # the lathe is no seat
        mdi = panel(anna, "mdi")
        expect(mdi.get_by_test_id("mdi-input")).to_be_disabled()
        expect(mdi.get_by_test_id("mdi-input")).to_have_attribute("title", re.compile("watching"))
        shot(anna, "graded-watching")
        strip.get_by_test_id("present-back").click()
        expect(anna.locator(".machine-select select")).to_have_value(seat)
        grid.get_by_test_id("grid-present-stop").click()
        expect(strip).to_have_count(0)
    finally:
        anna.close()
        c.close()
        api.post("/api/classes/show/end")


def test_an_instructor_writes_an_exercise_tries_it_and_saves_it(
    browser: Browser, srv: Server, api: httpx.Client
) -> None:
    """Exercises in the console: a shipped one opened as the start of a new one, its fault and
    mistuned start left out by mistake; the try-out on a copy says its 'stable' check passes
    with nobody at the machine; saved under its own id it is in the class form's list."""
    c = _console(browser, srv)
    try:
        c.get_by_test_id("exercises-open").click()
        ex = panel(c, "exercises")
        ex.get_by_test_id("exercise-open-soft-coupling").click()
        editor = ex.get_by_test_id("exercise-text")
        expect(editor).to_have_value(re.compile('id = "soft-coupling"'))
        text = editor.input_value()
        cut = text[: text.index("# what the autotune set")] + text[text.index("[[hints]]") :]
        editor.fill(cut.replace('id = "soft-coupling"', 'id = "soft-mine"'))
        ex.get_by_test_id("exercise-try-seconds").select_option("5")
        ex.get_by_test_id("exercise-try").click()
        dry = ex.get_by_test_id("exercise-dry-run")
        warnings = dry.get_by_test_id("dry-warnings")
        # the try-out computes on a copy (the grader's exact loop and its best bandwidth): a
        # few seconds of a core, longer beside other work
        expect(warnings).to_contain_text(
            "check 'stable' passes with nobody at the machine", timeout=60_000
        )
        expect(warnings).to_contain_text("no fault")
        shot(c, "exercise-authoring")
        ex.get_by_test_id("exercise-save").click()
        expect(ex.get_by_test_id("exercise-saved")).to_contain_text("saved as 'soft-mine'")
        expect(ex.get_by_test_id("exercise-open-soft-mine")).to_be_visible()
        # a wrong file: the refusal names the key
        editor.fill(cut.replace("points = 60", "pts = 60"))
        ex.get_by_test_id("exercise-try").click()
        expect(ex.get_by_test_id("exercise-refusal")).to_contain_text("checks[0].pts")
        c.get_by_test_id("class-new").click()
        form = panel(c, "class-create")
        form.get_by_test_id("class-exercise").select_option("soft-mine")
    finally:
        c.close()
        api.delete("/api/exercises/soft-mine")
