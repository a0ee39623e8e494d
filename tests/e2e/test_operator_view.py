"""What a new operator saw on the Demo lathe (issue 13, items 36/37 and the layout): lamps that
tell the truth during an E-stop, the jog feed bounded by the axis' own limit, no pydantic
text, the head (top bar, banners, trial bar) on screen while scrolling, and layout details.
Locators are scoped to their panel."""

from __future__ import annotations

from pathlib import Path

from playwright.sync_api import Browser, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import SIZES, commands_sent, open_hmi, panel, shot

NBSP = "\u00a0"


def test_during_an_emergency_stop_the_plc_lamps_show_the_drives_off(page: Page) -> None:
    page.get_by_test_id("tab-HLI / PLC").click()
    hli = panel(page, "hli")
    powered = hli.get_by_test_id("lamp-drives-powered")
    expect(powered).to_have_attribute("data-on", "1")
    expect(hli.get_by_test_id("hli-loop-X")).to_have_text("closed")
    page.get_by_test_id("estop").click()
    # at rest the PLC takes DriveOn and TorquePermission at once: nothing powered, no loop
    expect(hli.get_by_test_id("hli-X-DriveOn").locator("input")).not_to_be_checked()
    expect(powered).to_have_attribute("data-on", "0")
    for axis in ["X", "Z", "S1"]:
        expect(hli.get_by_test_id(f"hli-loop-{axis}")).to_have_text("open")
    shot(page, "hli-estop-desktop")
    page.get_by_test_id("reset").click()
    expect(powered).to_have_attribute("data-on", "1")  # the PLC's start-up again
    expect(hli.get_by_test_id("hli-loop-X")).to_have_text("closed")


def test_a_jog_feed_above_the_axis_limit_is_caught_inline_naming_it(page: Page) -> None:
    """X's handbetrieb.hb.vb_max in the demo list: 166666 µm/s = 9999.96 mm/min [002 §2.6.1]."""
    sent = commands_sent(page)
    jog = panel(page, "jog")
    jog.get_by_test_id("jog-axis-X").check()
    jog.get_by_test_id("jog-feed").fill("99999999")
    error = jog.get_by_test_id("jog-feed-error")
    expect(error).to_contain_text(f"at most 9999.96{NBSP}mm/min")
    expect(error).to_contain_text("P-AXIS-00213")
    for key in ["jog-plus", "jog-minus", "jog-step-plus", "jog-step-minus"]:
        expect(jog.get_by_test_id(key)).to_be_disabled()
    jog.get_by_test_id("jog-step-plus").click(force=True)
    assert not [b for b in sent if '"jog"' in b]
    shot(page, "jog-feed-limit-desktop")
    jog.get_by_test_id("jog-feed").fill("9999.96")  # the limit itself jogs
    expect(error).to_be_hidden()
    expect(jog.get_by_test_id("jog-step-plus")).to_be_enabled()


def test_a_schema_refusal_reads_as_a_sentence_with_its_unit(page: Page) -> None:
    spindle = panel(page, "spindle")
    spindle.get_by_test_id("m19-angle").fill("1e12")  # a number, beyond the API's ±1e9°
    spindle.get_by_test_id("m19").click()
    refusal = spindle.get_by_test_id("spindle-refusal")
    expect(refusal).to_have_text("M19 target angle must be at most 1e+09 °.")
    expect(refusal).not_to_contain_text("Input should")
    expect(refusal).not_to_contain_text("position_deg")


def test_the_m19_angle_error_moves_nothing(page: Page) -> None:
    spindle = panel(page, "spindle")
    m19, gear = spindle.get_by_test_id("m19"), spindle.get_by_test_id("gear-m40")
    before = (m19.bounding_box(), gear.bounding_box())
    spindle.get_by_test_id("m19-angle").fill("")
    expect(spindle.get_by_test_id("m19-angle-error")).to_be_visible()
    assert (m19.bounding_box(), gear.bounding_box()) == before


