"""The commissioning assistants in the browser: multi_gain by experiment (004 §3.6.2) done end
to end without arithmetic by hand, and an observer kept to reading.

The plant is made wrong through the simulated drive: `sim.drive_gain` 22857 digits per 1 m/min
where the demo's X list says multi_gain 10000, so physics gives f = 22857 / 10000 = 2.2857;
after the proposed correction the measured gain k equals kv, f = 1 [004 §3.6.2 equation 1].
"""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Browser, Locator, Page, expect

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD, Server, add_users
from tests.e2e.browser import open_hmi, panel, shot
from tests.e2e.plant import DRIVE_GAIN, KV_RAW, MULTI_GAIN, set_up

OWN_SERVICE = True  # adds an observer

RUN_TIMEOUT_MS = 90_000  # a run is seconds of machine time in a process; generous on 2 cores
OLE = "ole"  # an observer


def read(scope: Locator, test_id: str) -> float:
    """A figure as the panel shows it (− for minus)."""
    return float(scope.get_by_test_id(test_id).inner_text().replace("−", "-"))


def x_list(srv: Server, mid: str) -> dict[str, float]:
    rows = srv.http.get(f"/api/machines/{mid}/parameters?scope=axis&target=X").json()
    return {p["name"]: p["value"] for p in rows}


def test_multi_gain_by_experiment_end_to_end(page: Page, srv: Server, wrong_drive: str) -> None:
    f_expected = DRIVE_GAIN / MULTI_GAIN
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "assist")
    box.get_by_test_id("assist-pick-multi-gain").check()
    box.get_by_test_id("assist-axis").select_option("X")
    feed = box.get_by_test_id("assist-feed")
    feed.fill("0")  # refused as typed: the range, and no run
    expect(box.get_by_test_id("assist-feed-error")).to_contain_text("> 0")
    expect(box.get_by_test_id("assist-run")).to_be_disabled()
    feed.fill("200")
    expect(box.get_by_test_id("assist-what")).to_contain_text("X moves at 200 mm/min")
    expect(box.get_by_test_id("assist-what")).to_contain_text("the live machine does not move")

    box.get_by_test_id("assist-run").click()
    expect(box.get_by_test_id("assist-busy")).to_be_visible()
    expect(box.get_by_test_id("assist-result")).to_be_visible(timeout=RUN_TIMEOUT_MS)
    f = read(box, "assist-fig-f")
    assert f == pytest.approx(f_expected, rel=0.01)
    # k = v/s with v = 200 mm/min = 3.333 mm/s, and f = kv/k
    assert read(box, "assist-fig-k") == pytest.approx((KV_RAW / 100) / f_expected, rel=0.01)
    assert read(box, "assist-fig-s") == pytest.approx(
        (200 / 60) / (KV_RAW / 100 / f_expected), rel=0.01
    )
    expect(box.get_by_test_id("assist-check")).to_have_attribute("data-ok", "0")
    expect(box.get_by_test_id("assist-notes")).to_contain_text("> 1")  # the loop gain rises
    expect(box.get_by_test_id("assist-chart").locator("canvas")).to_have_count(1)
    kv_row = box.get_by_test_id("assist-change-getriebe[0].kv")
    expect(kv_row).to_contain_text(str(KV_RAW))
    shot(page, "assist-multi-gain-desktop")

    box.get_by_test_id("assist-apply").click()
    trial = page.get_by_test_id("param-trial")
    expect(trial).to_contain_text("getriebe[0].multi_gain_z")
    expect(trial).to_contain_text("getriebe[0].kv")
    # z and n read as their ratio, not as a 2285-fold change of z: 10000 × f (2.2857)
    expect(trial).to_contain_text(re.compile(r"\(multi_gain 10000 → 228[4-6]\d\)"))
    after = x_list(srv, wrong_drive)
    assert after["getriebe[0].multi_gain_z"] / after["getriebe[0].multi_gain_n"] == pytest.approx(
        DRIVE_GAIN, rel=0.01
    )
    assert after["getriebe[0].kv"] == pytest.approx(KV_RAW / f_expected, abs=1)

    box.get_by_test_id("assist-run").click()  # "Run again to check"
    check = box.get_by_test_id("assist-check")
    expect(check).to_have_attribute("data-ok", "1", timeout=RUN_TIMEOUT_MS)
    assert read(box, "assist-fig-f") == pytest.approx(1.0, abs=0.01)
    # nothing left to apply: no residual proposal beside "matches" (nor "3 changes proposed")
    expect(box.get_by_test_id("assist-no-changes")).to_be_visible()
    # k equals the kv now in force (004 §3.6.2 equation 1)
    assert read(box, "assist-fig-k") == pytest.approx(after["getriebe[0].kv"] / 100, rel=0.01)
    box.get_by_test_id("assist-result").scroll_into_view_if_needed()
    shot(page, "assist-multi-gain-checked-desktop")
    page.set_viewport_size({"width": 1024, "height": 768})
    box.get_by_test_id("assist-check").scroll_into_view_if_needed()
    shot(page, "assist-multi-gain-checked-tablet")

    page.get_by_test_id("param-revert").click()  # the trial bar takes the values back
    expect(trial).to_be_hidden()
    assert x_list(srv, wrong_drive)["getriebe[0].kv"] == KV_RAW


