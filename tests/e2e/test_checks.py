"""Input checks, the parameter trial across workspaces, the emergency stop's lamps and locks,
what reaches the operator as text, and measurements on noise - in Chromium against the real
service. Locators are scoped to their panel."""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest
from playwright.sync_api import Browser, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import commands_sent, open_hmi, panel, shot, signed_in_page


def test_no_request_ever_goes_to_an_empty_machine_id(browser: Browser, srv: Server) -> None:
    page = signed_in_page(browser, srv.base)
    urls: list[str] = []
    page.on("request", lambda r: urls.append(r.url))
    page.goto(srv.base + "/")
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    for tab in ["Operate", "Plots", "Scope", "Parameters", "HLI / PLC", "History", "Operate"]:
        page.get_by_test_id(f"tab-{tab}").click()
        page.wait_for_timeout(200)
    empty = [u for u in urls if re.search(r"/api/machines/(/|\?|$)", u)]
    assert any("/api/machines/demo/" in u for u in urls)
    assert empty == []
    page.close()


def test_m19_needs_an_angle(page: Page) -> None:
    sent = commands_sent(page)
    spindle = panel(page, "spindle")
    angle, m19 = spindle.get_by_test_id("m19-angle"), spindle.get_by_test_id("m19")
    for bad in ["", "abc"]:
        angle.fill(bad)
        expect(m19).to_be_disabled()
        expect(spindle.get_by_test_id("m19-angle-error")).to_be_visible()
        angle.press("Enter")  # the form cannot be sent by the keyboard either
    assert not [b for b in sent if "spindle_position" in b]  # never M19 S.POS=0
    shot(page, "m19-angle-invalid-desktop")
    angle.fill("45")
    expect(m19).to_be_enabled()
    m19.click()
    expect(page.get_by_test_id("lamp-in-position-S1")).to_have_attribute("data-on", "1")
    assert [b for b in sent if "spindle_position" in b and '"position_deg":45' in b]


@pytest.mark.parametrize("feed", ["abc", "-1000", "0"])
def test_an_invalid_jog_feed_jogs_nowhere(page: Page, srv: Server, feed: str, mid: str) -> None:
    jog = panel(page, "jog")
    jog.get_by_test_id("jog-axis-X").check()
    jog.get_by_test_id("jog-feed").fill(feed)
    expect(jog.get_by_test_id("jog-feed")).to_have_attribute("aria-invalid", "true")
    expect(jog.get_by_test_id("jog-feed-error")).to_be_visible()
    for key in ["jog-plus", "jog-minus", "jog-step-plus", "jog-step-minus"]:
        expect(jog.get_by_test_id(key)).to_be_disabled()
    x0 = srv.axis("X", mid)["pos_cmd"]
    jog.get_by_test_id("jog-plus").hover()
    page.mouse.down()
    time.sleep(0.5)
    page.mouse.up()
    assert srv.axis("X", mid)["state"] == "STANDSTILL" and srv.axis("X", mid)["pos_cmd"] == x0
    if feed == "abc":
        shot(page, "jog-feed-invalid-desktop")
    jog.get_by_test_id("jog-feed").fill("")  # empty: the G200 default, allowed
    expect(jog.get_by_test_id("jog-plus")).to_be_enabled()


def test_trial_survives_a_visit_to_operate_and_reverts(page: Page, srv: Server, mid: str) -> None:
    def kv() -> float:
        rows = srv.http.get(f"/api/machines/{mid}/parameters?target=X").json()
        return float(next(p["value"] for p in rows if p["name"] == "getriebe[0].kv"))

    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("P-AXIS-00099")
    params.get_by_test_id("param-input-getriebe[0].kv").fill("1000")
    params.get_by_test_id("param-apply").click()
    bar = page.get_by_test_id("trial-bar")
    expect(bar.get_by_test_id("param-trial")).to_contain_text("getriebe[0].kv 2000 → 1000")
    assert kv() == 1000
    # a second Apply waits for Keep/Revert: it would take this trial's Revert away
    params.get_by_test_id("param-input-getriebe[0].kv").fill("1200")
    expect(params.get_by_test_id("param-apply")).to_be_disabled()
    page.get_by_test_id("tab-Operate").click()  # test the values on the machine ...
    expect(bar.get_by_test_id("param-trial")).to_be_visible()  # ... the bar stays
    shot(page, "parameters-trial-operate-desktop")
    page.get_by_test_id("tab-Parameters").click()
    expect(bar.get_by_test_id("param-trial")).to_be_visible()
    page.get_by_test_id("tab-History").click()
    bar.get_by_test_id("param-revert").click()  # from any workspace
    expect(bar.get_by_test_id("param-trial")).to_be_hidden()
    expect(bar.get_by_test_id("trial-message")).to_contain_text("Reverted 1 value")
    assert kv() == 2000


