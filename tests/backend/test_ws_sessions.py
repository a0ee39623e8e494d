"""Telemetry websockets and the sessions behind them, over real HTTP and websockets: a page
opens its socket with a one-time ticket (never with the cookie alone), and the socket closes
(4401) and control goes when the session ends: logout, expiry, a removed user (also by the
CLI in another process), a revoked token."""

from __future__ import annotations

import asyncio
import sqlite3
import time
from contextlib import closing
from pathlib import Path
from typing import Any

import httpx
import pytest
import websockets

from tests.backend.server import PASSWORD, USER, Server
from tests.backend.test_accounts import browser_like, cli, login

CLOSE_WITHIN_S = 8.0  # the watch looks every 2 s; a loaded test machine gets slack


def session(srv: Server, name: str = USER, password: str = PASSWORD) -> httpx.Client:
    """A logged-in browser-like client that sends its CSRF token and a tab id."""
    c = browser_like(srv)
    assert login(c, name, password).status_code == 200
    c.headers["X-CSRF-Token"] = c.cookies["inbetrieb_csrf"]
    c.headers["X-Inbetrieb-Client"] = "tab-1"
    return c


def ticket(c: httpx.Client) -> str:
    r = c.post("/api/auth/ws-ticket")
    assert r.status_code == 200, r.text
    assert r.json()["expires_in_s"] == 30
    return str(r.json()["ticket"])


def url(srv: Server, mid: str, query: str = "") -> str:
    return f"{srv.ws_base}/api/machines/{mid}/telemetry{query}"


async def hello(address: str, **kw: Any) -> str:
    """The first message, or `refused <status>` when the handshake is refused."""
    try:
        async with websockets.connect(address, **kw) as ws:
            return str(await asyncio.wait_for(ws.recv(), 10))
    except websockets.InvalidStatus as e:
        return f"refused {e.response.status_code}"


async def closed_after(address: str, end: Any, **kw: Any) -> tuple[int, str, float]:
    """Open the socket, run `end` (blocking, on a thread), and wait for the server to close
    it: its close code, reason and how long it took."""
    async with websockets.connect(address, **kw) as ws:
        assert '"hello"' in str(await asyncio.wait_for(ws.recv(), 10))
        await asyncio.to_thread(end)
        t0 = time.monotonic()
        with pytest.raises(websockets.ConnectionClosed):
            while True:
                await asyncio.wait_for(ws.recv(), CLOSE_WITHIN_S)
        assert ws.close_code is not None
        return ws.close_code, ws.close_reason or "", time.monotonic() - t0


def test_a_ticket_opens_one_socket_once_as_the_session(srv: Server, mid: str) -> None:
    with closing(session(srv)) as c:
        me = c.get("/api/auth/me").json()
        t = ticket(c)
        # the cookie alone opens no socket: any page the browser shows could use it
        cookie = {"Cookie": f"inbetrieb_session={c.cookies['inbetrieb_session']}"}
        assert asyncio.run(hello(url(srv, mid), additional_headers=cookie)) == "refused 403"

        async def watch_as_ticket_holder() -> dict[str, Any]:
            async with websockets.connect(url(srv, mid, f"?ticket={t}")) as ws:
                assert '"hello"' in str(await asyncio.wait_for(ws.recv(), 10))
                # the socket is the session's (and the tab's) connection: take control with it
                r = await asyncio.to_thread(
                    c.post, f"/api/machines/{mid}/control", json={"action": "take"}
                )
                assert r.status_code == 200, r.text
                state: dict[str, Any] = c.get(f"/api/machines/{mid}/control").json()
                return state

        state = asyncio.run(watch_as_ticket_holder())
        holder = state["holder"]
        assert (holder["user"], holder["session"], holder["client"]) == (
            USER,
            me["session"],
            "tab-1",
        )
        assert state["connected"]  # the socket counts as this session's and tab's connection
        deadline = time.monotonic() + 5
        while c.get(f"/api/machines/{mid}/control").json()["connected"]:
            assert time.monotonic() < deadline, "closing the socket lost no connection"
            time.sleep(0.05)
        assert asyncio.run(hello(url(srv, mid, f"?ticket={t}"))) == "refused 403"  # used up
        assert asyncio.run(hello(url(srv, mid, "?ticket=made-up"))) == "refused 403"
        # a ticket opens nothing but a telemetry socket (and trying does not use it up)
        t = ticket(c)
        with browser_like(srv) as other:
            assert other.get(f"/api/machines/{mid}/status?ticket={t}").status_code == 401
        assert '"hello"' in asyncio.run(hello(url(srv, mid, f"?ticket={t}")))
        c.post(f"/api/machines/{mid}/control", json={"action": "release"})
    assert '"hello"' in asyncio.run(hello(url(srv, mid), **srv.ws_auth))  # scripts: a token


