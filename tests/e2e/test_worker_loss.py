"""The HMI when the machine's worker dies: a banner tells the viewer the machine was rebuilt
from its stored parameters, the event log starts again with that notice, the top bar names
the worker whose loop paces it now, and the machine answers again."""

from __future__ import annotations

import os
import signal

from playwright.sync_api import Page, expect

from tests.backend.server import Server
from tests.e2e.browser import panel, poll, shot

SERVE_ARGS = ("--workers", "2")  # the machine moves to the other worker when its own dies


def plotted(page: Page) -> tuple[float, float, float]:
    """The live plot's sample times: the first and last of its window, and the newest."""
    t: list[float] = page.evaluate(
        "() => { const r = window.inbetrieb.rings(); const t = r.window(60, [])[0];"
        " return [t[0] ?? 0, t[t.length - 1] ?? 0, r.lastTime]; }"
    )
    return t[0], t[1], t[2]


def test_a_killed_worker_shows_a_rebuilt_banner_and_the_machine_goes_on(
    page: Page, srv: Server, mid: str
) -> None:
    health = page.get_by_test_id("loop-health")
    workers = srv.http.get("/api/service/status").json()["workers"]
    (home,) = [w for w in workers if mid in w["machines"]]
    expect(health).to_contain_text(f"loop {home['id']}")
    poll(lambda: plotted(page)[2] > 1.0, "a second of samples plotted")
    before = plotted(page)[2]
    os.kill(home["pid"], signal.SIGKILL)
    banner = page.get_by_test_id("banner-notice")
    expect(banner).to_contain_text("rebuilt from its stored parameters")
    expect(banner).to_contain_text(home["id"])
    expect(health).not_to_contain_text(f"loop {home['id']} ")  # paced by another worker now
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    poll(lambda: srv.status(mid)["plc"]["drives_powered"], "powered again after the rebuild")
    # the live plot shows the new run alone: its time axis starts again, never mixes runs
    poll(lambda: 0.2 < plotted(page)[2] < before, "the plot follows the new run")
    first, last, _ = plotted(page)
    assert 0.0 <= first <= last < before
    shot(page, "worker-lost-desktop")
    banner.get_by_role("button", name="Dismiss").click()
    expect(banner).to_have_count(0)
    # the history marks the machine's new life: powered on again, rebuilt, and why
    page.get_by_test_id("tab-History").click()
    power = panel(page, "history").get_by_test_id("history-row").filter(has_text="powered on")
    expect(power.first).to_contain_text("rebuilt: its worker")