def test_a_fraction_for_an_integer_parameter_is_flagged_before_apply(page: Page) -> None:
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("P-AXIS-00099")  # kv: UNS32 [004]
    params.get_by_test_id("param-input-getriebe[0].kv").fill("2000.5")
    expect(params.get_by_test_id("param-error-getriebe[0].kv")).to_contain_text(
        "UNS32 takes whole numbers"
    )
    expect(params.get_by_test_id("param-apply")).to_be_disabled()
    params.get_by_test_id("param-input-getriebe[0].kv").fill("2001")
    expect(params.get_by_test_id("param-error-getriebe[0].kv")).to_be_hidden()
    expect(params.get_by_test_id("param-apply")).to_be_enabled()


def test_an_import_error_names_its_line(page: Page, tmp_path: Path) -> None:
    lis = tmp_path / "x-bad.lis"
    lis.write_text("# X, kv changed\ngetriebe[0].kv  1500\ngetriebe[0].kv  0\n")
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.locator("input[type=file]").set_input_files(str(lis))
    message = params.get_by_test_id("param-message")
    expect(message).to_contain_text("x-bad.lis")
    expect(message).to_contain_text("line 3")
    expect(message).to_contain_text("getriebe[0].kv")


def test_a_speed_beyond_the_machine_names_its_limit(page: Page) -> None:
    spindle = panel(page, "spindle")
    spindle.get_by_test_id("s-input").fill("2000000")
    spindle.get_by_test_id("m3").click()
    refusal = spindle.get_by_test_id("spindle-refusal")
    # the demo's highest gear stage: M45 up to 7000 rpm [000 §2.8.2]
    expect(refusal).to_contain_text("90017")
    expect(refusal).to_contain_text("7000 rpm")
    expect(refusal).not_to_contain_text("Input should be")
    shot(page, "spindle-speed-limit-desktop")


def test_events_read_as_words(page: Page) -> None:
    jog = panel(page, "jog")
    jog.get_by_test_id("jog-axis-X").check()
    jog.get_by_test_id("jog-step-plus").click()
    page.get_by_test_id("tab-History").click()
    table = panel(page, "history").get_by_test_id("history-table")
    done = table.locator("tr", has_text="motion done")
    expect(done.first).to_contain_text("18")
    messages = table.locator("tbody td:nth-child(5)").all_inner_texts()
    assert messages and not [m for m in messages if m.lower().startswith("ev ")], messages


def test_emergency_stop_darkens_enables_and_locks_motion(page: Page) -> None:
    machine, spindle, jog = panel(page, "machine"), panel(page, "spindle"), panel(page, "jog")
    expect(machine.get_by_test_id("lamp-enables")).to_have_attribute("data-on", "1")
    expect(machine.get_by_test_id("lamp-drive-ready")).to_have_attribute("data-on", "1")
    page.get_by_test_id("estop").click()
    expect(machine.get_by_test_id("lamp-estop")).to_have_attribute("data-on", "1")
    # the PLC takes DriveOn/TorquePermission once the axes stand: the lamps show it
    expect(machine.get_by_test_id("lamp-enables")).to_have_attribute("data-on", "0")
    expect(machine.get_by_test_id("lamp-drive-ready")).to_have_attribute("data-on", "0")
    locked = [
        spindle.get_by_test_id("m3"),
        spindle.get_by_test_id("m4"),
        spindle.get_by_test_id("m19"),
        spindle.get_by_test_id("gear-m41"),
        spindle.get_by_test_id("spindle-home"),
        jog.get_by_test_id("jog-plus"),
        jog.get_by_test_id("jog-minus"),
        jog.get_by_test_id("jog-step-plus"),
        jog.get_by_test_id("jog-home"),
        panel(page, "mdi").get_by_test_id("mdi-send"),
    ]
    panel(page, "mdi").get_by_test_id("mdi-input").fill("G91 G01 X1 F600")
    for button in locked:
        expect(button).to_be_disabled()
    expect(page.get_by_test_id("reset")).to_be_enabled()  # the way out
    shot(page, "estop-active-desktop")
    page.get_by_test_id("reset").click()
    expect(machine.get_by_test_id("lamp-estop")).to_have_attribute("data-on", "0")
    expect(machine.get_by_test_id("lamp-enables")).to_have_attribute("data-on", "1")
    expect(machine.get_by_test_id("lamp-drive-ready")).to_have_attribute("data-on", "1")
    for button in locked:
        expect(button).to_be_enabled()


