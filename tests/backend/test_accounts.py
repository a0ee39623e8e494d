"""People over real HTTP: logging in and out, sessions with CSRF tokens, expiry, the login
rate limit, one-time links, API tokens, the websocket handshake, and the `inbetrieb user` and
`token` commands on a real SQLite file."""

from __future__ import annotations

import asyncio
import re
import sqlite3
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import unquote

import httpx
import pytest
import websockets
from argon2 import PasswordHasher

from api.auth import Role
from backend.services.accounts import UNKNOWN_USER_HASH, Accounts
from backend.services.store import Store
from tests.backend.server import PASSWORD, ROOT, USER, Server

SPIN = {"type": "mdi", "block": "M3 S500"}


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("accounts") / "a.sqlite").start()
    yield s
    s.close()


def browser_like(srv: Server) -> httpx.Client:
    """A client with no token: only what it logs in with."""
    return httpx.Client(base_url=srv.base, timeout=10)


def login(c: httpx.Client, name: str = USER, password: str = PASSWORD) -> httpx.Response:
    return c.post("/api/auth/login", json={"name": name, "password": password})


def cli(db: Path, *args: str, stdin: str = "") -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "backend.cli", *args, "--db", str(db)]
    return subprocess.run(cmd, cwd=ROOT, input=stdin, capture_output=True, text=True, timeout=60)


def test_nothing_is_answered_to_a_stranger_but_health_and_login(srv: Server) -> None:
    with browser_like(srv) as c:
        assert c.get("/api/health").status_code == 200
        assert c.get("/api/machines").status_code == 401
        r = c.post("/api/machines/demo/commands", content=b"{not json")
        assert r.status_code == 401  # refused before the body is even looked at
        assert c.get("/rerun/").status_code == 401  # nobody else starts the viewer process
        assert c.get("/api/auth/me").status_code == 401
        wrong = c.get("/api/machines", headers={"Authorization": "Bearer not-a-token"})
        assert wrong.status_code == 401


def test_a_session_needs_its_csrf_token_to_change_anything(srv: Server, mid: str) -> None:
    with browser_like(srv) as c:
        r = login(c)
        assert r.status_code == 200 and (r.json()["name"], r.json()["role"]) == (USER, "admin")
        cookie = r.headers.get_list("set-cookie")
        session = next(h for h in cookie if h.startswith("inbetrieb_session="))
        assert "HttpOnly" in session and "SameSite=strict" in session.replace("Strict", "strict")
        csrf = c.cookies["inbetrieb_csrf"]
        assert c.get(f"/api/machines/{mid}/status").status_code == 200  # reading needs none
        url = f"/api/machines/{mid}/commands"
        refused = c.post(url, json=SPIN)
        assert refused.status_code == 403 and "X-CSRF-Token" in refused.json()["detail"]["message"]
        assert c.post(url, json=SPIN, headers={"X-CSRF-Token": "forged"}).status_code == 403
        assert srv.axis("S1", mid)["vel_cmd"] == 0.0  # nothing happened
        assert c.post(url, json=SPIN, headers={"X-CSRF-Token": csrf}).status_code == 200
        assert c.get("/api/auth/me").json()["name"] == USER
        assert c.post("/api/auth/logout").status_code == 204
        assert c.get("/api/auth/me").status_code == 401
    srv.command(mid, {"type": "spindle", "m": 5})


def test_an_expired_session_is_refused(srv: Server) -> None:
    with browser_like(srv) as c:
        assert login(c).status_code == 200
        assert c.get("/api/machines").status_code == 200
        with sqlite3.connect(srv.db) as db:  # the shift is over
            db.execute("UPDATE sessions SET expires = ?", (time.time() - 1,))
        r = c.get("/api/machines")
        assert r.status_code == 401 and "ended" in r.json()["detail"]["message"]


def test_wrong_passwords_are_refused_and_then_rate_limited(tmp_path: Path) -> None:
    s = Server(tmp_path / "limit.sqlite", "--no-demo").start()
    try:
        with browser_like(s) as c:
            for _ in range(5):
                r = login(c, password="wrong-password")
                assert r.status_code == 401 and r.json()["detail"]["message"]
            assert login(c, name="nobody").status_code == 429
            assert login(c).status_code == 429  # even the right password, for a minute
    finally:
        s.close()


def test_an_unknown_name_costs_a_login_as_much_as_a_known_one(tmp_path: Path) -> None:
    """An unknown name (or a user without a password) is checked against a constant hash with
    the hasher's own parameters: the same argon2 work, and it lets nobody in."""
    assert not PasswordHasher().check_needs_rehash(UNKNOWN_USER_HASH)
    store = Store(tmp_path / "a.sqlite")
    try:
        accounts = Accounts(store)
        accounts.add_user("ada", Role.OPERATOR, "a long password")
        accounts.add_user("nopass", Role.OBSERVER, None)
        assert accounts.check_password("ada", "a long password") is not None
        assert accounts.check_password("nobody", "a long password") is None
        assert accounts.check_password("nopass", "") is None
    finally:
        store.close()


