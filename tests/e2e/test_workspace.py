"""Issue 20: the workspace state kept across tabs, pending PLC handshakes shown on every
workspace, homing progress, and the machines managed from the HMI (Machines dialog)."""

from __future__ import annotations

import re

from playwright.sync_api import Browser, FilePayload, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import SIZES, number, open_hmi, panel, poll, shot

PLC_TIMEOUT_S = 20.0  # P-CHAN plc.m_ack_timeout set for the handshake test (the demo's is 5 s)


def tab(page: Page, name: str) -> None:
    page.get_by_test_id(f"tab-{name}").click()


def ring_span(page: Page) -> tuple[float, float, list[str]]:
    """The live plots' rings: oldest and newest sample time (s), and the signals they hold."""
    first, last, names = page.evaluate(
        "() => { const r = window.inbetrieb.rings(); const [t] = r.window(1e9, []);"
        " return [t.length ? t[0] : NaN, r.lastTime, r.names]; }"
    )
    return float(first), float(last), list(names)


def test_workspace_state_is_kept_across_tabs_and_the_plots_keep_recording(
    page: Page, srv: Server, mid: str
) -> None:
    jog = panel(page, "jog")
    jog.get_by_test_id("jog-axis-Z").check()
    jog.get_by_test_id("jog-step-size").select_option("0.1")
    jog.get_by_test_id("jog-feed").fill("2000")
    tab(page, "Parameters")
    params = panel(page, "parameters")
    params.get_by_test_id("param-target").select_option("Channel")
    params.get_by_test_id("param-search").fill("ack_timeout")
    expect(params.get_by_text("plc.m_ack_timeout")).to_be_visible()
    poll(lambda: ring_span(page)[1] > 0, "plot samples")
    # on the Parameters workspace no plot is on screen: the plots' rings keep filling anyway
    first, last, names = ring_span(page)
    assert "S1.speed_act_rpm" in names
    page.wait_for_timeout(1500)
    first2, last2, _ = ring_span(page)
    assert last2 > last + 0.5 and first2 <= first  # newer samples, the old ones still there
    tab(page, "Operate")
    expect(jog.get_by_test_id("jog-axis-Z")).to_be_checked()
    expect(jog.get_by_test_id("jog-step-size")).to_have_value("0.1")
    expect(jog.get_by_test_id("jog-feed")).to_have_value("2000")
    assert ring_span(page)[0] <= first  # the plot on screen again shows the history
    tab(page, "Parameters")
    expect(params.get_by_test_id("param-target")).to_have_value("Channel")
    expect(params.get_by_test_id("param-search")).to_have_value("ack_timeout")
    # and a reload of the page keeps them too (sessionStorage)
    page.reload()
    tab(page, "Parameters")
    expect(params.get_by_test_id("param-search")).to_have_value("ack_timeout")
    tab(page, "Operate")
    expect(jog.get_by_test_id("jog-feed")).to_have_value("2000")


def test_the_jog_feed_default_is_shown_as_a_value(page: Page) -> None:
    """Demo X: a jog without a typed feed goes at the HMI's safe 300 mm/min, not the G200
    default the tag names: hb.vb_max 166666 µm/s = 10 m/min, below getriebe[0].dynamik.vb_max
    30 m/min [002 §2.6.1] (issue 39: a 2 s press at 10 m/min took X 350 mm)."""
    jog = panel(page, "jog")
    jog.get_by_test_id("jog-axis-X").check()
    expect(jog.get_by_test_id("jog-feed")).to_have_value("300")
    expect(jog.get_by_test_id("jog-feed-default")).to_have_text(
        re.compile(r"^safe default · G200 up to 10000\s+mm/min$")
    )
    jog.get_by_test_id("jog-feed").fill("3000")
    expect(jog.get_by_test_id("jog-feed-default")).to_have_count(0)
    jog.get_by_test_id("jog-feed-reset").click()
    expect(jog.get_by_test_id("jog-feed")).to_have_value("300")


