"""The HMI in headless Chromium against the real service, driven through the UI only.

The machine runs in real time; the tests wait for states and judge values against the
manuals and physics (speeds, gear ranges, lag = v/kv), never against wall-clock speed.
"""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Page, expect

from tests.backend.server import Server
from tests.e2e.browser import number, panel, poll, shot

# The demo's gear range table is the manual's example [000 §2.8.2], rpm per stage M40..M45.
GEAR_RANGES = [(50, 560), (400, 800), (700, 3500), (3501, 4000), (3800, 5500), (5400, 7000)]
KV_X = 20.0  # 1/s: getriebe[0].kv 2000 in 0.01/s


def latest(page: Page, signal: str) -> float:
    return number(page, f"latest-{signal}")


def mdi(page: Page, block: str) -> None:
    page.get_by_test_id("mdi-input").fill(block)
    page.get_by_test_id("mdi-send").click()


def test_m3_speed_rises_to_s_and_m5_stops(page: Page) -> None:
    page.get_by_test_id("s-input").fill("1000")
    page.get_by_test_id("m3").click()
    reached = page.get_by_test_id("lamp-speed-reached-S1")
    expect(reached).to_have_attribute("data-on", "1")
    # the plot's actual-speed trace has risen to the programmed 1000 rpm
    poll(lambda: abs(latest(page, "S1.speed_act_rpm") - 1000) < 1.0, "plot at 1000 rpm")
    assert latest(page, "S1.speed_cmd_rpm") == pytest.approx(1000, abs=1e-6)
    assert page.get_by_test_id("lamp-stopped-S1").get_attribute("data-on") == "0"
    shot(page, "spindle-running-desktop")
    page.get_by_test_id("m5").click()
    expect(page.get_by_test_id("lamp-stopped-S1")).to_have_attribute("data-on", "1")
    assert reached.get_attribute("data-on") == "0"
    # "stopped" comes below vb_min_null (1 rpm) and, against encoder ripple, drops back only
    # beyond it by the speed filter's resolution, so a lone count while creeping to rest may
    # still read ~2 rpm; the settled loop then rests at exactly 0
    poll(lambda: number(page, "vact-S1") == 0.0, "S1 at rest")


def _per_frame(page: Page, frames: int) -> tuple[float, float]:
    """Live-plot draws and simulated seconds of samples per telemetry frame over the next
    `frames` frames."""
    now = "[inbetrieb.fps.draws, inbetrieb.frames.received, inbetrieb.rings().lastTime]"
    before = page.evaluate(now)
    poll(
        lambda: page.evaluate("inbetrieb.frames.received") >= before[1] + frames,
        f"{frames} telemetry frames",
    )
    after = page.evaluate(now)
    n = float(after[1] - before[1])
    return (after[0] - before[0]) / n, (after[2] - before[2]) / n


def test_the_plot_refresh_is_chosen_kept_and_draws_that_often(
    page: Page, srv: Server, mid: str
) -> None:
    """50/s draws every telemetry frame (one every 20 ms); at 10/s the page asks for a frame
    every 100 ms, each with five times the samples, and draws each, still showing the newest
    samples; the choice survives a reload."""
    plot = panel(page, "plot")
    rate = plot.get_by_test_id("plot-rate")
    rate.select_option("50")
    page.get_by_test_id("s-input").fill("600")
    page.get_by_test_id("m3").click()
    draws_50, span_50 = _per_frame(page, 100)  # about 2 s
    rate.select_option("10")
    _per_frame(page, 2)  # the frames of the new period from here on
    draws_10, span_10 = _per_frame(page, 20)  # about 2 s
    # a draw for (nearly) every frame: a page drawing at 10/s whatever was chosen would draw
    # 0.2 per frame at 50/s; a Chromium sharing two cores with the rest of the suite skipped
    # up to 45 % of the 20 ms frames (0.55), so more than 0.4 counts
    assert draws_50 > 0.4 and draws_10 > 0.6, (draws_50, draws_10)
    assert span_10 > 2.5 * span_50, (span_10, span_50)  # 0.1 s of samples a frame, not 0.02
    # still the newest samples: the speed the machine reports now (its status, over REST),
    # about 600 rpm; the measured speed steps by 2.4 rpm there (598.1 or 600.6 for seconds)
    poll(
        lambda: (
            abs((shown := latest(page, "S1.speed_act_rpm")) - srv.axis("S1", mid)["vel_act"]) < 1.0
            and abs(shown - 600) < 2.5
        ),
        "the plot at the machine's speed",
    )
    page.reload()
    expect(panel(page, "plot").get_by_test_id("plot-rate")).to_have_value("10")


