"""The main spindle as the rotary axis C in the HMI (issue 17, item 5): the changeover of
003 Fig. 4-1 shown in the spindle panel, the PLC's acknowledgement ROTMOD_Q given by hand on
the HLI/PLC workspace, and the name C wherever the axis is listed. Locators are scoped to
their panel."""

from __future__ import annotations

import math
import re

from playwright.sync_api import Browser, Locator, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import commands_sent, open_hmi, panel, poll, shot


def _plc_manual(page: Page) -> None:
    page.get_by_test_id("tab-HLI / PLC").click()
    panel(page, "hli").get_by_test_id("plc-mode").select_option("manual")
    expect(panel(page, "hli").get_by_test_id("plc-signal-ROTMOD_Q")).to_be_visible()


def _mdi(page: Page, block: str) -> None:
    page.get_by_test_id("tab-Operate").click()
    mdi = panel(page, "mdi")
    mdi.get_by_test_id("mdi-input").fill(block)
    mdi.get_by_test_id("mdi-send").click()


def _deg(scope: Locator, test_id: str) -> float:
    """A readout in degrees as shown (the HMI writes − for minus)."""
    return float(scope.get_by_test_id(test_id).inner_text().replace("−", "-"))


def test_g00_c45_waits_for_rotmod_q_set_by_hand_then_c_reaches_45(page: Page) -> None:
    """003 Fig. 4-1: the NC sets ROTMOD and waits for the PLC's ROTMOD_Q; in manual PLC mode
    nothing answers until the operator sets it, then the spindle is the rotary axis C and the
    block moves it to 45°."""
    spindle, machine = panel(page, "spindle"), panel(page, "machine")
    expect(spindle.get_by_test_id("spindle-mode")).to_have_text("spindle S1")
    expect(machine.get_by_test_id("name-S1")).to_have_text("S1")
    _plc_manual(page)
    _mdi(page, "G00 C45")
    waiting = spindle.get_by_test_id("spindle-changeover")
    expect(waiting).to_contain_text("waiting for ROTMOD_Q")
    # the mode changes only once the changeover completed: still not C while it waits
    expect(spindle.get_by_test_id("spindle-mode")).to_have_text("changing over")
    expect(machine.get_by_test_id("name-S1")).to_have_text("S1")

    page.get_by_test_id("tab-HLI / PLC").click()
    hli = panel(page, "hli")
    expect(hli.get_by_test_id("lamp-ROTMOD")).to_have_attribute("data-on", "1")
    expect(hli.get_by_test_id("lamp-ROTMOD_Q")).to_have_attribute("data-on", "0")
    expect(hli.get_by_test_id("pending-ROTMOD")).to_be_visible()
    hli.get_by_test_id("plc-signal-ROTMOD_Q").click()
    expect(hli.get_by_test_id("lamp-ROTMOD_Q")).to_have_attribute("data-on", "1")
    expect(hli.get_by_test_id("pending-ROTMOD")).to_have_count(0)
    expect(hli.get_by_test_id("sig-S1-ROTARY")).to_have_attribute("data-on", "1")
    # withdrawing it now would withdraw the mode in force: the key says so
    withdraw = hli.get_by_test_id("plc-signal-ROTMOD_Q")
    expect(withdraw).to_have_text("Withdraw ROTMOD_Q")
    expect(withdraw).to_have_attribute("title", re.compile("process error 90031"))

    page.get_by_test_id("tab-Operate").click()
    expect(spindle.get_by_test_id("spindle-mode")).to_have_text("rotary axis C")
    expect(spindle.get_by_test_id("spindle-changeover")).to_have_count(0)
    expect(machine.get_by_test_id("name-S1")).to_have_text("C")
    poll(lambda: math.isclose(_deg(machine, "pos-S1"), 45.0, abs_tol=0.01), "C at 45°")

    # the jog addresses C: the key is named C and a 10° increment moves it on to 55°
    sent = commands_sent(page)
    jog = panel(page, "jog")
    choice = jog.get_by_test_id("jog-axis-S1")
    expect(choice.locator("xpath=..")).to_have_text("C")
    choice.check()
    expect(jog.get_by_test_id("jog-plus")).to_have_text("+ C")
    jog.get_by_test_id("jog-step-size").select_option("10")
    jog.get_by_test_id("jog-step-plus").click()
    # within a few hundredths: C settles slowly into its in-position window after the step
    poll(lambda: math.isclose(_deg(machine, "pos-S1"), 55.0, abs_tol=0.05), "C at 55°")
    assert any('"axis":"C"' in body.replace(" ", "") for body in sent), sent