def test_homing_shows_its_phase_distance_and_speed(page: Page, srv: Server, mid: str) -> None:
    """Demo X from 50 mm towards its cam at 280 mm at vb_refmax 5 m/min, off it at vb_reflow
    [002 §2.7], here 0.1 m/min: back over the 1.7 mm it overran the cam braking from 5 m/min
    at 2 m/s² takes about a second (at the demo's 1 m/min a tenth, between two statuses)."""
    change = {"scope": "axis", "target": "X", "name": "getriebe[0].vb_reflow", "value": 1666}
    r = srv.http.patch(f"/api/machines/{mid}/parameters", json={"changes": [change]})
    assert r.status_code == 200, r.text
    assert srv.http.post(f"/api/machines/{mid}/control", json={"action": "release"}).is_success
    panel(page, "jog").get_by_test_id("jog-axis-X").check()
    panel(page, "jog").get_by_test_id("jog-home").click()
    line = panel(page, "machine").get_by_test_id("homing-X")
    expect(line.get_by_test_id("homing-phase-X")).to_have_text("search for the cam")
    expect(line.get_by_test_id("homing-speed-X")).to_have_text(re.compile(r"^5000\s+mm/min$"))
    poll(lambda: number(page, "homing-moved-X") > 0, "moving")
    shot(page, "homing-progress-desktop")
    # off the cam at vb_reflow 1 m/min (the last phase, back to the edge, lasts a moment)
    expect(line.get_by_test_id("homing-phase-X")).to_have_text("leaving the cam", timeout=20_000)
    expect(line.get_by_test_id("homing-speed-X")).to_have_text(re.compile(r"^100\s+mm/min$"))
    expect(line).to_have_count(0, timeout=20_000)  # homed: the line goes
    expect(panel(page, "machine").get_by_test_id("axis-X")).to_contain_text("✓")


def test_a_pending_gear_change_is_shown_and_acknowledged_outside_the_hli_tab(
    page: Page, srv: Server, mid: str
) -> None:
    r = srv.http.patch(
        f"/api/machines/{mid}/parameters",
        json={
            "changes": [
                {
                    "scope": "channel",
                    "target": None,
                    "name": "plc.m_ack_timeout",
                    "value": int(PLC_TIMEOUT_S * 1e6),
                }
            ]
        },
    )
    assert r.status_code == 200, r.text
    assert srv.http.post(f"/api/machines/{mid}/control", json={"action": "release"}).is_success
    tab(page, "HLI / PLC")
    panel(page, "hli").get_by_test_id("plc-mode").select_option("manual")
    tab(page, "Operate")
    spindle = panel(page, "spindle")
    expect(spindle.get_by_test_id("spindle-gear")).to_have_text("M42")
    spindle.get_by_test_id("gear-m41").click()
    strip = page.get_by_test_id("pending-strip")
    item = strip.get_by_test_id("pending-strip-m41")
    expect(item.get_by_test_id("pending-what")).to_have_text(
        "gear change M41 (S1): PLC acknowledge"
    )
    left = number(page, "pending-left")
    assert 0 < left <= PLC_TIMEOUT_S
    poll(lambda: number(page, "pending-left") < left - 0.5, "the countdown running down")
    shot(page, "pending-handshake-desktop")
    page.set_viewport_size({"width": SIZES["tablet"][0], "height": SIZES["tablet"][1]})
    shot(page, "pending-handshake-tablet")
    item.get_by_test_id("pending-ack-m41").click()
    expect(strip).to_have_count(0)
    expect(spindle.get_by_test_id("spindle-gear")).to_have_text("M41")
    assert not [e for e in srv.status(mid)["job_errors"] if e["code"] == 90004]


