"""Issue 20: an accessibility pass. axe-core (pinned in frontend/package.json) checks every
workspace, the Machines and Account dialogs, the instructor console and a student's exercise
against WCAG 2 A/AA: no "serious" or "critical" violation. And the Operate workspace works from
the keyboard alone: Tab reaches the workspace tabs, the jog keys, the spindle's S field and M3,
and the MDI line; the tabs follow the WAI-ARIA tab pattern (arrow keys, Enter and Space)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, expect

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD, Server, add_users
from tests.e2e.browser import WORKSPACES, open_hmi, panel, signed_in_page

OWN_SERVICE = True  # adds an instructor and runs a class

AXE = Path(__file__).resolve().parents[2] / "frontend" / "node_modules" / "axe-core" / "axe.min.js"
TRAINER = "trainer"


@pytest.fixture(scope="module", autouse=True)
def instructor(srv: Server) -> None:
    add_users(srv.db, {TRAINER: Role.INSTRUCTOR})


def axe_problems(page: Page, where: str) -> list[str]:
    """The serious and critical WCAG 2 A/AA violations axe finds on the page as it is, one
    readable line per element."""
    if not page.evaluate("() => typeof window.axe !== 'undefined'"):
        # evaluated through the DevTools protocol: the HMI's CSP allows no inline script tag
        page.evaluate(AXE.read_text())
    result: dict[str, Any] = page.evaluate(
        "() => axe.run(document, { runOnly: { type: 'tag', values: ['wcag2a', 'wcag2aa'] },"
        " resultTypes: ['violations'] })"
    )
    lines = []
    for v in result["violations"]:
        if v["impact"] not in ("serious", "critical"):
            continue
        for node in v["nodes"][:8]:
            lines.append(
                f"{where}: [{v['impact']}] {v['id']}: {v['help']}\n    at {node['target']}: "
                f"{node['html'][:160]}\n    {node.get('failureSummary', '')[:300]}"
            )
    return lines


def test_no_serious_axe_violations_anywhere(browser: Browser, srv: Server, mid: str) -> None:
    problems: list[str] = []
    page = open_hmi(browser, srv.base, mid)
    try:
        for name in WORKSPACES:
            page.get_by_test_id(f"tab-{name}").click()
            expect(page.get_by_role("tabpanel")).to_have_attribute(
                "aria-labelledby", page.get_by_test_id(f"tab-{name}").get_attribute("id") or "?"
            )
            page.wait_for_timeout(300)
            problems += axe_problems(page, name)
        page.get_by_test_id("open-machines").click()
        expect(page.get_by_test_id("machines-close")).to_be_visible()
        problems += axe_problems(page, "Machines dialog")
        page.get_by_test_id("machines-close").click()
        page.get_by_test_id("account-open").click()
        expect(page.get_by_test_id("account-close")).to_be_visible()
        problems += axe_problems(page, "Account dialog")
        page.get_by_test_id("account-close").click()
    finally:
        page.close()
    # the instructor's console with a class of one seat, and that seat's student
    console = signed_in_page(browser, srv.base, user=TRAINER, password=OTHERS_PASSWORD)
    try:
        console.goto(f"{srv.base}/")
        expect(console.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
        console.get_by_test_id("open-classes").click()
        expect(console.get_by_test_id("console")).to_be_visible()
        console.get_by_test_id("class-new").click()
        form = panel(console, "class-create")
        expect(form.get_by_test_id("class-exercise")).to_be_visible()
        problems += axe_problems(console, "Classes: new class")
        form.get_by_test_id("class-exercise").select_option("multi-gain")
        form.get_by_test_id("class-id").fill("a11y")
        form.get_by_test_id("class-seats").fill("1")
        form.get_by_test_id("class-create").click()
        links = panel(console, "seat-links")
        expect(links).to_contain_text("Shown this once", timeout=60_000)
        url = links.get_by_test_id("seat-link-1").get_by_test_id("link-url").input_value()
        problems += axe_problems(console, "Classes: seat links")
        links.get_by_test_id("links-done").click()
        expect(panel(console, "grid")).to_be_visible()
        problems += axe_problems(console, "Classes: grid")
        student = browser.new_context(viewport={"width": 1920, "height": 1080})
        try:
            sp = student.new_page()
            sp.goto(url)
            expect(sp.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
            expect(sp.get_by_test_id("tab-Exercise")).to_have_attribute("aria-selected", "true")
            sp.wait_for_timeout(300)
            problems += axe_problems(sp, "student: Exercise")
        finally:
            student.close()
    finally:
        console.close()
    # one line per rule and element, where it was seen first (the head is on every page)
    unique = list({p.split(": ", 1)[1]: p for p in reversed(problems)}.values())[::-1]
    assert not unique, "axe found serious or critical violations:\n" + "\n".join(unique)


@pytest.fixture
def operate(browser: Browser, srv: Server, mid: str) -> Iterator[Page]:
    p = open_hmi(browser, srv.base, mid)
    yield p
    p.close()


def tab_until(page: Page, test_id: str, limit: int = 200) -> list[str]:
    """Press Tab until the element with `test_id` has the focus; the test ids passed on the
    way. Fails if it is not reached."""
    seen: list[str] = []
    for _ in range(limit):
        page.keyboard.press("Tab")
        focused = page.evaluate(
            "() => { const e = document.activeElement;"
            " return e?.getAttribute('data-testid') ?? e?.tagName; }"
        )
        seen.append(str(focused))
        if focused == test_id:
            # a visible focus mark: the focus-visible outline
            outline = page.evaluate("() => getComputedStyle(document.activeElement).outlineStyle")
            assert outline not in ("none", ""), f"{test_id} has the focus but no outline"
            return seen
    raise AssertionError(f"Tab never reached {test_id}; passed {seen}")


def test_the_operate_workspace_by_keyboard(operate: Page) -> None:
    page = operate
    page.locator("body").click(position={"x": 5, "y": 300})  # start from the page, not an input
    page.keyboard.press("Home")
    passed = tab_until(page, "tab-Operate")
    # one tab stop for the whole tab list (the selected tab): the others are reached by arrows
    assert "tab-Program" not in passed
    page.keyboard.press("ArrowRight")
    expect(page.get_by_test_id("tab-Program")).to_be_focused()
    expect(page.get_by_test_id("tab-Program")).to_have_attribute("aria-selected", "true")
    expect(panel(page, "program")).to_be_visible()
    page.keyboard.press("End")
    expect(page.get_by_test_id("tab-Fleet")).to_be_focused()
    page.keyboard.press("ArrowRight")  # wraps round to the first
    expect(page.get_by_test_id("tab-Operate")).to_be_focused()
    expect(page.get_by_test_id("tab-Operate")).to_have_attribute("aria-selected", "true")
    # Enter and Space activate a tab as they do a button
    page.keyboard.press("ArrowLeft")
    page.keyboard.press("Home")
    expect(page.get_by_test_id("tab-Operate")).to_be_focused()
    page.get_by_test_id("tab-Scope").focus()
    page.keyboard.press("Enter")
    expect(page.get_by_test_id("tab-Scope")).to_have_attribute("aria-selected", "true")
    page.get_by_test_id("tab-Operate").focus()
    page.keyboard.press("Space")
    expect(page.get_by_test_id("tab-Operate")).to_have_attribute("aria-selected", "true")
    # from the tab on into the workspace: the spindle's S and M3, the jog keys, the MDI line
    page.get_by_test_id("tab-Operate").focus()
    tab_until(page, "s-input")
    tab_until(page, "m3")
    jog = panel(page, "jog")
    minus = jog.locator(".jogkey").first.get_attribute("data-testid")
    assert minus
    tab_until(page, minus)
    tab_until(page, "mdi-input")
