"""The engineer's HMI (issue 39): plots that keep their history and give each quantity its
own axis, labels that are not clipped, states that follow the axis, safe defaults. Each test
fails without its fix."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from playwright.sync_api import Locator, Page, expect

from tests.e2e.browser import panel, shot

# ui/scopeAxes.ts: the axes' tick font, and tick length plus the gap to the text
AXIS_FONT = "12px system-ui, sans-serif"
TICK_AND_GAP_PX = 15
# seconds of history the page's sample rings hold
SPAN_JS = (
    "(() => { const [t] = window.inbetrieb.rings().window(30, []);"
    " return t.length ? t[t.length - 1] - t[0] : 0; })()"
)


def _ticks_per_axis(chart: Locator) -> list[list[str]]:
    """The y axes' tick labels as the chart drew them (ui/scopeAxes.ts data-y-ticks)."""
    text = chart.get_attribute("data-y-ticks") or ""
    return [[t for t in axis.split(" | ") if t] for axis in text.split(" ‖ ")]


def test_a_signal_added_to_a_live_plot_keeps_the_others_and_gets_its_own_axis(
    page: Page,
) -> None:
    """Adding X's velocity to the lag plot: the lag keeps its history and its axis at once
    (before, a signal without history made the one shared y scale NaN: every trace and the
    axis vanished for up to a window), and the velocity reads on an axis of its own."""
    page.get_by_test_id("tab-Plots").click()
    plot = panel(page, "plots").get_by_test_id("plot-p2")
    chart = plot.locator(".uplot")
    page.wait_for_function(f"() => {SPAN_JS} > 2.0")
    expect(plot).to_have_attribute("data-y-scales", "lag [mm]")
    picker = plot.locator("details.signal-picker")
    picker.locator("summary").click()
    picker.locator("input[data-signal='X.vel_cmd_mm_min']").check()
    picker.locator("summary").click()
    expect(plot).to_have_attribute("data-y-scales", "lag [mm]|vel [mm/min]")
    # at once, not a window later: both axes have their ticks, and the history is there
    page.wait_for_function(
        "(el) => (el.dataset.yTicks || '').split(' ‖ ').length === 2"
        " && (el.dataset.yTicks || '').split(' ‖ ').every((a) => a.includes('|'))",
        arg=chart.element_handle(),
        timeout=1000,
    )
    assert page.evaluate(f"() => {SPAN_JS}") > 2.0
    # one axis per unit when the engineer shares them: lag (mm) and velocity (mm/min) differ
    plot.get_by_test_id("plot-share-y").check()
    expect(plot).to_have_attribute("data-y-scales", "mm|mm/min")
    shot(page, "plots-axes-desktop")


def test_negative_tick_labels_fit_their_axis(page: Page, tmp_path: Path) -> None:
    """A standing axis' lag, −0.05 µm with noise: the ticks read −4.0e−5 and so on; every
    label, minus sign and all, fits inside its axis (a fixed 56 px cut the sign off)."""
    rng = np.random.default_rng(7)
    lag_mm = rng.normal(-5e-5, 4e-6, 2000)
    rows = [f"{k},{k * 1e-3:.3f},{float(v)!r}" for k, v in enumerate(lag_mm)]
    csv = tmp_path / "x-lag-negative.csv"
    csv.write_text("cycle,t_s,X.lag_mm [mm]\n" + "\n".join(rows) + "\n")
    page.get_by_test_id("tab-Scope").click()
    library = panel(page, "trace-library")
    library.get_by_test_id("trace-import").set_input_files(str(csv))
    library.locator("tr", has_text="x-lag-negative").get_by_role("button", name="show").click()
    chart = panel(page, "capture").get_by_test_id("capture-chart").locator(".uplot")
    expect(chart).to_have_attribute("data-y-ticks", re.compile(r"\|"))  # drawn
    (ticks,) = _ticks_per_axis(chart)
    assert all(t.startswith("−") for t in ticks), ticks
    widest = page.evaluate(
        "([labels, font]) => { const c = document.createElement('canvas').getContext('2d');"
        " c.font = font; return Math.max(...labels.map((l) => c.measureText(l).width)); }",
        [ticks, AXIS_FONT],
    )
    axis = chart.locator(".u-axis").nth(1).bounding_box()  # the first y axis (after time)
    assert axis is not None
    assert widest + TICK_AND_GAP_PX <= axis["width"], (ticks, widest, axis)
    shot(page, "scope-negative-ticks-desktop")


def test_the_scope_gives_a_spindles_lag_an_axis_apart_from_its_position(page: Page) -> None:
    """S1's position (thousands of degrees) and its lag (hundredths) in one capture: each its
    own axis, so the lag does not flatten to zero; shared, one degree axis."""
    page.get_by_test_id("tab-Scope").click()
    setup = panel(page, "scope-setup")
    picker = setup.get_by_test_id("scope-channels")
    picker.locator("summary").click()
    checked = picker.locator("input[data-signal]:checked")
    for _ in range(checked.count()):
        checked.first.uncheck()
    for name in ("S1.pos_act_deg", "S1.lag_deg"):
        picker.locator(f'input[data-signal="{name}"]').check()
    picker.locator("summary").click()
    setup.get_by_test_id("scope-length").fill("0.5")
    setup.get_by_test_id("trigger-event").check()
    setup.get_by_test_id("trigger-kind").select_option("m_start")
    setup.get_by_test_id("trigger-axis").select_option("S1")
    setup.get_by_test_id("trigger-m").select_option("3")
    setup.get_by_test_id("scope-arm").click()
    expect(setup.get_by_test_id("scope-state")).to_contain_text("history 100 %", timeout=10_000)
    strip = panel(page, "scope-commands")
    strip.get_by_test_id("s-input").fill("1000")
    strip.get_by_test_id("m3").click()
    chart = panel(page, "capture").get_by_test_id("capture-chart")
    expect(chart).to_have_attribute("data-y-scales", "pos [deg]|lag [deg]", timeout=15_000)
    expect(chart.locator(".u-axis")).to_have_count(3)  # time, position, lag
    shot(page, "scope-quantity-axes-desktop")
    chart.get_by_test_id("chart-share-y").check()
    expect(chart).to_have_attribute("data-y-scales", "deg")
    expect(chart.locator(".u-axis")).to_have_count(2)
    chart.get_by_test_id("chart-share-y").uncheck()  # this browser keeps the choice