def test_m19_orients_to_90_degrees_within_the_window(page: Page, srv: Server, mid: str) -> None:
    window_deg = 1e-4 * float(  # kenngr.exact_stop_window in 0.1 µ°
        next(
            p["value"]
            for p in srv.http.get(f"/api/machines/{mid}/parameters?target=S1").json()
            if p["name"] == "kenngr.exact_stop_window"
        )
    )
    page.get_by_test_id("m19-angle").fill("90")
    page.get_by_test_id("m19").click()
    expect(page.get_by_test_id("lamp-in-position-S1")).to_have_attribute("data-on", "1")
    poll(lambda: page.get_by_test_id("state-S1").inner_text() == "STANDSTILL", "M19 done")
    pos = number(page, "pos-S1") % 360.0
    assert abs(pos - 90.0) <= window_deg + 0.005  # the readout shows two decimals
    shot(page, "spindle-m19-desktop")


def test_s950_selects_the_gear_stage_that_holds_it(page: Page) -> None:
    def stage_for(rpm: float) -> int:  # automatic selection, range_way 0: bottom-up
        return next(g for g, (lo, hi) in enumerate(GEAR_RANGES, 1) if lo <= rpm <= hi)

    page.get_by_test_id("s-input").fill("300")
    page.get_by_test_id("m3").click()
    expect(page.get_by_test_id("spindle-gear")).to_have_text(f"M{39 + stage_for(300)}")
    page.get_by_test_id("s-input").fill("950")
    page.get_by_test_id("m3").click()
    g = stage_for(950)
    expect(page.get_by_test_id("spindle-gear")).to_have_text(f"M{39 + g}")
    expect(page.get_by_test_id(f"gear-bar-{g}")).to_have_attribute("data-active", "1")
    expect(page.get_by_test_id("gear-mark")).to_have_attribute("data-rpm", "950")
    assert page.get_by_test_id(f"gear-bar-{g}").get_attribute("data-holds") == "1"
    assert page.get_by_test_id("gear-bar-1").get_attribute("data-holds") == "0"
    shot(page, "spindle-gears-desktop")
    page.get_by_test_id("m5").click()


def test_kv_apply_changes_the_lag_and_revert_restores_it(page: Page) -> None:
    feed_mm_min = 600.0
    v = feed_mm_min / 60.0
    mdi(page, f"G01 X250 F{feed_mm_min:g}")  # 20 s at 10 mm/s: constant speed meanwhile

    def lag_settles_at(expected: float) -> None:
        poll(lambda: abs(number(page, "lag-X") - expected) < 2e-3, f"lag {expected} mm")

    lag_settles_at(v / KV_X)  # 0.5 mm
    page.get_by_test_id("tab-Parameters").click()
    page.get_by_test_id("param-search").fill("P-AXIS-00099")
    field = page.get_by_test_id("param-input-getriebe[0].kv")
    field.fill("1000")
    expect(page.get_by_test_id("param-eng-getriebe[0].kv")).to_have_text("10\u00a01/s")
    page.get_by_test_id("param-apply").click()
    expect(page.get_by_test_id("param-trial")).to_be_visible()
    lag_settles_at(v / (1000 * 0.01))  # 1.0 mm: lag = v / (kv · 0.01)
    shot(page, "parameters-trial-desktop")
    page.get_by_test_id("param-revert").click()
    expect(page.get_by_test_id("param-trial")).to_be_hidden()
    lag_settles_at(v / KV_X)
    expect(field).to_have_value("2000")

    # out of range: the range is shown inline, Apply stays disabled, nothing changes
    field.fill("0")
    error = page.get_by_test_id("param-error-getriebe[0].kv")
    expect(error).to_contain_text("out of range 1 … 4294967295 0.01/s")
    expect(page.get_by_test_id("param-apply")).to_be_disabled()
    lag_settles_at(v / KV_X)
    shot(page, "parameters-invalid-desktop")