def test_screenshots_of_the_rotary_axis_and_the_handshake(
    browser: Browser, srv: Server, mid: str
) -> None:
    """The spindle panel in rotary axis mode and the handshake on the PLC workspace, at both
    sizes (kept under tests/e2e/screenshots, not committed)."""
    for size in ("desktop", "tablet"):
        page = open_hmi(browser, srv.base, mid, size)
        spindle = panel(page, "spindle")
        if size == "desktop":
            _plc_manual(page)
            _mdi(page, "G00 C45")
            waiting = spindle.get_by_test_id("spindle-changeover")
            expect(waiting).to_contain_text("waiting for ROTMOD_Q")
            shot(page, "caxis-waiting-desktop")
            page.get_by_test_id("tab-HLI / PLC").click()
            shot(page, "caxis-handshake-waiting-desktop")
            panel(page, "hli").get_by_test_id("plc-signal-ROTMOD_Q").click()
            page.get_by_test_id("tab-Operate").click()
        if size == "tablet":  # the desktop page held control: take it, or every key is grey
            page.get_by_test_id("control-strip").get_by_test_id("control-take").click()
            expect(
                page.get_by_test_id("control-strip").get_by_test_id("control-take")
            ).to_have_count(0)
        expect(spindle.get_by_test_id("spindle-mode")).to_have_text("rotary axis C")
        spindle.scroll_into_view_if_needed()
        shot(page, f"caxis-spindle-{size}")
        page.get_by_test_id("tab-HLI / PLC").click()
        expect(panel(page, "hli").get_by_test_id("lamp-ROTMOD_Q")).to_have_attribute("data-on", "1")
        panel(page, "hli").get_by_test_id("handshake").scroll_into_view_if_needed()
        shot(page, f"caxis-handshake-{size}")
        page.close()


def test_the_cax_keys_change_over_and_back_with_the_plc_answering_by_itself(page: Page) -> None:
    """In auto PLC mode the changeover completes without a hand: #CAX makes the spindle the
    rotary axis C, #CAX OFF the spindle S1 again; the key of the mode in force is disabled and
    says why, and the handshake levels follow the mode (ROTMOD_Q in rotary mode, SPMOD_Q in
    spindle mode) [003 §4.1]."""
    spindle, machine = panel(page, "spindle"), panel(page, "machine")
    mode = spindle.get_by_test_id("spindle-mode")
    on, off = spindle.get_by_test_id("cax-on"), spindle.get_by_test_id("cax-off")
    expect(mode).to_have_text("spindle S1")
    expect(off).to_be_disabled()
    expect(off).to_have_attribute("title", "already spindle S1")
    on.click()
    expect(mode).to_have_text("rotary axis C")
    expect(machine.get_by_test_id("name-S1")).to_have_text("C")
    expect(on).to_be_disabled()
    expect(on).to_have_attribute("title", "already rotary axis C")
    page.get_by_test_id("tab-HLI / PLC").click()
    hli = panel(page, "hli")
    expect(hli.get_by_test_id("lamp-ROTMOD_Q")).to_have_attribute("data-on", "1")
    expect(hli.get_by_test_id("lamp-SPMOD_Q")).to_have_attribute("data-on", "0")
    # auto mode: no manual keys
    expect(hli.get_by_test_id("plc-signal-ROTMOD_Q")).to_have_count(0)
    page.get_by_test_id("tab-Operate").click()
    off.click()
    expect(mode).to_have_text("spindle S1")
    expect(machine.get_by_test_id("name-S1")).to_have_text("S1")
    page.get_by_test_id("tab-HLI / PLC").click()
    expect(hli.get_by_test_id("lamp-SPMOD_Q")).to_have_attribute("data-on", "1")
    expect(hli.get_by_test_id("lamp-ROTMOD_Q")).to_have_attribute("data-on", "0")
