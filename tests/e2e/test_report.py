"""The commissioning report in the browser: multi_gain by experiment run in the Commissioning
workspace, the run listed in the Report panel, signed off, the report opened in a new tab (it
shows the run's figures and its lag plot) and its PDF downloaded.

The plant is made wrong as in test_assist.py: `sim.drive_gain` 22857 where the NC assumes
multi_gain 10000, so f = 2.2857 and k = 20 / 2.2857 1/s [004 §3.6.2].
"""

from __future__ import annotations

import json
import re

import pytest
from playwright.sync_api import Browser, Page, expect

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD, Server, add_users
from tests.e2e.browser import SIZES, open_hmi, panel, shot

OWN_SERVICE = True  # adds an observer

F_PHYSICS = 22857 / 10000
RUN_TIMEOUT_MS = 90_000  # a run is seconds of machine time in a process; generous on 2 cores


def test_run_sign_off_open_the_report_and_download_its_pdf(
    page: Page, srv: Server, wrong_drive: str
) -> None:
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "assist")
    box.get_by_test_id("assist-pick-multi-gain").check()
    box.get_by_test_id("assist-axis").select_option("X")
    box.get_by_test_id("assist-feed").fill("200")
    report = panel(page, "report")
    expect(report.get_by_test_id("report-no-runs")).to_be_visible()
    box.get_by_test_id("assist-run").click()
    expect(box.get_by_test_id("assist-result")).to_be_visible(timeout=RUN_TIMEOUT_MS)
    k_shown = float(box.get_by_test_id("assist-fig-k").inner_text().replace("−", "-"))

    # the run is listed (the panel follows without a reload) with its figures
    rows = report.get_by_test_id("report-runs").locator("tbody tr")
    expect(rows).to_have_count(1, timeout=10_000)
    expect(rows.first).to_contain_text("multi_gain by experiment")
    f_listed = re.search(r"f = ([\d.]+)", rows.first.inner_text())
    assert f_listed is not None and float(f_listed.group(1)) == pytest.approx(F_PHYSICS, rel=0.01)

    report.get_by_test_id("sign-name").fill("Erika Mustermann")
    report.get_by_test_id("sign-role").fill("commissioning engineer")
    report.get_by_test_id("sign-remark").fill("X: multi_gain corrected")
    report.get_by_test_id("sign-off").click()
    expect(report.get_by_test_id("report-signed")).to_contain_text("Erika Mustermann")
    report.scroll_into_view_if_needed()
    shot(page, "report-panel-desktop")

    with page.context.expect_page() as opened:
        report.get_by_test_id("report-open").click()
    doc = opened.value
    try:
        runs = doc.locator("section#runs")
        expect(runs.locator("article.run")).to_have_count(1)
        k_cell = runs.locator('tr[data-figure="k"] td.num')
        assert float(k_cell.inner_text()) == pytest.approx(k_shown, rel=1e-3)
        assert float(k_cell.inner_text()) == pytest.approx(20 / F_PHYSICS, rel=0.01)
        f_cell = runs.locator('tr[data-figure="f"] td.num')
        assert float(f_cell.inner_text()) == pytest.approx(F_PHYSICS, rel=0.01)
        plot = runs.locator("svg.plot polyline")
        expect(plot).to_have_count(1)
        assert len(plot.get_attribute("points").split()) > 100  # type: ignore[union-attr]
        expect(doc.locator("section#sign-off")).to_contain_text("Erika Mustermann")
        expect(doc.locator("section#machine")).to_contain_text(wrong_drive)
        for size, (w, h) in SIZES.items():
            doc.set_viewport_size({"width": w, "height": h})
            shot(doc, f"report-page-{size}")
        runs.scroll_into_view_if_needed()
        shot(doc, "report-page-run-tablet")
    finally:
        doc.close()

    with page.expect_download(timeout=90_000) as dl:
        report.get_by_test_id("report-pdf").click()
    download = dl.value
    assert download.suggested_filename == f"commissioning-report-{wrong_drive}.pdf"
    pdf = download.path().read_bytes()
    assert pdf.startswith(b"%PDF-") and len(re.findall(rb"/Type\s*/Page(?![a-zA-Z])", pdf)) >= 5
    page.set_viewport_size({"width": 1024, "height": 768})
    report.scroll_into_view_if_needed()
    shot(page, "report-panel-tablet")


def test_an_observer_opens_the_report_but_does_not_sign_off(
    browser: Browser, srv: Server, mid: str
) -> None:
    add_users(srv.db, {"olaf": Role.OBSERVER})
    p = open_hmi(browser, srv.base, mid, user="olaf", password=OTHERS_PASSWORD)
    try:
        p.get_by_test_id("tab-Commissioning").click()
        report = panel(p, "report")
        expect(report.get_by_test_id("sign-name")).to_be_disabled()
        expect(report.get_by_test_id("sign-off")).to_be_disabled()
        expect(report.get_by_test_id("sign-off")).to_have_attribute("title", re.compile("observer"))
        expect(report.get_by_test_id("report-open")).to_have_attribute(
            "href", f"/api/machines/{mid}/report"
        )
    finally:
        p.close()


def test_a_chosen_trace_goes_into_the_report(page: Page, srv: Server, mid: str) -> None:
    # a stored trace of this machine (a CSV whose description names it, as an export has)
    meta = {
        "id": "x", "machine": mid, "machine_name": mid, "name": "X lag ramp", "notes": "",
        "source": "capture", "stored": True, "trigger": "forced", "forced": True,
        "created_unix": 0, "first_cycle": 0, "trigger_cycle": None, "count": 300,
        "cycle_s": 0.001, "channels": [{"name": "X.lag_mm", "unit": "mm", "kind": "float"}],
        "params_changed": 0, "params": [], "events": [],
    }  # fmt: skip
    rows = "".join(f"{i},{i * 0.001}\n" for i in range(300))
    csv = f"# meta: {json.dumps(meta)}\ncycle,X.lag_mm [mm]\n{rows}"
    r = srv.http.post("/api/traces/import", content=csv, headers={"content-type": "text/csv"})
    assert r.status_code == 201, r.text
    tid = r.json()["id"]
    page.get_by_test_id("tab-Commissioning").click()
    report = panel(page, "report")
    report.get_by_test_id(f"report-trace-{tid}").check()
    link = report.get_by_test_id("report-open")
    expect(link).to_have_attribute("href", f"/api/machines/{mid}/report?trace={tid}")
    with page.context.expect_page() as opened:
        link.click()
    doc = opened.value
    try:
        trace = doc.locator(f'article[data-trace="{tid}"]')
        expect(trace).to_contain_text("X lag ramp")
        points = trace.locator("svg.plot polyline").get_attribute("points") or ""
        assert len(points.split()) == 300  # every stored sample
    finally:
        doc.close()