def test_bad_mdi_block_shows_the_error_under_its_column(page: Page) -> None:
    block = "G01 X10 F500 &"
    mdi(page, block)
    err = page.get_by_test_id("mdi-error")
    expect(err).to_be_visible()
    column = block.index("&") + 1
    assert err.get_attribute("data-column") == str(column)
    caret_line = err.inner_text().splitlines()[1]
    assert caret_line.index("^") == column - 1  # the caret sits under the bad character
    expect(page.get_by_test_id("mdi-refusal")).to_contain_text("90010")
    shot(page, "mdi-error-desktop")


def test_mdi_shows_it_runs_and_the_modal_words_the_next_block_inherits(page: Page) -> None:
    """`G01 X60 F500` then a bare `X70`: the MDI panel says the block runs, then shows
    G01 … F500 in force, and X70 moves X at the feed (issue 16: modal words carry over)."""
    panel = page.get_by_test_id("panel-mdi")
    state = panel.get_by_test_id("mdi-state")
    mdi(page, "G01 X60 F500")
    expect(state).to_have_attribute("data-mdi", "1", timeout=5_000)
    expect(state).to_have_attribute("data-mdi", "0", timeout=10_000)
    expect(panel.get_by_test_id("mdi-modal")).to_have_text("G01 G17 G90 F500")
    mdi(page, "X70")
    expect(state).to_have_attribute("data-mdi", "1", timeout=5_000)
    expect(state).to_have_attribute("data-mdi", "0", timeout=10_000)


def test_job_error_is_shown_as_a_banner_until_dismissed_and_stays_until_reset(
    page: Page, srv: Server, mid: str
) -> None:
    page.get_by_test_id("tab-HLI / PLC").click()
    drive_on = page.get_by_test_id("hli-X-DriveOn").locator("input")
    drive_on.click()  # the switch shows the HLI as the NC reports it back
    expect(drive_on).not_to_be_checked()
    expect(page.get_by_test_id("lamp-enables")).to_have_attribute("data-on", "0")
    page.get_by_test_id("tab-Operate").click()
    page.get_by_test_id("jog-axis-X").check()
    page.get_by_test_id("jog-step-plus").click()
    refusal = page.get_by_test_id("jog-refusal")
    expect(refusal).to_contain_text("90001")  # drive enables missing [job error table]
    banner = page.get_by_test_id("banner-error")
    expect(banner).to_contain_text("90001")
    shot(page, "job-error-banner-desktop")
    # the banner's button only hides it (the PLC acknowledge is the pending strip's): so named
    expect(banner.get_by_role("button", name="Acknowledge")).to_have_count(0)
    expect(banner).to_contain_text("Reset clears it.")
    dismiss = banner.get_by_role("button", name="Dismiss")
    expect(dismiss).to_have_attribute("title", re.compile("stays active until Reset"))
    dismiss.click()
    expect(banner).to_be_hidden()
    assert any(e["code"] == 90001 for e in srv.status(mid)["job_errors"])  # still in error
    page.get_by_test_id("tab-HLI / PLC").click()
    drive_on.click()
    expect(drive_on).to_be_checked()
    expect(page.get_by_test_id("lamp-enables")).to_have_attribute("data-on", "1")