def test_the_sign_check_says_the_signs_are_right_on_the_demo(page: Page) -> None:
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "assist")
    box.get_by_test_id("assist-pick-sign-check").check()
    box.get_by_test_id("assist-axis").select_option("X")
    box.get_by_test_id("assist-distance").fill("1")
    expect(box.get_by_test_id("assist-what")).to_contain_text("X moves +1 mm at 100 mm/min")
    box.get_by_test_id("assist-run").click()
    expect(box.get_by_test_id("assist-verdict")).to_have_text(
        "✓ signs right", timeout=RUN_TIMEOUT_MS
    )
    # a 1 mm move at 100 mm/min lags v/kv = 1.667/20 mm at most, far below lag_max
    assert read(box, "assist-max-lag") == pytest.approx((100 / 60) / (KV_RAW / 100), rel=0.05)
    expect(box.get_by_test_id("assist-no-changes")).to_be_visible()
    expect(box.get_by_test_id("assist-apply")).to_be_disabled()
    shot(page, "assist-sign-check-desktop")


def test_an_assistant_without_a_form_of_its_own_gets_one_from_its_schema(page: Page) -> None:
    """The resolution check has no panel code: its form comes from the catalogue's schema
    (range checked as typed), its result from the common view. Z moves -50 mm on a copy and
    the engineer measured 49.9 mm: k = 50/49.9 and wegaufz/wegaufn · k is proposed."""
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "assist")
    box.get_by_test_id("assist-pick-resolution-check").check()
    box.get_by_test_id("assist-axis").select_option("Z")
    distance = box.get_by_test_id("assist-in-distance")
    distance.fill("5000")
    expect(box.get_by_test_id("assist-in-distance-error")).to_contain_text("≤ 1000 mm")
    expect(box.get_by_test_id("assist-run")).to_be_disabled()
    distance.fill("-50")
    box.get_by_test_id("assist-in-measured").fill("-49.9")
    expect(box.get_by_test_id("assist-what")).to_contain_text("wegaufz/wegaufn · k")
    box.get_by_test_id("assist-run").click()
    expect(box.get_by_test_id("assist-result")).to_be_visible(timeout=RUN_TIMEOUT_MS)
    assert read(box, "assist-fig-k") == pytest.approx(50 / 49.9, rel=1e-4)
    expect(box.get_by_test_id("assist-change-getriebe[0].wegaufz")).to_be_visible()
    expect(box.get_by_test_id("assist-apply")).to_be_enabled()
    shot(page, "assist-resolution-check-desktop")


def test_the_sign_check_finds_an_inverted_encoder_and_applies_the_flip(
    browser: Browser, srv: Server, mid: str
) -> None:
    # the plant's wiring takes effect with the restart (effect "restart"), on the copy as well
    set_up(srv, mid, "X", {"sim.encoder_inverted": 1}, restart=True)
    p = open_hmi(browser, srv.base, mid)
    try:
        p.get_by_test_id("tab-Commissioning").click()
        box = panel(p, "assist")
        box.get_by_test_id("assist-pick-sign-check").check()
        box.get_by_test_id("assist-run").click()
        # the axis moved as commanded but its actual value counts the other way [004 §3.5]
        expect(box.get_by_test_id("assist-verdict")).to_have_text(
            "⚠ flip vz_istw", timeout=RUN_TIMEOUT_MS
        )
        # found by the run-away, long before lag monitoring would trip
        assert read(box, "assist-max-lag") < 0.5 * float(
            box.get_by_test_id("assist-fig-lag_max").inner_text()
        )
        box.get_by_test_id("assist-apply").click()
        trial = p.get_by_test_id("param-trial")
        expect(trial).to_contain_text("lr_hw[0].vz_istw default → 1 (at restart)")
        shot(p, "assist-sign-check-flip-desktop")
        # reverted before any restart: the value in force (the default 0) stays, nothing waits
        p.get_by_test_id("param-revert").click()
        expect(trial).to_be_hidden()
        row = next(
            r
            for r in srv.http.get(f"/api/machines/{mid}/parameters?target=X").json()
            if r["name"] == "lr_hw[0].vz_istw"
        )
        assert row["pending"] is None and row["value"] == 0
    finally:
        p.close()


def test_a_run_the_nc_refuses_shows_the_services_message(page: Page) -> None:
    page.get_by_test_id("tab-Commissioning").click()
    box = panel(page, "assist")
    box.get_by_test_id("assist-axis").select_option("S1")
    box.get_by_test_id("assist-speed").fill("50000")  # in the API's range, beyond every gear
    box.get_by_test_id("assist-run").click()
    # the demo's highest gear stage M45 ends at 7000 rpm [000 §2.8.2]
    expect(box.get_by_test_id("assist-refusal")).to_contain_text(
        "spindle speed out of reach: S50000 rpm is above the highest gear stage, M45 up to 7000"
    )
    expect(box.get_by_test_id("assist-result")).to_have_count(0)


def test_an_observer_reads_the_panel_but_runs_nothing(
    browser: Browser, srv: Server, mid: str
) -> None:
    add_users(srv.db, {OLE: Role.OBSERVER})
    p = open_hmi(browser, srv.base, mid, user=OLE, password=OTHERS_PASSWORD)
    try:
        p.get_by_test_id("tab-Commissioning").click()
        box = panel(p, "assist")
        expect(box.get_by_test_id("assist-readonly")).to_contain_text("needs the role operator")
        expect(box.get_by_test_id("assist-run")).to_be_disabled()
        expect(box.get_by_test_id("assist-what")).to_contain_text("the live machine does not move")
    finally:
        p.close()
