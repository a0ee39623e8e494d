"""The account dialog in a real browser: an API token created in the UI works for a script
and is refused once revoked in the UI; an admin adds a user there; the telemetry socket opens
with a one-time ticket, never with the cookie alone."""

from __future__ import annotations

import httpx
from playwright.sync_api import APIResponse, Page, Route, expect

from tests.backend.server import Server
from tests.e2e.browser import panel, shot

OWN_SERVICE = True  # makes and revokes users and tokens


def test_a_token_made_in_the_ui_works_until_revoked_there(page: Page, srv: Server) -> None:
    page.get_by_test_id("account-open").click()
    account = panel(page, "account")
    tokens = account.get_by_test_id("account-tokens")
    tokens.get_by_test_id("token-label").fill("e2e script")
    tokens.get_by_test_id("token-create").click()
    secret = tokens.get_by_test_id("token-secret").inner_text().strip()
    row = tokens.get_by_test_id("token-row").filter(has_text="e2e script")
    expect(row).to_have_count(1)
    token_id = row.get_attribute("data-token-id")
    assert token_id and token_id.startswith("token-") and secret not in token_id
    shot(page, "account-token-created")
    bearer = {"Authorization": f"Bearer {secret}"}
    me = httpx.get(f"{srv.base}/api/auth/me", headers=bearer)
    assert me.status_code == 200 and me.json()["session"] == token_id
    row.get_by_test_id("token-revoke").click()
    expect(row).to_have_count(0)
    expect(tokens.get_by_test_id("token-secret")).to_have_count(0)  # gone with its token
    refused = httpx.get(f"{srv.base}/api/auth/me", headers=bearer)
    assert refused.status_code == 401
    account.get_by_test_id("account-close").click()
    expect(panel(page, "account")).to_have_count(0)


def test_a_list_answered_late_never_hides_the_token_just_made(page: Page) -> None:
    """The token list the dialog asks for as it opens is answered by the service at once
    but handed to the page only after a token has been made and the list asked for after it
    is shown: the late, older answer must not replace the newer list (the new token would
    vanish from it)."""
    held: list[tuple[Route, APIResponse]] = []

    def hold_the_first_list(route: Route) -> None:
        if route.request.method == "GET" and not held:
            held.append((route, route.fetch()))  # the list as it is now, before the token
        else:
            route.fallback()

    page.route("**/api/auth/tokens", hold_the_first_list)
    page.get_by_test_id("account-open").click()
    tokens = panel(page, "account").get_by_test_id("account-tokens")
    for _ in range(250):  # Playwright calls the route handler while it waits
        if held:
            break
        page.wait_for_timeout(20)
    assert held, "the dialog asked for no token list"
    tokens.get_by_test_id("token-label").fill("made meanwhile")
    tokens.get_by_test_id("token-create").click()
    row = tokens.get_by_test_id("token-row").filter(has_text="made meanwhile")
    expect(row).to_have_count(1)
    first, answer = held[0]
    with page.expect_response(lambda r: r.request == first.request) as late:
        first.fulfill(response=answer)
    late.value.finished()
    # the page handles the answer within a few tasks; two animation frames and a margin later
    # a stale list would have been rendered
    page.evaluate("() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)))")
    page.wait_for_timeout(300)
    expect(row).to_have_count(1)


def test_an_admin_adds_a_user_in_the_ui(page: Page, srv: Server) -> None:
    page.get_by_test_id("account-open").click()
    users = panel(page, "account").get_by_test_id("account-users")
    users.get_by_test_id("user-new-name").fill("uwe")
    users.get_by_test_id("user-new-role").select_option("instructor")
    users.get_by_test_id("user-new-password").fill("uwe-password")
    users.get_by_test_id("user-add").click()
    row = users.locator('[data-testid="user-row"][data-user="uwe"]')
    expect(row.get_by_test_id("user-role-select")).to_have_value("instructor")
    # the change is a request of its own: the login below waits for its answer
    with page.expect_response(
        lambda r: r.request.method == "PATCH" and r.url.endswith("/api/users/uwe")
    ) as changed:
        row.get_by_test_id("user-role-select").select_option("observer")
    assert changed.value.ok
    login = httpx.post(
        f"{srv.base}/api/auth/login", json={"name": "uwe", "password": "uwe-password"}
    )
    assert login.status_code == 200 and login.json()["role"] == "observer"
    row.get_by_test_id("user-remove").click()
    expect(row).to_have_count(0)
    assert [u["name"] for u in srv.http.get("/api/users").json()].count("uwe") == 0


def test_the_telemetry_socket_opens_with_a_ticket(page: Page, srv: Server, mid: str) -> None:
    """The page's socket carries a fresh ticket on every (re)connect, never the cookie alone."""
    urls: list[str] = []
    page.on("websocket", lambda ws: urls.append(ws.url))
    for _ in range(2):
        page.reload()
        expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
    tickets = [u.split("ticket=")[1] for u in urls if f"/{mid}/telemetry?ticket=" in u]
    assert len(tickets) == 2 and tickets[0] != tickets[1], urls