def test_the_printed_login_link_works_once(tmp_path: Path) -> None:
    """`make run` on a fresh store: the first admin and a one-time link, as Jupyter does."""
    out = tmp_path / "out.txt"
    s = Server(tmp_path / "fresh.sqlite", "--no-demo", seed=False)
    with out.open("w") as f:
        s.start(stdout=f)
    try:
        link = re.search(r"Log in as admin .*: (http://\S+)", out.read_text())
        assert link, out.read_text()
        with browser_like(s) as c:
            first = c.get(link[1].replace("localhost", "127.0.0.1"))
            assert first.status_code == 303 and first.headers["location"] == "/"
            me = c.get("/api/auth/me").json()
            assert (me["name"], me["role"]) == ("admin", "admin")
        with browser_like(s) as c:
            again = c.get(link[1].replace("localhost", "127.0.0.1"))
            assert again.status_code == 401
            assert c.get("/api/auth/me").status_code == 401
    finally:
        s.close()


def test_the_websocket_needs_a_token_or_a_ticket(srv: Server, mid: str) -> None:
    """Not the session cookie alone (any page the browser shows would send it): a token, or
    a ticket (tests/backend/test_ws_sessions.py)."""
    url = f"{srv.ws_base}/api/machines/{mid}/telemetry"

    async def hello(**kw: object) -> str:
        try:
            async with websockets.connect(url, **kw) as ws:  # type: ignore[arg-type]
                return str(await asyncio.wait_for(ws.recv(), 10))
        except websockets.InvalidStatus as e:
            return f"refused {e.response.status_code}"

    assert asyncio.run(hello()) == "refused 403"
    assert '"hello"' in asyncio.run(hello(**srv.ws_auth))
    with browser_like(srv) as c:
        assert login(c).status_code == 200
        cookie = f"inbetrieb_session={c.cookies['inbetrieb_session']}"
    assert asyncio.run(hello(additional_headers={"Cookie": cookie})) == "refused 403"


def test_users_and_tokens_on_the_command_line(tmp_path: Path) -> None:
    db = tmp_path / "cli.sqlite"
    assert (
        cli(
            db,
            "user",
            "add",
            "ute",
            "--role",
            "operator",
            "--password-stdin",
            stdin="correct horse\n",
        ).returncode
        == 0
    )
    short = cli(db, "user", "add", "kim", "--password-stdin", stdin="short\n")
    assert short.returncode == 2 and "at least 8" in short.stderr
    assert cli(db, "user", "list").stdout.splitlines() == ["ute\toperator"]
    token = cli(db, "token", "create", "--user", "ute").stdout.strip()
    assert len(token) >= 40
    s = Server(db, "--no-demo").start()
    try:
        with browser_like(s) as c:
            me = c.get("/api/auth/me", headers={"Authorization": f"Bearer {token}"})
            assert (me.json()["name"], me.json()["role"]) == ("ute", "operator")
            assert login(c, "ute", "correct horse").status_code == 200
            assert (
                cli(
                    db, "user", "passwd", "ute", "--password-stdin", stdin="battery staple\n"
                ).returncode
                == 0
            )
            assert c.get("/api/auth/me").status_code == 401  # a new password ends sessions
            assert login(c, "ute", "battery staple").status_code == 200
        # the first login on a server, where nothing is printed at start
        link = cli(db, "user", "link", "ute", "--url", s.base + "/").stdout.strip()
        assert link.startswith(f"{s.base}/auth/once?token="), link
        path = link.removeprefix(s.base)
        with browser_like(s) as c:
            assert c.get(path, follow_redirects=False).status_code == 303
            assert c.get("/api/auth/me").json()["name"] == "ute"
        with browser_like(s) as c:
            assert c.get(path, follow_redirects=False).status_code == 401  # good once
        with browser_like(s) as c:
            assert login(c, "ute", "battery staple").status_code == 200
            assert cli(db, "user", "remove", "ute").returncode == 0
            gone = c.get("/api/auth/me", headers={"Authorization": f"Bearer {token}"})
            assert gone.status_code == 401  # their token went with them
    finally:
        s.close()
    assert cli(db, "token", "create", "--user", "ute").returncode == 2


def test_a_viewer_ticket_opens_one_trace_once(srv: Server) -> None:
    """The Rerun viewer's loader sends no cookie: the viewer link carries a ticket for the
    one .rrd request, good once, for that trace only."""
    csv = "cycle,X.pos_act_mm\n0,1.0\n1,2.0\n"
    r = srv.http.post("/api/traces/import", content=csv, headers={"Content-Type": "text/csv"})
    assert r.status_code == 201, r.text
    tid = r.json()["id"]
    go = srv.http.get(f"/api/traces/{tid}/viewer", follow_redirects=False)
    rrd_url = unquote(re.search(r"url=([^&]+)", go.headers["location"])[1])  # type: ignore[index]
    path, ticket = rrd_url.split(srv.base, 1)[1].split("?ticket=")
    assert path == f"/api/traces/{tid}/trace.rrd"
    with browser_like(srv) as c:
        assert c.get(f"/api/traces/{tid}/data?ticket={ticket}").status_code == 401  # that path only
        first = c.get(f"{path}?ticket={ticket}")
        assert first.status_code == 200 and first.content[:4] == b"RRF2"  # a Rerun file
        assert c.get(f"{path}?ticket={ticket}").status_code == 401  # used up
