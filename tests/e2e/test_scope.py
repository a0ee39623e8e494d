"""The scope in the browser: arm a single trigger on M19 start, issue M19 from the UI, and the
capture appears with its trigger marker, cursors and measurements; save, import a CSV and
overlay it; open a capture in the bundled Rerun web viewer."""

from __future__ import annotations

import re
from pathlib import Path

from playwright.sync_api import Browser, Page, Request, expect

from tests.backend.server import Server
from tests.e2e.browser import commands_sent, number, open_hmi, panel, poll, shot, signed_in_page

LENGTH_S = 4.0
PRE_PCT = 25.0


def arm_on_m19(page: Page) -> None:
    page.get_by_test_id("tab-Scope").click()
    page.get_by_test_id("scope-length").fill(str(LENGTH_S))
    page.get_by_test_id("scope-pretrigger").fill(str(PRE_PCT))
    page.get_by_test_id("scope-mode").select_option("single")
    page.get_by_test_id("trigger-event").check()
    page.get_by_test_id("trigger-kind").select_option("m_start")
    page.get_by_test_id("trigger-axis").select_option("S1")
    page.get_by_test_id("trigger-m").select_option("19")
    page.get_by_test_id("scope-arm").click()
    state = page.get_by_test_id("scope-state")
    expect(state).to_have_attribute("data-state", "armed")
    expect(state).to_contain_text("history 100 %", timeout=10_000)  # the pre-trigger is there


def capture_m19(page: Page) -> str:
    arm_on_m19(page)
    page.get_by_test_id("tab-Operate").click()
    page.get_by_test_id("m19-angle").fill("90")
    page.get_by_test_id("m19").click()
    page.get_by_test_id("tab-Scope").click()
    view = page.get_by_test_id("capture-view")
    expect(view).to_be_visible(timeout=LENGTH_S * 1000 + 10_000)
    expect(page.get_by_test_id("scope-state")).to_have_attribute("data-state", "done")
    return str(view.get_attribute("data-trace"))


def test_single_trigger_on_m19_start_shows_the_capture_with_marker_and_measurements(
    browser: Browser, srv: Server, mid: str
) -> None:
    page = open_hmi(browser, srv.base, mid)
    tid = capture_m19(page)
    expect(page.get_by_test_id("capture-trigger")).to_have_text("M19 start on S1")
    # the pre-trigger asked for: 25 % of 4 s
    expect(page.get_by_test_id("capture-pre")).to_have_text(f"{LENGTH_S * PRE_PCT / 100:.3f} s")
    marker = page.get_by_test_id("trigger-marker")
    expect(marker).to_be_visible()
    assert marker.get_attribute("data-t") == "0"
    # the marker sits a quarter of the way across the plotting area (whole record shown)
    chart = page.get_by_test_id("capture-chart").locator(".u-over").bounding_box()
    m = marker.bounding_box()
    assert chart is not None and m is not None
    assert abs((m["x"] - chart["x"]) / chart["width"] - PRE_PCT / 100) < 0.01

    # the trigger is the first cycle in POSITIONING, as the server's record says
    detail = srv.http.get(f"/api/traces/{tid}").json()
    assert detail["first_cycle"] == detail["trigger_cycle"] - round(LENGTH_S * PRE_PCT * 10)

    # measurements of the spindle position: it ends at 90° (kenngr.exact_stop_window 0.1°)
    page.get_by_test_id("meas-channel").select_option("S1.pos_act_deg")
    expect(page.get_by_test_id("meas-final")).to_contain_text("deg")
    final = float(page.get_by_test_id("meas-final").inner_text().split()[0].replace("−", "-"))
    assert abs(final % 360 - 90) <= 0.1
    page.get_by_test_id("meas-channel").select_option("S1.lag_deg")
    expect(page.get_by_test_id("meas-max-abs")).not_to_have_text("—")

    # two cursors: Δt is B − A as read at the cursors
    box = chart
    page.mouse.click(box["x"] + box["width"] * 0.3, box["y"] + box["height"] / 2)
    page.keyboard.down("Shift")
    page.mouse.click(box["x"] + box["width"] * 0.6, box["y"] + box["height"] / 2)
    page.keyboard.up("Shift")
    expect(page.get_by_test_id("cursor-b")).to_be_visible()
    ta, tb = number(page, "cursor-a-t"), number(page, "cursor-b-t")
    assert abs((tb - ta) - 0.3 * LENGTH_S) < 0.02
    dt_ms = float(page.get_by_test_id("cursor-dt").inner_text().split()[0])
    assert abs(dt_ms - (tb - ta) * 1000) < 0.11

    # the measurement window starts at the sample at cursor A: within one cycle (1 ms) of it
    def window_start() -> float:
        return float(page.get_by_test_id("meas-window").inner_text().split()[0].replace("−", "-"))

    poll(lambda: abs(window_start() - ta) <= 0.0011, "the measurement window at cursor A")
    # the record's events: M19 is raised after the cycle before the trigger, which is the
    # first cycle under M19
    page.get_by_test_id("capture-events").locator("summary").click()
    expect(page.get_by_test_id("capture-events")).to_contain_text("M19 S.POS=90")
    expect(
        page.get_by_test_id("capture-events").locator("tr", has_text="M19 S.POS")
    ).to_contain_text("−0.001 s")
    shot(page, "scope-m19-desktop")
    page.close()


