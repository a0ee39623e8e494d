"""The engineer's HMI (issue 39): plots that keep their history and give each quantity its
own axis, labels that are not clipped, states that follow the axis, safe defaults. Each test
fails without its fix."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from playwright.sync_api import Locator, Page, expect

from tests.backend.server import Server
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


def test_the_trace_librarys_delete_reads_as_red_text_not_blue_on_red(
    page: Page, tmp_path: Path
) -> None:
    csv = tmp_path / "any-trace.csv"
    csv.write_text("cycle,t_s,X.lag_mm [mm]\n0,0.000,0.0\n1,0.001,0.0\n")
    page.get_by_test_id("tab-Scope").click()
    library = panel(page, "trace-library")
    library.get_by_test_id("trace-import").set_input_files(str(csv))
    delete = library.locator("tr", has_text="any-trace").get_by_role("button", name="delete")
    style = delete.evaluate(
        "e => { const s = getComputedStyle(e); return [s.color, s.backgroundColor]; }"
    )
    assert style == ["rgb(192, 32, 42)", "rgba(0, 0, 0, 0)"], style  # --bad on the page


def test_states_follow_the_axes_and_the_service_view_its_limits(
    page: Page, srv: Server, mid: str
) -> None:
    """X with kv 2/s (getriebe[0].kv 200) at 300 mm/min: lag v/kv = 2.5 mm, settling into
    the 10 µm window takes ln(250)/2 = 2.8 s after the set-point arrived. During the X-only
    block Z stands still; after it X is SETTLING (not STANDSTILL) until its lag is in. The
    service view's velocity limit at rest is the axis' vb_max, not the last F."""
    r = srv.http.patch(
        f"/api/machines/{mid}/parameters",
        json={
            "changes": [{"scope": "axis", "target": "X", "name": "getriebe[0].kv", "value": 200}]
        },
    )
    assert r.status_code == 200, r.text
    machine = panel(page, "machine")
    page.get_by_test_id("tab-Service").click()
    svc = panel(page, "service").get_by_test_id("svc-X")
    expect(svc.get_by_test_id("svc-X-v-limit-source")).to_contain_text("vb_max")
    expect(svc.get_by_test_id("svc-X-da")).to_contain_text("digital: no D/A range")  # SERCOS
    r = srv.command(mid, {"type": "mdi", "block": "G01 X60 F300"})
    assert r.status_code in (200, 202), r.text
    expect(machine.get_by_test_id("state-X")).to_have_text("MOVING")
    expect(machine.get_by_test_id("state-Z")).to_have_text("STANDSTILL")
    expect(machine.get_by_test_id("state-X")).to_have_text("SETTLING", timeout=10_000)
    lag = float(machine.get_by_test_id("lag-X").inner_text().replace("−", "-"))
    assert abs(lag) > 0.01
    shot(page, "state-settling-desktop")
    expect(machine.get_by_test_id("state-X")).to_have_text("STANDSTILL", timeout=10_000)
    assert abs(srv.axis("X", mid)["lag"]) <= 0.010


def test_the_spindle_s_field_follows_an_mdi_s(page: Page, srv: Server, mid: str) -> None:
    s_input = panel(page, "spindle").get_by_test_id("s-input")
    expect(s_input).to_have_value("1000")
    r = srv.command(mid, {"type": "mdi", "block": "M3 S600"})
    assert r.status_code in (200, 202), r.text
    expect(s_input).to_have_value("600")
    s_input.fill("750")  # typed: it stays until sent
    srv.command(mid, {"type": "mdi", "block": "S650"})
    expect(panel(page, "machine").get_by_test_id("vcmd-S1")).to_have_text("650.0", timeout=10_000)
    expect(s_input).to_have_value("750")


def test_jog_defaults_to_a_safe_feed_and_warns_while_unhomed(
    page: Page, srv: Server, mid: str
) -> None:
    """A 1 s press with nothing typed moves X about 300 mm/min · 1 s = 5 mm, not the G200
    rapid's 10 000 mm/min (167 mm); the panel says X is not homed, and 'homing…' while G74
    runs."""
    jog = panel(page, "jog")
    jog.get_by_test_id("jog-axis-X").check()
    expect(jog.get_by_test_id("jog-feed")).to_have_value("300")
    expect(jog.get_by_test_id("jog-feed-default")).to_contain_text("safe default")
    expect(jog.get_by_test_id("jog-unhomed")).to_contain_text("X is not homed")
    shot(page, "jog-safe-default-desktop")
    x0 = srv.axis("X", mid)["pos_cmd"]
    jog.get_by_test_id("jog-plus").hover()
    page.mouse.down()
    expect(panel(page, "machine").get_by_test_id("state-X")).to_have_text("JOG")
    page.wait_for_timeout(1000)
    page.mouse.up()
    expect(panel(page, "machine").get_by_test_id("state-X")).to_have_text("STANDSTILL")
    moved = srv.axis("X", mid)["pos_cmd"] - x0
    assert 2.0 < moved < 12.0, moved
    jog.get_by_test_id("jog-home").click()
    expect(jog.get_by_test_id("jog-homed")).to_have_text("homing…")
    expect(jog.get_by_test_id("jog-unhomed")).to_have_count(0)


def test_a_live_run_confirmation_does_not_also_say_on_a_copy(page: Page) -> None:
    page.get_by_test_id("tab-Commissioning").click()
    assist = panel(page, "assist")
    assist.get_by_test_id("assist-run-live").click()
    expect(assist.get_by_test_id("assist-confirm")).to_contain_text("The machine will move")
    expect(assist.get_by_test_id("assist-what")).to_contain_text("on the machine itself")
    expect(assist.get_by_test_id("assist-what")).not_to_contain_text("on a copy")


def test_the_trial_bar_drops_at_reset_once_someone_else_resets(
    page: Page, srv: Server, mid: str
) -> None:
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("P-AXIS-00178")  # swe_pos: takes effect at reset
    params.get_by_test_id("param-input-kenngr.swe_pos").fill("5000000")
    params.get_by_test_id("param-apply").click()
    trial = page.get_by_test_id("trial-bar").get_by_test_id("param-trial")
    expect(trial).to_contain_text("(at reset)")
    page.get_by_test_id("control-release").click()  # someone else takes over and resets
    expect(page.get_by_test_id("control-release")).to_have_count(0)
    r = srv.command(mid, {"type": "reset"})
    assert r.status_code in (200, 202), r.text
    expect(trial).to_contain_text("in force since the reset")
    expect(trial).not_to_contain_text("(at reset)")


def test_the_machine_view_stays_on_screen_on_a_wide_screen(page: Page) -> None:
    """A wide screen (1920 px, here 700 px high so Operate surely scrolls), the Operate
    workspace scrolled to its live plot: the machine view beside it is still in the window
    (it scrolled away and left an empty column)."""
    page.set_viewport_size({"width": 1920, "height": 700})
    expect(panel(page, "jog")).to_be_visible()
    page.evaluate("window.scrollTo(0, document.documentElement.scrollHeight)")
    assert page.evaluate("window.scrollY") > 300
    box = panel(page, "machine").bounding_box()
    assert box is not None and 0 <= box["y"] < 300, box
    shot(page, "wide-scrolled-desktop")


def test_the_program_view_warns_when_the_path_axes_kv_differ(
    page: Page, srv: Server, mid: str
) -> None:
    """X at kv 8.75 1/s (as multi_gain's full proposal leaves it), Z at 20: the program view
    says so; both at 20 again, the warning goes."""
    page.get_by_test_id("tab-Program").click()
    prog = panel(page, "program")
    expect(prog.get_by_test_id("program-ok")).to_be_visible()
    expect(prog.get_by_test_id("kv-mismatch")).to_have_count(0)

    def kv_x(raw: int) -> None:
        r = srv.http.patch(
            f"/api/machines/{mid}/parameters",
            json={
                "changes": [
                    {"scope": "axis", "target": "X", "name": "getriebe[0].kv", "value": raw}
                ]
            },
        )
        assert r.status_code == 200, r.text

    kv_x(875)
    page.reload()
    page.get_by_test_id("tab-Program").click()
    warning = prog.get_by_test_id("kv-mismatch")
    expect(warning).to_contain_text("X kv 8.75 1/s, Z kv 20.00 1/s")
    shot(page, "program-kv-mismatch-desktop")
    kv_x(2000)
    page.reload()
    page.get_by_test_id("tab-Program").click()
    expect(prog.get_by_test_id("program-ok")).to_be_visible()
    expect(prog.get_by_test_id("kv-mismatch")).to_have_count(0)
