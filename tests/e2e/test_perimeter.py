"""The HMI and the API docs in a real browser under the service's Content-Security-Policy:
nothing refused, nothing fetched from another host, and no other page may frame them."""

from __future__ import annotations

from playwright.sync_api import Browser, ConsoleMessage, Request, expect

from tests.backend.server import Server
from tests.e2e.browser import panel, poll, shot, signed_in_page


def test_the_hmi_and_the_docs_need_nothing_the_policy_refuses(
    browser: Browser, srv: Server, mid: str
) -> None:
    page = signed_in_page(browser, srv.base)
    refused: list[str] = []
    foreign: list[str] = []

    def on_console(m: ConsoleMessage) -> None:
        if "Content Security Policy" in m.text or "Refused to" in m.text:
            refused.append(m.text)

    def on_request(r: Request) -> None:
        if not r.url.startswith((srv.base, srv.ws_base, "data:", "blob:")):
            foreign.append(r.url)

    page.on("console", on_console)
    page.on("request", on_request)
    page.goto(f"{srv.base}/#{mid}")
    expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    plots = panel(page, "plot")  # the Operate tab's live plot
    poll(lambda: plots.locator("canvas").count() > 0, "a plot drawn")
    page.goto(f"{srv.base}/docs")
    expect(page.locator(".swagger-ui .info .title")).to_contain_text("Inbetrieb")
    expect(page.locator(".swagger-ui .opblock").first).to_be_visible()
    shot(page, "docs-desktop")
    assert refused == [] and foreign == []
    page.close()


def test_another_page_cannot_frame_the_hmi(browser: Browser, srv: Server, mid: str) -> None:
    """Clickjacking: a foreign page showing our E-STOP and jog buttons in a frame."""
    page = browser.new_page()
    page.set_content(f'<iframe id="f" src="{srv.base}/#{mid}" width="800" height="600"></iframe>')
    page.wait_for_timeout(1500)  # let the frame's navigation finish (or be refused)
    frame = next(f for f in page.frames if f != page.main_frame)
    assert frame.locator("#app").count() == 0  # the HMI's page never loaded in the frame
    page.close()