def test_save_import_csv_and_overlay(
    browser: Browser, srv: Server, tmp_path: Path, mid: str
) -> None:
    page = open_hmi(browser, srv.base, mid)
    tid = capture_m19(page)
    page.get_by_test_id("save-name").fill("M19 kv default")
    page.get_by_test_id("save-trace").click()
    row = page.get_by_test_id(f"trace-{tid}")
    expect(row).to_contain_text("M19 kv default")

    csv = tmp_path / "m19-before.csv"
    csv.write_text(srv.http.get(f"/api/traces/{tid}/csv").text)
    page.get_by_test_id("trace-import").set_input_files(str(csv))
    # scoped to the library: the chart's legend rows name the overlay too
    imported = page.get_by_test_id("panel-trace-library").locator("tr", has_text="m19-before")
    expect(imported).to_be_visible()
    compare = page.get_by_test_id("compare")
    expect(compare).to_contain_text("m19-before")
    expect(compare).to_contain_text("same parameters")
    legend = page.get_by_test_id("capture-chart").locator(".u-legend")
    expect(legend).to_contain_text("m19-before: S1.pos_act_deg")
    # the overlay measured alike, side by side: the same capture, so the same figures
    meas = page.get_by_test_id("measurements")
    expect(meas.get_by_test_id("meas-head-overlay")).to_contain_text("m19-before")
    expect(meas.get_by_test_id("meas-overlay-final")).not_to_have_text("—")
    expect(meas.get_by_test_id("meas-overlay-final")).to_have_text(
        meas.get_by_test_id("meas-final").inner_text()
    )
    shot(page, "scope-overlay-desktop")
    page.close()


