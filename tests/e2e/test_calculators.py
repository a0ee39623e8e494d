"""The calculators in the Commissioning workspace: the acceleration curve fitted from the
manual's interpolation points shows the manual's coefficients (000 §2.8.4) and puts them on
trial, a resolution from the manual's example (004 §3.4), and the gear-range editor previews
the NC's automatic selection for a typed S (000 §2.8.2) as the ranges are edited.
"""

from __future__ import annotations

import pytest
from playwright.sync_api import Browser, Locator, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import open_hmi, panel, shot
from tests.e2e.plant import set_up


def read(scope: Locator, test_id: str) -> float:
    return float(scope.get_by_test_id(test_id).inner_text().replace("−", "-"))


def s1_list(srv: Server, mid: str) -> dict[str, object]:
    rows = srv.http.get(f"/api/machines/{mid}/parameters?scope=axis&target=S1").json()
    return {p["name"]: p["value"] for p in rows}


def test_curve_fit_from_the_manuals_points(page: Page, srv: Server, mid: str) -> None:
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "calc")
    box.get_by_test_id("calc-pick-curve-fit").click()
    box.get_by_test_id("curve-gear").select_option("2")
    box.get_by_test_id("curve-typ-2").check()
    box.get_by_test_id("curve-manual").click()  # (12000, 16000) ... (48000, 2000) in °/s, °/s²
    box.get_by_test_id("curve-a-1").fill("-8000")  # refused as typed
    expect(box.get_by_test_id("curve-input-error")).to_contain_text("a of point 2")
    expect(box.get_by_test_id("curve-run")).to_be_disabled()
    box.get_by_test_id("curve-a-1").fill("8000")
    box.get_by_test_id("curve-run").click()
    expect(box.get_by_test_id("assist-result")).to_be_visible()
    # the manual's coefficients of the polynomial through its four points
    assert read(box, "assist-fig-b3") == pytest.approx(-1.92901234e-10, rel=1e-6)
    assert read(box, "assist-fig-b2") == pytest.approx(2.08333333e-5, rel=1e-6)
    assert read(box, "assist-fig-b1") == pytest.approx(-0.88888888, rel=1e-6)
    assert read(box, "assist-fig-n_limit") == 12000
    # the points and the curves of the three types in one chart
    expect(box.get_by_test_id("curve-chart").locator("canvas")).to_have_count(1)
    legend = box.get_by_test_id("curve-chart").locator(".u-legend")
    for label in ("points", "type 1 hyperbola", "type 2 polynomial", "type 3 asynchronous"):
        expect(legend).to_contain_text(label)
    row = box.get_by_test_id("assist-change-getriebe[1].beschl_kennlinie.n_grenz")
    expect(row).to_contain_text("12000000")
    shot(page, "calc-curve-fit")

    box.get_by_test_id("curve-apply").click()
    expect(box.get_by_test_id("curve-applied")).to_be_visible()
    now = s1_list(srv, mid)
    assert now["getriebe[1].beschl_kennlinie.typ"] == 2
    assert now["getriebe[1].beschl_kennlinie.b1"] == pytest.approx(-0.88888888, rel=1e-6)
    expect(page.get_by_test_id("param-keep")).to_be_visible()


def test_resolution_from_the_manuals_example(page: Page, mid: str) -> None:
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "calc")
    box.get_by_test_id("calc-pick-resolution").click()
    box.get_by_test_id("calc-axis").select_option("X")
    box.get_by_test_id("calc-increments").fill("4096")
    box.get_by_test_id("calc-pitch").fill("0")
    expect(box.get_by_test_id("calc-pitch-error")).to_contain_text("> 0")
    box.get_by_test_id("calc-pitch").fill("5")
    box.get_by_test_id("calc-ratio").fill("10")
    box.get_by_test_id("calc-run").click()
    # 4096 increments per 5 mm / i = 10 -> 4096/5000 (004 §3.4)
    expect(box.get_by_test_id("assist-change-getriebe[0].wegaufz")).to_contain_text("4096")
    expect(box.get_by_test_id("assist-change-getriebe[0].wegaufn")).to_contain_text("5000")


