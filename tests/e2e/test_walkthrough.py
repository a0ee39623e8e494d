"""The user guide's commissioning walkthrough on the demo lathe (docs/user-guide.md), done in
the browser as written: baseline, sign check, multi_gain by experiment on the machine itself,
Apply and check again, the gear ranges, a version, the report signed off. Its screenshots are
the guide's (tests/e2e/screenshots/walkthrough-*.png, copied to docs/walkthrough/).

The X drive is made wrong as the walkthrough asks (`sim.drive_gain` 22857 digits per 1 m/min
where the NC assumes 10000): f = 2.2857 [004 §3.6.2], and after Apply k equals kv (f = 1).
"""

from __future__ import annotations

import pytest
from playwright.sync_api import Locator, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import SHOTS, panel
from tests.e2e.plant import DRIVE_GAIN, MULTI_GAIN
from tests.e2e.test_assist import RUN_TIMEOUT_MS, read


def _shot(part: Locator, name: str) -> None:
    """A panel alone: the user guide shows what the step is about."""
    SHOTS.mkdir(exist_ok=True)
    part.scroll_into_view_if_needed()
    part.screenshot(path=str(SHOTS / f"walkthrough-{name}.png"))


def test_the_readme_walkthrough(page: Page, srv: Server, wrong_drive: str) -> None:
    # 1. the baseline: the parameters as commissioning starts
    page.get_by_test_id("tab-Parameters").click()
    page.get_by_test_id("param-view-versions").click()
    versions = panel(page, "versions")
    versions.get_by_test_id("baseline-now").click()
    expect(versions.get_by_test_id("baseline-tag")).to_be_visible()

    # 2. the signs [004 §3.5], previewed on a copy
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "assist")
    box.get_by_test_id("assist-pick-sign-check").check()
    box.get_by_test_id("assist-axis").select_option("X")
    box.get_by_test_id("assist-run").click()
    expect(box.get_by_test_id("assist-verdict")).to_have_text(
        "✓ signs right", timeout=RUN_TIMEOUT_MS
    )
    _shot(box, "1-sign-check")

    # 3. multi_gain by experiment [004 §3.6.2] on the machine itself, the motion confirmed
    box.get_by_test_id("assist-pick-multi-gain").check()
    box.get_by_test_id("assist-feed").fill("200")
    box.get_by_test_id("assist-run-live").click()
    expect(box.get_by_test_id("assist-confirm")).to_contain_text("X moves at 200 mm/min")
    _shot(box, "2-confirm")
    box.get_by_test_id("assist-confirm-live").click()
    expect(box.get_by_test_id("assist-result")).to_be_visible(timeout=RUN_TIMEOUT_MS)
    assert read(box, "assist-fig-f") == pytest.approx(DRIVE_GAIN / MULTI_GAIN, rel=0.01)
    _shot(box, "3-multi-gain")

    # 4. Apply on trial, check again: k equals kv, then Keep
    box.get_by_test_id("assist-apply").click()
    expect(page.get_by_test_id("param-trial")).to_contain_text("getriebe[0].multi_gain_z")
    box.get_by_test_id("assist-run").click()
    expect(box.get_by_test_id("assist-check")).to_have_attribute(
        "data-ok", "1", timeout=RUN_TIMEOUT_MS
    )
    assert read(box, "assist-fig-f") == pytest.approx(1.0, abs=0.01)
    page.get_by_test_id("param-keep").click()

    # 5. the gear ranges [000 §2.8.2]: which stage M40 selects for S
    calc = panel(page, "calc")
    calc.get_by_test_id("calc-pick-gear-ranges").click()
    calc.get_by_test_id("gear-s").fill("650 750 950 3900")
    expect(calc.get_by_test_id("gear-steps")).to_contain_text("S3900")
    _shot(calc, "4-gear-ranges")

    # 6. a version, compared with the baseline
    page.get_by_test_id("tab-Parameters").click()
    page.get_by_test_id("param-view-versions").click()
    versions.get_by_test_id("version-name").fill("X multi_gain corrected")
    versions.get_by_test_id("version-take").click()
    versions.get_by_test_id("diff-from").select_option(value="baseline")
    versions.get_by_test_id("diff-to").select_option(value="live")
    expect(versions.get_by_test_id("diff-table")).to_contain_text("getriebe[0].multi_gain_z")
    _shot(versions, "5-versions")

    # 7. the report, signed off
    page.get_by_test_id("tab-Commissioning").click()
    report = panel(page, "report")
    rows = report.get_by_test_id("report-runs").locator("tbody tr")
    expect(rows).to_have_count(3, timeout=10_000)  # sign check, on the machine, the check
    report.get_by_test_id("sign-name").fill("Erika Mustermann")
    report.get_by_test_id("sign-role").fill("commissioning engineer")
    report.get_by_test_id("sign-remark").fill("X: signs right, multi_gain corrected (f = 2.286)")
    report.get_by_test_id("sign-off").click()
    expect(report.get_by_test_id("report-signed")).to_contain_text("Erika Mustermann")
    _shot(report, "6-report-panel")
    with page.context.expect_page() as opened:
        report.get_by_test_id("report-open").click()
    doc = opened.value
    try:
        doc.set_viewport_size({"width": 1100, "height": 1400})
        expect(doc.locator("section#runs article.run")).to_have_count(3)
        expect(doc.locator("section#sign-off")).to_contain_text("Erika Mustermann")
        doc.screenshot(path=str(SHOTS / "walkthrough-7-report.png"))
    finally:
        doc.close()