def test_rerun_viewer_page_for_a_capture_loads(browser: Browser, srv: Server, mid: str) -> None:
    page = open_hmi(browser, srv.base, mid)
    tid = capture_m19(page)
    viewer = signed_in_page(browser, srv.base)
    viewer.set_viewport_size({"width": 1280, "height": 800})
    elsewhere: list[str] = []  # requests for other hosts, and why they failed

    def failed(r: Request) -> None:
        if not r.url.startswith(srv.base):
            elsewhere.append(f"{r.url} {r.failure}")

    viewer.on("requestfailed", failed)
    slow = 60_000  # a 43 MB wasm, compiled in a software-rendering browser
    with (
        viewer.expect_response(lambda r: r.url.endswith(".wasm"), timeout=slow) as wasm,
        viewer.expect_response(lambda r: "/trace.rrd?ticket=" in r.url, timeout=slow) as rrd,
    ):
        viewer.goto(f"{srv.base}/api/traces/{tid}/viewer", timeout=slow)
    assert viewer.url.startswith(f"{srv.base}/rerun/?")
    assert wasm.value.status == 200  # the viewer itself, through the service
    assert rrd.value.status == 200 and tid in rrd.value.url  # it loaded the capture
    expect(viewer.locator("canvas")).to_be_attached()
    # web fonts (and usage telemetry, once the viewer asks) are stopped by our CSP
    assert elsewhere and all(e.endswith(" csp") for e in elsewhere), elsewhere
    shot(viewer, "rerun-viewer")
    viewer.close()
    page.close()