def test_gear_editor_previews_the_selection_for_a_typed_s(
    page: Page, srv: Server, mid: str
) -> None:
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "calc")
    box.get_by_test_id("calc-pick-gear-ranges").click()
    # the manual's table: M41 400-800 and M42 700-3500 overlap
    expect(box.get_by_test_id("gear-max-2")).to_have_value("800")
    expect(box.get_by_test_id("gear-overlaps-2")).to_contain_text("M42 700–800")
    expect(box.get_by_test_id("gear-overlap-2-3")).to_have_count(1)
    box.get_by_test_id("gear-current").select_option("1")
    box.get_by_test_id("gear-way").select_option("0")
    box.get_by_test_id("gear-s").fill("750")
    # from M40, bottom-up: M41 is the first range holding 750 rpm
    expect(box.get_by_test_id("gear-step-0")).to_have_attribute("data-m", "41")
    box.get_by_test_id("gear-way").select_option("1")  # top-down: M42
    expect(box.get_by_test_id("gear-step-0")).to_have_attribute("data-m", "42")
    box.get_by_test_id("gear-way").select_option("0")
    box.get_by_test_id("gear-s").fill("850")  # above M41's 800: M42
    expect(box.get_by_test_id("gear-step-0")).to_have_attribute("data-m", "42")
    box.get_by_test_id("gear-max-2").fill("900")  # M41 widened: it holds 850 now
    expect(box.get_by_test_id("gear-step-0")).to_have_attribute("data-m", "41")
    expect(box.get_by_test_id("gear-row-2")).to_have_attribute("data-chosen", "1")
    expect(box.get_by_test_id("gear-changes")).to_contain_text("range_table[1].max_speed")
    shot(page, "calc-gear-ranges")
    # dragging M41's upper end to the right widens it further (the input follows)
    handle = box.get_by_test_id("gear-handle-2-max").bounding_box()
    assert handle is not None
    cx, cy = handle["x"] + handle["width"] / 2, handle["y"] + handle["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx + 60, cy, steps=6)
    page.mouse.up()
    dragged = int(box.get_by_test_id("gear-max-2").input_value())
    assert dragged > 900 and dragged % 10 == 0
    expect(box.get_by_test_id("gear-changes")).to_contain_text(str(dragged))
    box.get_by_test_id("gear-max-2").fill("900")
    expect(box.get_by_test_id("gear-changes")).to_contain_text("900")
    box.get_by_test_id("gear-apply").click()
    expect(box.get_by_test_id("gear-applied")).to_be_visible()
    rows = srv.http.get(f"/api/machines/{mid}/parameters?scope=channel").json()
    assert {p["name"]: p["value"] for p in rows}["spindel[0].range_table[1].max_speed"] == 900


@pytest.mark.parametrize("size", ["desktop", "tablet"])
def test_calculators_screenshots(browser: Browser, srv: Server, mid: str, size: str) -> None:
    page = open_hmi(browser, srv.base, mid, size=size)
    try:
        page.get_by_test_id("tab-Commissioning").click()
        box = panel(page, "calc")
        box.get_by_test_id("calc-pick-curve-fit").click()
        box.get_by_test_id("curve-run").click()
        expect(box.get_by_test_id("curve-chart").locator("canvas")).to_have_count(1)
        box.scroll_into_view_if_needed()
        shot(page, f"calc-curve-{size}")
        box.get_by_test_id("calc-pick-gear-ranges").click()
        box.get_by_test_id("gear-s").fill("650 750 950 3900")
        expect(box.get_by_test_id("gear-step-3")).to_be_visible()
        box.get_by_test_id("gear-scale").scroll_into_view_if_needed()
        shot(page, f"calc-gears-{size}")
        box.get_by_test_id("gear-steps").scroll_into_view_if_needed()
        shot(page, f"calc-gears-steps-{size}")
        box.get_by_test_id("calc-pick-multi-gain-calc").click()
        box.get_by_test_id("calc-example").click()
        box.get_by_test_id("calc-run").click()
        # the manual's 10.1134 multiplies the rounded f = 3.6408 and n = 2.7778; exact: 10.11327
        expect(box.get_by_test_id("assist-fig-multi_gain")).to_have_text("10.1133")
        expect(box.get_by_test_id("assist-check")).to_have_count(0)  # the experiment's k vs kv
        box.get_by_test_id("calc-run").scroll_into_view_if_needed()
        shot(page, f"calc-multi-gain-{size}")
    finally:
        page.close()


def test_curve_from_a_run_up_on_a_copy(page: Page, srv: Server, mid: str) -> None:
    """S1's gear 6 carries the manual's polynomial; run up on a copy, the fit finds it."""
    poly: dict[str, float] = {"typ": 2, "n_grenz": 12000000, "a_konst": 16000, "a_min": 2000}
    poly |= {"b1": -0.88888888, "b2": 2.08333333e-5, "b3": -1.92901234e-10}
    set_up(srv, mid, "S1", {f"getriebe[5].beschl_kennlinie.{k}": v for k, v in poly.items()})
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "calc")
    box.get_by_test_id("calc-pick-curve-fit").click()
    box.get_by_test_id("curve-gear").select_option("6")
    box.get_by_test_id("curve-source-run-up").check()
    expect(box.get_by_test_id("curve-what")).to_contain_text("the live spindle does not turn")
    box.get_by_test_id("curve-run").click()
    expect(box.get_by_test_id("assist-result")).to_be_visible(timeout=90_000)
    assert read(box, "assist-fig-n_limit") == pytest.approx(12000, rel=0.03)
    assert read(box, "assist-fig-a_konst") == pytest.approx(16000, rel=0.02)
    expect(box.get_by_test_id("curve-chart").locator(".u-legend")).to_contain_text("type 3")
    box.get_by_test_id("curve-chart").scroll_into_view_if_needed()
    shot(page, "calc-curve-run-up")
