"""One unit per quantity and the gears' three names in the browser: the parameter page reads
X's rapid velocity in the unit and number the machine view shows while X runs at it; the
spindle panel's range bars stand on an rpm scale and name M40…M45 = gear 1…6 =
getriebe[0]…[5], as the parameter page's gear records do."""

from __future__ import annotations

from playwright.sync_api import Page, expect

from tests.e2e.browser import SIZES, number, panel, poll, shot

RAPID_MM_MIN = 333333 * 60 / 1000  # the demo's X getriebe[0].vb_eilgang, µm/s → mm/min
# the demo's spindle ranges [000 §2.8.2], rpm
GEAR_RANGES = [(50, 560), (400, 800), (700, 3500), (3501, 4000), (3800, 5500), (5400, 7000)]


def test_x_rapid_velocity_reads_alike_in_machine_view_and_parameter_page(page: Page) -> None:
    machine = panel(page, "machine")
    expect(machine.get_by_test_id("vcmd-X")).to_be_visible()
    unit = machine.get_by_test_id("axis-X").locator("td.unit").nth(1)
    expect(unit).to_have_text("mm/min")
    page.get_by_test_id("mdi-input").fill("G00 X950")  # 900 mm at 20 m/min: 2.7 s, most at speed
    page.get_by_test_id("mdi-send").click()
    top = [0.0]

    def at_rapid() -> bool:
        top[0] = max(top[0], number(page, "vcmd-X"))
        return abs(top[0] - RAPID_MM_MIN) < 0.5

    poll(at_rapid, f"X at G00 speed {RAPID_MM_MIN} mm/min")
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("vb_eilgang")
    eng = params.get_by_test_id("param-eng-getriebe[0].vb_eilgang")
    text = eng.inner_text().replace("\u00a0", " ")
    value, shown_unit = text.split(" ")
    assert shown_unit == "mm/min"
    assert abs(float(value) - top[0]) <= 0.1  # the machine view shows one decimal
    shot(page, "parameters-units-desktop")
    # weights in %, not as a bare fraction
    params.get_by_test_id("param-search").fill("r_trans_weight")
    expect(params.get_by_test_id("param-eng-getriebe[0].dynamik.r_trans_weight")).to_have_text(
        "100\u00a0%"
    )
    # multi_gain as the manual's ratio z/n: 10000/1 digits per 1 m/min [004 §3.6.2]
    params.get_by_test_id("param-search").fill("multi_gain_z")
    expect(params.get_by_test_id("param-eng-getriebe[0].multi_gain_z")).to_have_text(
        "multi_gain 10000 digits per 1 m/min"
    )


def test_gear_bars_on_an_rpm_scale_and_the_gear_mapping(page: Page) -> None:
    spindle = panel(page, "spindle")
    expect(spindle.get_by_test_id("gear-mapping")).to_contain_text(
        "M40…M45 = gear 1…6 = gear records getriebe[0]…[5]"
    )
    # the demo starts in M42: the third range, record getriebe[2]
    expect(spindle.get_by_test_id("gear-mapping")).to_contain_text("now M42 · gear 3 · getriebe[2]")
    scale = spindle.get_by_test_id("gear-bars-scale")
    ticks = [float(v) for v in (scale.get_attribute("data-ticks") or "").split()]
    assert ticks[0] == 0 and ticks[-1] >= max(hi for _lo, hi in GEAR_RANGES)
    # the tick labels' centres give the scale: each bar starts and ends at its rpm on it
    labels = scale.locator("text")
    xs = []
    for k in range(1, len(ticks) - 1):  # inner labels are centred on their tick
        box = labels.nth(k).bounding_box()
        assert box is not None
        xs.append((ticks[k], box["x"] + box["width"] / 2))
    (r1, x1), (r2, x2) = xs[0], xs[-1]
    px_per_rpm = (x2 - x1) / (r2 - r1)
    for g, (lo, hi) in enumerate(GEAR_RANGES, 1):
        bar = spindle.get_by_test_id(f"gear-bar-{g}").locator("rect").bounding_box()
        assert bar is not None
        assert abs(bar["x"] - (x1 + (lo - r1) * px_per_rpm)) < 2.0, f"M{39 + g} min"
        assert abs(bar["x"] + bar["width"] - (x1 + (hi - r1) * px_per_rpm)) < 2.0, f"M{39 + g} max"
    shot(page, "spindle-gears-scale-desktop")

    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-target").select_option("Axis S1")
    expect(params.locator("tr.group-row", has_text="getriebe[2]")).to_have_text(
        "Gear record getriebe[2] (M42 · gear 3)"
    )
    page.set_viewport_size({"width": SIZES["tablet"][0], "height": SIZES["tablet"][1]})
    shot(page, "parameters-gears-tablet")


def test_a_parameter_without_effect_in_the_simulation_says_so_and_why(page: Page) -> None:
    # P-CHAN-00078 rund_aufloes converts rotary positions to an internal integer
    # representation the simulation does not have (issue 36: the editor shows the reason)
    page.get_by_role("tab", name="Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-target").select_option("Channel")
    params.get_by_test_id("param-search").fill("rund_aufloes")
    mark = params.get_by_test_id("param-no-effect-rund_aufloes")
    expect(mark).to_contain_text("no effect here")
    expect(mark).to_contain_text("floating-point degrees")
    shot(page, "parameter-without-effect")
    params.get_by_test_id("param-target").select_option("Axis X")
    params.get_by_test_id("param-search").fill("kv")
    expect(params.get_by_test_id("param-row-getriebe[0].kv")).to_be_visible()
    expect(params.locator("[data-testid^=param-no-effect-]")).to_have_count(0)  # kv acts