def test_roll_mode_runs_free_and_a_capture_fits_a_tablet(
    browser: Browser, srv: Server, mid: str
) -> None:
    page = open_hmi(browser, srv.base, mid, "tablet")
    page.get_by_test_id("tab-Scope").click()
    page.get_by_test_id("scope-mode").select_option("roll")
    page.get_by_test_id("scope-length").fill("2")
    page.get_by_test_id("scope-arm").click()
    expect(page.get_by_test_id("scope-state")).to_have_attribute("data-state", "roll")
    chart = page.get_by_test_id("roll-chart")
    expect(chart).to_be_visible()
    # the window reaches back one record length from the newest sample, and moves on
    info = page.get_by_test_id("roll-info")
    expect(info).to_have_attribute("data-span-s", re.compile(r"^1\.99"))
    first = int(info.get_attribute("data-last-cycle") or 0)
    expect(info).not_to_have_attribute("data-last-cycle", str(first))
    assert int(info.get_attribute("data-last-cycle") or 0) > first
    page.get_by_test_id("scope-stop").click()
    expect(page.get_by_test_id("scope-state")).to_have_attribute("data-state", "idle")
    capture_m19(page)
    page.get_by_test_id("capture-view").scroll_into_view_if_needed()
    overflow = page.evaluate("document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 0
    shot(page, "scope-capture-tablet")
    page.close()


def test_one_y_axis_per_unit_booleans_as_lanes_and_commands_from_the_scope(
    browser: Browser, srv: Server, mid: str
) -> None:
    """rpm, degrees and a boolean in one capture: two y axes (rpm, deg) and a digital lane; the
    signal picker opens below Arm, and M3 from the scope's own command strip triggers it."""
    page = open_hmi(browser, srv.base, mid)
    page.get_by_test_id("tab-Scope").click()
    setup = panel(page, "scope-setup")
    picker = setup.get_by_test_id("scope-channels")
    picker.locator("summary").click()
    for name in ("S1.speed_cmd_rpm", "S1.lag_deg"):  # the default set keeps two rpm, two deg
        picker.locator(f'input[data-signal="{name}"]').uncheck()
    picker.locator('input[data-signal="S1.speed_reached"]').check()
    body = picker.locator(".picker-body").bounding_box()
    arm_box = setup.get_by_test_id("scope-arm").bounding_box()
    assert body is not None and arm_box is not None
    assert arm_box["y"] + arm_box["height"] <= body["y"], "the open picker covers Arm"
    picker.locator("summary").click()
    setup.get_by_test_id("scope-length").fill("1.5")
    setup.get_by_test_id("trigger-event").check()
    setup.get_by_test_id("trigger-kind").select_option("m_start")
    setup.get_by_test_id("trigger-axis").select_option("S1")
    setup.get_by_test_id("trigger-m").select_option("3")
    setup.get_by_test_id("scope-arm").click()
    expect(setup.get_by_test_id("scope-state")).to_contain_text("history 100 %", timeout=10_000)

    strip = panel(page, "scope-commands")
    sent = commands_sent(page)
    strip.get_by_test_id("s-input").fill("1000")
    strip.get_by_test_id("m3").click()
    chart = panel(page, "capture").get_by_test_id("capture-chart")
    expect(chart).to_be_visible(timeout=15_000)
    assert any('"m":3' in s for s in sent)
    # channels in their picker order: rpm first (left), deg (right), the boolean as a lane
    expect(chart).to_have_attribute("data-y-units", "rpm|deg")
    expect(chart).to_have_attribute("data-lanes", "S1.speed_reached")
    # uPlot's axes: time, rpm, deg and the lanes' labels
    expect(chart.locator(".u-axis")).to_have_count(4)
    # the lane reads 0/1 at the cursor, never the drawn level
    legend = chart.locator(".u-legend")
    expect(legend).to_contain_text("S1.speed_reached")
    shot(page, "scope-axes-desktop")
    page.set_viewport_size({"width": 1024, "height": 768})
    expect(chart.locator(".u-axis")).to_have_count(4)
    chart.scroll_into_view_if_needed()
    overflow = page.evaluate("document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 0
    shot(page, "scope-axes-tablet")
    page.close()


def test_a_drive_rate_capture_of_x_while_it_jogs(browser: Browser, srv: Server, mid: str) -> None:
    """The Scope's drive rate: X's drive signals every 125 µs around a level trigger on the
    NC's feed; X jogs at 1000 mm/min (10 mm per motor revolution: the motor ends at 100 rpm)."""
    page = open_hmi(browser, srv.base, mid)
    page.get_by_test_id("tab-Scope").click()
    setup = panel(page, "scope-setup")
    setup.get_by_test_id("scope-rate").select_option("drive")
    setup.get_by_test_id("scope-channels").locator("summary").click()
    setup.locator('[data-signal="X.drive.speed_motor_rpm"]').check(force=True)  # already chosen
    expect(setup.locator('[data-signal="X.lag_mm"]')).to_have_count(0)  # NC signals not offered
    setup.get_by_test_id("scope-channels").locator("summary").click()
    setup.get_by_test_id("scope-length").fill("0.5")
    setup.get_by_test_id("scope-pretrigger").fill("20")
    setup.get_by_test_id("trigger-level").check()
    # a trigger is the NC's: the level trigger offers X's NC signals, the first by default
    expect(setup.get_by_test_id("trigger-signal")).to_have_value("X.pos_cmd_mm")
    setup.get_by_test_id("trigger-signal").select_option("X.vel_cmd_mm_min")
    setup.get_by_test_id("trigger-value").fill("50")
    setup.get_by_test_id("scope-arm").click()
    expect(setup.get_by_test_id("scope-state")).to_contain_text("every drive step")
    expect(setup.get_by_test_id("scope-state")).to_contain_text("history 100 %", timeout=10_000)
    jog = {"type": "jog", "axis": "X", "action": "start", "direction": 1, "feed_mm_min": 1000}
    assert srv.command(mid, {**jog, "hold_s": 2}).status_code == 200
    view = page.get_by_test_id("capture-view")
    expect(view).to_be_visible(timeout=10_000)
    tid = str(view.get_attribute("data-trace"))
    detail = srv.http.get(f"/api/traces/{tid}").json()
    assert detail["cycle_s"] == 125e-6 and detail["count"] == 4000
    # 20 % of 0.5 s and the first NC cycle's steps before the NC's first sample
    expect(page.get_by_test_id("capture-pre")).to_have_text("0.101 s")
    page.get_by_test_id("meas-channel").select_option("X.drive.speed_motor_rpm")
    final = float(page.get_by_test_id("meas-final").inner_text().split()[0].replace("−", "-"))
    assert abs(final - 100.0) < 0.5
    shot(page, "scope-drive-rate-desktop")
    page.set_viewport_size({"width": 1024, "height": 768})
    shot(page, "scope-drive-rate-1024")
    page.close()