def test_a_ticket_expires(tmp_path: Path) -> None:
    s = Server(tmp_path / "short.sqlite", env={"INBETRIEB_WS_TICKET_S": "0.2"}).start()
    try:
        with closing(session(s)) as c:
            r = c.post("/api/auth/ws-ticket")
            assert r.json()["expires_in_s"] == 0.2
            time.sleep(0.5)
            address = url(s, "demo", f"?ticket={r.json()['ticket']}")
            assert asyncio.run(hello(address)) == "refused 403"
    finally:
        s.close()


def test_a_ticket_needs_the_csrf_token_and_a_session(srv: Server) -> None:
    with browser_like(srv) as c:
        assert c.post("/api/auth/ws-ticket").status_code == 401
        assert login(c).status_code == 200
        assert c.post("/api/auth/ws-ticket").status_code == 403  # no CSRF header


def test_logout_closes_the_sessions_sockets(srv: Server, mid: str) -> None:
    c = session(srv)
    address = url(srv, mid, f"?ticket={ticket(c)}")

    def logout() -> None:
        assert c.post("/api/auth/logout").status_code == 204

    code, reason, took = asyncio.run(closed_after(address, logout))
    assert (code, reason) == (4401, "session ended")
    assert took < 1.5  # the route pokes the watch: at once, not at its next look
    c.close()


def test_an_expired_session_closes_its_sockets_and_releases_control(srv: Server, mid: str) -> None:
    srv.http.post("/api/users", json={"name": "eva", "role": "operator", "password": "eva-secret"})
    c = session(srv, "eva", "eva-secret")
    assert c.post(f"/api/machines/{mid}/control", json={"action": "take"}).status_code == 200
    assert c.get(f"/api/machines/{mid}/control").json()["holder"]["user"] == "eva"

    def expire() -> None:  # the shift is over (no request tells the service)
        with sqlite3.connect(srv.db) as db:
            db.execute("UPDATE sessions SET expires = ? WHERE user = 'eva'", (time.time() - 1,))

    code, reason, _ = asyncio.run(closed_after(url(srv, mid, f"?ticket={ticket(c)}"), expire))
    assert (code, reason) == (4401, "session ended")
    assert srv.http.get(f"/api/machines/{mid}/control").json()["holder"] is None
    c.close()


def test_a_user_removed_on_the_command_line_loses_their_sockets(srv: Server, mid: str) -> None:
    srv.http.post("/api/users", json={"name": "rolf", "role": "observer", "password": "rolf-pass"})
    c = session(srv, "rolf", "rolf-pass")

    def remove() -> None:
        done = cli(srv.db, "user", "remove", "rolf")
        assert done.returncode == 0, done.stderr

    code, reason, _ = asyncio.run(closed_after(url(srv, mid, f"?ticket={ticket(c)}"), remove))
    assert (code, reason) == (4401, "session ended")
    c.close()


def test_a_revoked_tokens_sockets_close(srv: Server, mid: str) -> None:
    made = srv.http.post("/api/auth/tokens", json={"label": "plotter"}).json()
    auth = {"additional_headers": {"Authorization": f"Bearer {made['token']}"}}

    def revoke() -> None:
        assert srv.http.delete(f"/api/auth/tokens/{made['info']['id']}").status_code == 204

    code, reason, _ = asyncio.run(closed_after(url(srv, mid), revoke, **auth))
    assert (code, reason) == (4401, "session ended")