def test_noise_has_no_step_and_its_axis_ticks_differ(page: Page, tmp_path: Path) -> None:
    """A standing axis' lag: white noise of 0.02 µm. No overshoot or rise time to report,
    and the axis ticks (a few 0.01 µm apart) must not all read 0."""
    rng = np.random.default_rng(5)
    n = 2000
    lag_mm = rng.normal(0.0, 2e-5, n)
    lag_mm[0] = 6e-5  # the first sample 3 σ off: a 'step' to the mean of the end
    rows = [f"{k},{(k - 500) * 1e-3:.3f},{float(v)!r}" for k, v in enumerate(lag_mm)]
    csv = tmp_path / "x-lag-noise.csv"
    csv.write_text("cycle,t_s,X.lag_mm [mm]\n" + "\n".join(rows) + "\n")
    page.get_by_test_id("tab-Scope").click()
    library = panel(page, "trace-library")
    library.get_by_test_id("trace-import").set_input_files(str(csv))
    row = library.locator("tr", has_text="x-lag-noise")
    row.get_by_role("button", name="show").click()
    capture = panel(page, "capture")
    expect(capture.get_by_test_id("capture-trigger")).to_have_text("x-lag-noise")
    meas = capture.get_by_test_id("measurements")
    expect(meas.get_by_test_id("meas-no-step")).to_be_visible()
    expect(meas.get_by_test_id("meas-overshoot")).to_have_text("—")
    expect(meas.get_by_test_id("meas-rise")).to_have_text("—")
    sigma = float(meas.get_by_test_id("meas-noise").inner_text().split()[0])
    assert sigma == pytest.approx(2e-5, rel=0.15)
    chart = capture.get_by_test_id("capture-chart").locator(".uplot")
    expect(chart).to_have_attribute("data-y-ticks", re.compile(r"\|"))
    ticks = (chart.get_attribute("data-y-ticks") or "").split(" | ")
    assert len(ticks) >= 3 and len(set(ticks)) == len(ticks), ticks
    assert not [t for t in ticks if re.fullmatch(r"[-−]0(\.0*)?", t)], ticks
    values = [float(t.replace("−", "-")) for t in ticks]
    assert values == sorted(values) and max(values) > 4e-5 and min(values) < -4e-5
    steps = np.diff(values)
    assert np.allclose(steps, steps[0], rtol=1e-3), ticks  # evenly spaced, as labelled
    final = meas.get_by_test_id("meas-final").inner_text().split()[0].replace("−", "-")
    assert float(final) == pytest.approx(0.0, abs=1e-5)
    shot(page, "scope-noise-desktop")


def test_the_new_bars_and_messages_fit_a_tablet(browser: Browser, srv: Server, mid: str) -> None:
    """Trial bar, inline errors and the E-stop lock at 1024×768: nothing overflows sideways."""
    page = open_hmi(browser, srv.base, mid, "tablet")
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("P-AXIS-00099")
    params.get_by_test_id("param-input-getriebe[0].kv").fill("1500")
    params.get_by_test_id("param-apply").click()
    bar = page.get_by_test_id("trial-bar")
    expect(bar.get_by_test_id("param-trial")).to_be_visible()
    page.get_by_test_id("tab-Operate").click()
    panel(page, "spindle").get_by_test_id("m19-angle").fill("")
    panel(page, "jog").get_by_test_id("jog-feed").fill("-1000")
    page.get_by_test_id("estop").click()
    expect(panel(page, "machine").get_by_test_id("lamp-enables")).to_have_attribute("data-on", "0")
    overflow = page.evaluate("document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 0
    shot(page, "checks-operate-tablet")
    bar.get_by_test_id("param-revert").click()
    expect(bar.get_by_test_id("param-trial")).to_be_hidden()
    page.get_by_test_id("reset").click()
    page.close()


def test_a_search_the_open_list_cannot_answer_says_which_list_has_it(page: Page) -> None:
    """P-CHAN-00008 (cax_face_id) is a channel parameter [000 §3.1]: searched in X's list the
    editor says so and opens the channel list on a click."""
    page.get_by_test_id("tab-Parameters").click()
    params = panel(page, "parameters")
    params.get_by_test_id("param-search").fill("P-CHAN-00008")
    hint = params.get_by_test_id("param-no-match")
    expect(hint).to_contain_text("P-CHAN-00008")
    expect(hint.get_by_role("button")).to_have_count(1)  # the channel list only
    hint.get_by_test_id("param-look-Channel").click()
    expect(params.get_by_test_id("param-row-cax_face_id")).to_be_visible()
    expect(params.get_by_test_id("param-no-match")).to_have_count(0)