def test_machines_are_created_restarted_and_deleted_from_the_hmi(
    browser: Browser, srv: Server, mid: str
) -> None:
    page = open_hmi(browser, srv.base, mid)
    new = f"{mid}-ui"
    try:
        page.get_by_test_id("open-machines").click()
        dialog = panel(page, "machines")
        form = dialog.get_by_test_id("new-machine")
        form.get_by_test_id("new-machine-id").fill(new)
        form.get_by_test_id("new-machine-name").fill("Lathe from the HMI")
        form.get_by_test_id("new-machine-create").click()
        expect(form.get_by_test_id("new-machine-created")).to_contain_text(new)
        select = page.locator(".machine-select select")
        expect(select.locator(f"option[value='{new}']")).to_have_text("Lathe from the HMI")
        expect(dialog.get_by_test_id(f"machine-row-{new}")).to_be_visible()
        shot(page, "machines-dialog-desktop")
        # open it, let it run a while, restart it: it starts again at cycle 0
        dialog.get_by_test_id(f"machine-row-{new}").get_by_role("button", name="Open").click()
        expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
        srv.wait_powered(new)
        poll(lambda: srv.status(new)["simulation"]["cycle"] > 2000, "2 s simulated")
        pacing = dialog.get_by_test_id("machine-pacing")
        pacing.get_by_test_id("machine-restart").click()
        pacing.get_by_test_id("restart-confirm").click()
        expect(pacing.get_by_test_id("restart-confirm")).to_have_count(0)
        expect(dialog.get_by_test_id("machine-refusal")).to_have_count(0)
        # it says what happened; "created" is old news once the new machine is on screen
        expect(pacing.get_by_test_id("restart-done")).to_contain_text(f"Restarted {new} at")
        expect(form.get_by_test_id("new-machine-created")).to_have_count(0)
        poll(lambda: srv.status(new)["simulation"]["cycle"] < 2000, "cycle 0 again")
        # pacing from the same place: pause, step 250 cycles, run
        pacing.get_by_test_id("pace-pause").click()
        expect(pacing.get_by_test_id("pace-pause")).to_have_attribute("aria-pressed", "true")
        before = srv.status(new)["simulation"]["cycle"]
        pacing.get_by_test_id("step-cycles").fill("250")
        pacing.get_by_test_id("pace-step").click()
        poll(lambda: srv.status(new)["simulation"]["cycle"] == before + 250, "250 cycles on")
        pacing.get_by_test_id("pace-run").click()
        expect(pacing.get_by_test_id("pace-run")).to_have_attribute("aria-pressed", "true")
        page.set_viewport_size({"width": SIZES["tablet"][0], "height": SIZES["tablet"][1]})
        shot(page, "machines-dialog-tablet")
        dialog.get_by_test_id(f"machine-delete-{new}").click()
        dialog.get_by_test_id(f"machine-delete-confirm-{new}").click()
        expect(dialog.get_by_test_id(f"machine-row-{new}")).to_have_count(0)
        expect(dialog.get_by_test_id("machine-deleted")).to_contain_text(f"Deleted {new}")
        expect(select.locator(f"option[value='{new}']")).to_have_count(0)
        assert srv.http.get(f"/api/machines/{new}/status").status_code == 404
    finally:
        srv.http.delete(f"/api/machines/{new}")
        page.close()


def lis(name: str, text: str) -> FilePayload:
    """A list file as the file picker hands it over."""
    return {"name": name, "mimeType": "text/plain", "buffer": text.encode()}


def test_lists_refused_on_create_show_their_problems_line_by_line(page: Page) -> None:
    page.get_by_test_id("open-machines").click()
    form = panel(page, "machines").get_by_test_id("new-machine")
    form.get_by_test_id("new-machine-id").fill("broken-lists")
    form.get_by_test_id("new-machine-lists").check()
    form.get_by_test_id("new-machine-channel").set_input_files(
        files=[lis("channel.lis", "no_such.parameter 1\n")]
    )
    form.get_by_test_id("new-machine-axes").set_input_files(
        files=[lis("axis_1.lis", "kopf.achs_nr 1\nkenngr.swe_pos banana\n")]
    )
    form.get_by_test_id("new-machine-create").click()
    problems = form.get_by_test_id("new-machine-problems").locator("li")
    expect(problems.first).to_contain_text("line 1")
    assert problems.count() >= 1
    shot(page, "machines-create-refused-desktop")