def test_head_and_trial_bar_stay_on_screen_when_scrolled_on_a_tablet(
    browser: Browser, srv: Server, mid: str
) -> None:
    page = open_hmi(browser, srv.base, mid, "tablet")
    w, h = SIZES["tablet"]
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("P-AXIS-00099")
    params.get_by_test_id("param-input-getriebe[0].kv").fill("1500")
    params.get_by_test_id("param-apply").click()
    bar = page.get_by_test_id("trial-bar")
    expect(bar.get_by_test_id("param-trial")).to_be_visible()
    page.get_by_test_id("tab-Operate").click()
    # a job error: S above the highest gear stage (90017), its banner under the top bar
    spindle = panel(page, "spindle")
    spindle.get_by_test_id("s-input").fill("2000000")
    spindle.get_by_test_id("m3").click()
    banner = page.get_by_test_id("banner-error")
    expect(banner).to_be_visible()
    panel(page, "jog").get_by_test_id("jog-feed").fill("99999999")
    expect(panel(page, "jog").get_by_test_id("jog-feed-error")).to_be_visible()
    shot(page, "operate-limits-tablet")
    panel(page, "plot").scroll_into_view_if_needed()  # down to the live plot
    page.mouse.wheel(0, 5000)
    page.wait_for_timeout(300)
    assert page.evaluate("window.scrollY") > 300  # the page did scroll
    top = page.locator("header.topbar").bounding_box()
    ban = banner.bounding_box()
    revert = bar.get_by_test_id("param-revert").bounding_box()
    assert top is not None and ban is not None and revert is not None
    assert top["y"] == 0  # the top bar at the top ...
    assert ban["y"] >= top["y"] + top["height"] - 0.5  # ... the banner below it, not under it
    assert revert["y"] >= 0 and revert["y"] + revert["height"] <= h
    shot(page, "head-sticky-scrolled-tablet")
    # the head covers nothing for good: a control scrolled to lands below it
    jog_home = panel(page, "jog").get_by_test_id("jog-home")
    jog_home.focus()
    head = page.locator(".head").bounding_box()
    box = jog_home.bounding_box()
    assert head is not None and box is not None and box["y"] >= head["y"] + head["height"]
    bar.get_by_test_id("param-revert").click()  # reachable from the scrolled page
    expect(bar.get_by_test_id("param-trial")).to_be_hidden()
    overflow = page.evaluate("document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 0 and w == 1024
    page.close()


def test_units_sit_with_their_numbers(browser: Browser, srv: Server, mid: str) -> None:
    page = open_hmi(browser, srv.base, mid, "tablet")
    spindle = panel(page, "spindle")
    override = spindle.locator("label.slider")
    expect(override).to_contain_text("max 120.0")  # the spindle list has loaded
    # a space before "max"; a no-break space between number and unit, so "%" never wraps
    # onto a line of its own (the demo spindle: kenngr.max_vb_override 1200 ‰)
    assert f"100.0{NBSP}% max 120.0{NBSP}% (P-AXIS-00109)" in (override.text_content() or "")
    page.get_by_test_id("tab-HLI / PLC").click()
    hint = panel(page, "hli").locator("fieldset.hli-axis").first.locator(".hint").first
    expect(hint).to_contain_text("override")
    assert f"override 100.0{NBSP}%" in (hint.text_content() or "")
    shot(page, "hli-tablet")
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    search = params.get_by_test_id("param-search")
    # the whole placeholder fits its field
    assert search.evaluate("e => e.scrollWidth <= e.clientWidth")
    fits = search.evaluate(
        "e => { const c = document.createElement('canvas').getContext('2d');"
        " c.font = getComputedStyle(e).font; return c.measureText(e.placeholder).width"
        " <= e.clientWidth - parseFloat(getComputedStyle(e).paddingLeft)"
        " - parseFloat(getComputedStyle(e).paddingRight); }"
    )
    assert fits
    search.fill("P-AXIS-00109")  # kenngr.max_vb_override in 0.1 %: read in %
    raw = float(params.get_by_test_id("param-input-kenngr.max_vb_override").input_value())
    eng = params.get_by_test_id("param-eng-kenngr.max_vb_override")
    expect(eng).to_have_text(f"{raw / 10:g}\u00a0%")  # a weight in %, not "0.0000 1"
    shot(page, "parameters-tablet")
    page.close()


def test_long_signal_names_stay_beside_their_checkbox(page: Page) -> None:
    page.get_by_test_id("tab-Plots").click()
    picker = page.locator("details.signal-picker").first
    picker.locator("summary").click()
    label = picker.locator("label", has=page.locator("input[data-signal='X.vel_cmd_mm_min']"))
    box = label.locator("input").bounding_box()
    rects = label.evaluate("e => e.getClientRects().length")
    height = label.evaluate("e => e.getBoundingClientRect().height")
    assert box is not None and rects == 1
    assert height < 2 * box["height"] + 4  # one line: the name beside its box, not below
    shot(page, "plots-signal-picker-desktop")


def test_reimporting_an_unchanged_export_changes_nothing(
    page: Page, srv: Server, mid: str, tmp_path: Path
) -> None:
    export = srv.http.get(f"/api/machines/{mid}/parameters/export", params={"target": "X"})
    lis = tmp_path / "export_x.lis"
    lis.write_text(export.text)
    audit = srv.http.get(f"/api/machines/{mid}/parameters/audit").json()
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.locator("input[type=file]").set_input_files(str(lis))
    message = params.get_by_test_id("param-message")
    expect(message).to_contain_text("Imported export_x.lis: no value changed")
    assert srv.http.get(f"/api/machines/{mid}/parameters/audit").json() == audit
