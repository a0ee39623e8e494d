"""API tokens and users over real HTTP and the CLI: tokens created and revoked by their
owner (an admin: anyone's), shown once, listed by public id; users managed by admins, never
removing themselves or the last admin; each change in the audit trail."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import closing
from typing import Any

import httpx
import pytest

from tests.backend.server import USER, Server
from tests.backend.test_accounts import browser_like, cli, login


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("people") / "p.sqlite", "--no-demo").start()
    yield s
    s.close()


def add_user(srv: Server, name: str, role: str) -> None:
    r = srv.http.post("/api/users", json={"name": name, "role": role, "password": f"{name}-pass"})
    assert r.status_code == 201, r.text


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def audit(srv: Server, kind: str, at_least: int) -> list[dict[str, Any]]:
    """The service-wide trail's rows of a kind, oldest first (written behind the request)."""
    deadline = time.monotonic() + 5
    while True:
        r = srv.http.get("/api/audit", params={"kind": kind})
        assert r.status_code == 200, r.text
        rows: list[dict[str, Any]] = r.json()["rows"][::-1]
        if len(rows) >= at_least or time.monotonic() > deadline:
            return rows
        time.sleep(0.05)


def test_a_token_is_shown_once_listed_by_id_and_refused_once_revoked(srv: Server) -> None:
    add_user(srv, "olga", "observer")
    with closing(browser_like(srv)) as c:
        assert login(c, "olga", "olga-pass").status_code == 200
        c.headers["X-CSRF-Token"] = c.cookies["inbetrieb_csrf"]
        made = c.post("/api/auth/tokens", json={"label": "plot script"})
        assert made.status_code == 201, made.text
        token, info = made.json()["token"], made.json()["info"]
        assert (info["user"], info["label"]) == ("olga", "plot script")
        me = c.get("/api/auth/me", headers=bearer(token)).json()
        assert (me["name"], me["session"]) == ("olga", info["id"])  # the id control shows
        listed = c.get("/api/auth/tokens").json()
        assert [t["id"] for t in listed] == [info["id"]]
        assert token not in made.text.replace(token, "", 1)  # shown once, nowhere else
        assert token not in str(listed) and listed[0]["last_used_unix"] is not None
        assert c.get("/api/auth/tokens", params={"all": "true"}).status_code == 403
        # the admin sees everyone's; an observer cannot revoke another's
        everyone = srv.http.get("/api/auth/tokens", params={"all": "true"}).json()
        assert {t["user"] for t in everyone} >= {"olga", USER}
        mine = next(t for t in everyone if t["user"] == USER)
        assert c.delete(f"/api/auth/tokens/{mine['id']}").status_code == 403
        assert c.delete("/api/auth/tokens/token-0000000000000000").status_code == 404
        assert c.delete(f"/api/auth/tokens/{info['id']}").status_code == 204
        refused = c.get("/api/auth/me", headers=bearer(token))
        assert refused.status_code == 401 and "revoked" in refused.json()["detail"]["message"]
        assert c.get("/api/auth/tokens").json() == []
    rows = audit(srv, "token", 3)
    assert [(r["action"], r["outcome"][:7]) for r in rows[-3:]] == [
        (f"created API token {info['id']}", "ok"),
        (f"revoke API token {mine['id']}", "refused"),  # the observer's try on another's
        (f"revoked API token {info['id']}", "ok"),
    ]
    assert all(r["actor"] == "olga" and token not in str(r) for r in rows[-3:])


def test_tokens_on_the_command_line(srv: Server) -> None:
    made = srv.http.post("/api/auth/tokens", json={"label": "cli check"}).json()
    listed = cli(srv.db, "token", "list", "--user", USER)
    assert listed.returncode == 0
    line = next(x for x in listed.stdout.splitlines() if x.startswith(made["info"]["id"]))
    assert line.endswith("\tcli check") and made["token"] not in listed.stdout
    assert cli(srv.db, "token", "revoke", made["info"]["id"]).returncode == 0
    assert httpx.get(f"{srv.base}/api/auth/me", headers=bearer(made["token"])).status_code == 401
    again = cli(srv.db, "token", "revoke", made["info"]["id"])
    assert again.returncode == 2 and "no API token" in again.stderr


def test_admins_manage_users(srv: Server) -> None:
    add_user(srv, "otto", "operator")
    assert (
        srv.http.post(
            "/api/users", json={"name": "otto", "role": "observer", "password": "long enough"}
        ).json()["detail"]["message"]
        == "user 'otto' exists"
    )
    short = srv.http.post("/api/users", json={"name": "kurt", "password": "short"})
    assert short.status_code == 422 and "8" in short.text  # as the CLI: 8 characters at least
    with closing(browser_like(srv)) as c:
        assert login(c, "otto", "otto-pass").status_code == 200
        assert c.get("/api/users").status_code == 403  # an operator manages nobody
        r = srv.http.patch("/api/users/otto", json={"role": "instructor"})
        assert r.status_code == 200 and r.json()["role"] == "instructor"
        assert c.get("/api/auth/me").json()["role"] == "instructor"  # from the next request
        r = srv.http.patch("/api/users/otto", json={"password": "otto-new-pass"})
        assert r.status_code == 200
        assert c.get("/api/auth/me").status_code == 401  # a new password ends the sessions
        assert login(c, "otto", "otto-new-pass").status_code == 200
    assert srv.http.patch("/api/users/otto", json={}).status_code == 422
    assert srv.http.patch("/api/users/nobody", json={"role": "admin"}).status_code == 404
    assert srv.http.delete("/api/users/otto").status_code == 204
    assert "otto" not in [u["name"] for u in srv.http.get("/api/users").json()]
    assert [r["action"] for r in audit(srv, "user", 5)][-4:] == [
        "added user otto",
        "changed user otto",
        "changed user otto",
        "removed user otto",
    ]
    assert all("otto-new-pass" not in str(r) for r in audit(srv, "user", 5))


def test_nobody_removes_themselves_or_the_last_admin(srv: Server) -> None:
    me = srv.http.delete(f"/api/users/{USER}")
    assert me.status_code == 409 and "yourself" in me.json()["detail"]["message"]
    # the store's other admin (created at start without a password) goes; then USER is last
    admins = [u["name"] for u in srv.http.get("/api/users").json() if u["role"] == "admin"]
    for name in admins:
        if name != USER:
            assert srv.http.delete(f"/api/users/{name}").status_code == 204
    last = srv.http.patch(f"/api/users/{USER}", json={"role": "operator"})
    assert last.status_code == 409 and "last admin" in last.json()["detail"]["message"]
    add_user(srv, "ada", "admin")
    with closing(browser_like(srv)) as c:
        assert login(c, "ada", "ada-pass").status_code == 200
        c.headers["X-CSRF-Token"] = c.cookies["inbetrieb_csrf"]
        assert c.patch(f"/api/users/{USER}", json={"role": "operator"}).status_code == 200
        assert c.patch("/api/users/ada", json={"role": "observer"}).status_code == 409
        assert c.patch(f"/api/users/{USER}", json={"role": "admin"}).status_code == 200
