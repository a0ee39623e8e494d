"""One operator per machine over real HTTP and websockets: requests and grants, taking,
the lapse after the holder's connection is lost, logout, a held jog that belongs to its
holder, and parameter writes that carry the version they were based on."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from websockets.asyncio.client import connect

from api.auth import Role
from tests.backend.server import OTHERS_PASSWORD, Server, add_users, bearer

# the service's grace period in these tests (INBETRIEB_CONTROL_GRACE_S): a script's control
# lapses that long after its last request, so it outlasts a test's steps on a loaded machine
GRACE_S = 3.0
KV = {"scope": "axis", "target": "X", "name": "getriebe[0].kv"}


@pytest.fixture(scope="module")
def people(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Server, dict[str, str]]]:
    db = tmp_path_factory.mktemp("control") / "db.sqlite"
    tokens = add_users(
        db,
        {
            "otto": Role.OPERATOR,
            "ona": Role.OPERATOR,
            "ida": Role.INSTRUCTOR,
            "olga": Role.OBSERVER,
        },
    )
    s = Server(db, "--no-demo", env={"INBETRIEB_CONTROL_GRACE_S": str(GRACE_S)}).start()
    yield s, tokens
    s.close()


@pytest.fixture
def srv(people: tuple[Server, dict[str, str]]) -> Server:
    return people[0]  # for the `mid` fixture: a fresh machine per test


@pytest.fixture
def tokens(people: tuple[Server, dict[str, str]]) -> dict[str, str]:
    return people[1]


def act(s: Server, token: str, mid: str, action: str, **kw: str) -> httpx.Response:
    return s.http.post(
        f"/api/machines/{mid}/control", json={"action": action, **kw}, headers=bearer(token)
    )


def state(s: Server, mid: str) -> dict[str, Any]:
    body: dict[str, Any] = s.http.get(f"/api/machines/{mid}/control").json()
    return body


def command(s: Server, token: str, mid: str, body: dict[str, Any]) -> httpx.Response:
    return s.http.post(f"/api/machines/{mid}/commands", json=body, headers=bearer(token))


def wait_for(pred: Any, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not pred():
        assert time.monotonic() < deadline, "not reached"
        time.sleep(0.05)


def test_a_request_granted_moves_control_and_a_refused_one_does_not(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    otto, ona = tokens["otto"], tokens["ona"]
    assert state(srv, mid)["holder"] is None
    assert act(srv, otto, mid, "take").json()["holder"]["user"] == "otto"
    assert act(srv, ona, mid, "take").status_code == 403  # an operator asks, does not take
    refused = command(srv, ona, mid, {"type": "reset"})
    assert refused.status_code == 403
    assert "held by otto (operator)" in refused.json()["detail"]["message"]
    asked = act(srv, ona, mid, "request").json()
    ona_party = asked["requests"][0]
    assert (ona_party["user"], asked["holder"]["user"]) == ("ona", "otto")
    assert act(srv, ona, mid, "grant", session=ona_party["session"]).status_code == 403
    who = {"session": ona_party["session"], "client": ona_party["client"]}
    assert act(srv, otto, mid, "refuse", **who).json()["requests"] == []
    assert state(srv, mid)["holder"]["user"] == "otto"
    act(srv, ona, mid, "request")
    granted = act(srv, otto, mid, "grant", **who).json()
    assert granted["holder"]["user"] == "ona" and granted["requests"] == []
    assert command(srv, ona, mid, {"type": "reset"}).status_code == 200
    assert command(srv, otto, mid, {"type": "reset"}).status_code == 403


def test_an_observer_asks_with_a_message_but_is_never_granted_control(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    """A remote observer may ask for the holder's attention with a word; the holder sees it,
    can only answer it (granting would not let an observer command: 409, the request kept);
    taking or releasing stays refused to observers, and the refusal is audited."""
    otto, olga = tokens["otto"], tokens["olga"]
    act(srv, otto, mid, "take").raise_for_status()
    taken = act(srv, olga, mid, "take")
    assert taken.status_code == 403 and "may not take or hand over control" in taken.text
    asked = act(srv, olga, mid, "request", message="  may I watch S1 at 3000 rpm?  ").json()
    party = asked["requests"][0]
    assert (party["user"], party["message"]) == ("olga", "may I watch S1 at 3000 rpm?")
    too_long = act(srv, olga, mid, "request", message="x" * 301)
    assert too_long.status_code == 422
    who = {"session": party["session"], "client": party["client"]}
    granted = act(srv, otto, mid, "grant", **who)
    assert granted.status_code == 409 and "may watch only" in granted.text
    assert [r["user"] for r in state(srv, mid)["requests"]] == ["olga"]
    assert act(srv, otto, mid, "refuse", **who).json()["requests"] == []
    rows = srv.http.get(f"/api/machines/{mid}/history", params={"kind": "control"}).json()
    texts = [(r["actor"], r["text"], r["outcome"]) for r in rows["rows"]]
    assert ("olga", "requested control from otto (operator): “may I watch S1 at 3000 rpm?”",
            "ok") in texts  # fmt: skip
    assert any(a == "olga" and t == "take" and o.startswith("refused (403)") for a, t, o in texts)


def test_an_instructor_takes_control_and_the_old_holders_jog_stops(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    otto, ida = tokens["otto"], tokens["ida"]
    jog = {"type": "jog", "axis": "X", "action": "start", "direction": 1, "hold_s": 5.0}
    assert command(srv, otto, mid, jog).status_code == 200  # a free machine: taken by acting
    wait_for(lambda: srv.axis("X", mid)["vel_act"] > 100)
    assert act(srv, ida, mid, "take").json()["holder"]["user"] == "ida"
    # the lease would run 5 s more; the jog belongs to otto's control, which is gone
    wait_for(lambda: srv.axis("X", mid)["state"] == "STANDSTILL", timeout_s=3.0)
    assert command(srv, otto, mid, jog).status_code == 403  # the renewal is refused


def test_anyone_who_may_command_may_stop_the_machine_without_control(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    assert act(srv, tokens["otto"], mid, "take").status_code == 200
    stop = srv.http.post(f"/api/machines/{mid}/emergency-stop", headers=bearer(tokens["ona"]))
    assert stop.status_code == 200
    assert srv.status(mid)["emergency_stop"]
    observer = srv.http.post(f"/api/machines/{mid}/emergency-stop", headers=bearer(tokens["olga"]))
    assert observer.status_code == 403


def test_control_lapses_after_the_grace_period_once_the_holders_socket_closes(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    otto = tokens["otto"]
    url = f"{srv.ws_base}/api/machines/{mid}/telemetry?client=tab-1"

    async def watch_and_take() -> dict[str, Any]:
        async with connect(url, additional_headers=bearer(otto)) as ws:
            await ws.recv()  # hello
            r = srv.http.post(
                f"/api/machines/{mid}/control",
                json={"action": "take"},
                headers=bearer(otto) | {"X-Inbetrieb-Client": "tab-1"},
            )
            held: dict[str, Any] = r.json()
            return held

    held = asyncio.run(watch_and_take())
    assert held["holder"]["client"] == "tab-1" and held["connected"]
    lost = state(srv, mid)  # the socket closed: the grace period runs
    assert lost["holder"]["user"] == "otto" and not lost["connected"]
    assert lost["release_at_unix"] is not None
    wait_for(lambda: state(srv, mid)["holder"] is None, timeout_s=GRACE_S + 5)


def test_the_same_user_in_another_tab_does_not_hold_control(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    otto = tokens["otto"]
    tab = {"X-Inbetrieb-Client": "tab-a"}
    r = srv.http.post(
        f"/api/machines/{mid}/control", json={"action": "take"}, headers=bearer(otto) | tab
    )
    assert r.json()["holder"]["client"] == "tab-a"
    other = srv.http.post(
        f"/api/machines/{mid}/commands",
        json={"type": "reset"},
        headers=bearer(otto) | {"X-Inbetrieb-Client": "tab-b"},
    )
    assert other.status_code == 403 and "another tab" in other.json()["detail"]["message"]
    over = srv.http.post(
        f"/api/machines/{mid}/control",
        json={"action": "take"},
        headers=bearer(otto) | {"X-Inbetrieb-Client": "tab-b"},
    )
    assert over.json()["holder"]["client"] == "tab-b"  # one's own control: taken over


def test_logging_out_releases_control(srv: Server, mid: str) -> None:
    with httpx.Client(base_url=srv.base, timeout=10) as c:
        assert c.post("/api/auth/login", json={"name": "ona", "password": OTHERS_PASSWORD})
        csrf = {"X-CSRF-Token": c.cookies["inbetrieb_csrf"]}
        r = c.post(f"/api/machines/{mid}/control", json={"action": "take"}, headers=csrf)
        assert r.json()["holder"]["user"] == "ona"
        assert c.post("/api/auth/logout", headers=csrf).status_code == 204
    assert state(srv, mid)["holder"] is None


def _kv(s: Server, token: str, mid: str) -> dict[str, Any]:
    values = s.http.get(
        f"/api/machines/{mid}/parameters",
        params={"scope": "axis", "target": "X"},
        headers=bearer(token),
    ).json()
    return next(v for v in values if v["name"] == KV["name"])


def _write(s: Server, token: str, mid: str, value: float, base: int | None) -> httpx.Response:
    change = KV | {"value": value, "base_version": base}
    return s.http.patch(
        f"/api/machines/{mid}/parameters", json={"changes": [change]}, headers=bearer(token)
    )


def test_a_write_over_a_newer_value_is_refused_with_both_values(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    otto, ona = tokens["otto"], tokens["ona"]
    seen_by_ona = _kv(srv, ona, mid)  # both read the same value
    assert _write(srv, otto, mid, 150.0, _kv(srv, otto, mid)["version"]).status_code == 200
    act(srv, otto, mid, "release")
    stale = _write(srv, ona, mid, 300.0, seen_by_ona["version"])
    assert stale.status_code == 409
    detail = stale.json()["detail"]
    [both] = detail["stale"]
    assert (both["yours"], both["current"], both["by"]) == (300.0, 150.0, "otto")
    assert _kv(srv, ona, mid)["value"] == 150.0  # nothing was written
    again = _write(srv, ona, mid, 300.0, both["version"])  # "write mine anyway", knowingly
    assert again.status_code == 200 and _kv(srv, ona, mid)["value"] == 300.0
    assert _kv(srv, ona, mid)["version"] > both["version"]
    audit = srv.http.get(
        f"/api/machines/{mid}/audit", params={"kind": "parameter", "actor": "ON"}
    ).json()["rows"]  # part of the name, any case
    assert {r["actor"] for r in audit} == {"ona"}
    assert [r["outcome"][:13] for r in audit] == ["ok", "refused (409)"]  # newest first


def test_a_user_acting_through_another_session_is_told_to_release_it_there(
    srv: Server, mid: str, tokens: dict[str, str]
) -> None:
    assert act(srv, tokens["otto"], mid, "take").status_code == 200  # otto's script
    with httpx.Client(base_url=srv.base, timeout=10) as c:
        c.post("/api/auth/login", json={"name": "otto", "password": OTHERS_PASSWORD})
        csrf = {"X-CSRF-Token": c.cookies["inbetrieb_csrf"]}
        r = c.post(f"/api/machines/{mid}/commands", json={"type": "reset"}, headers=csrf)
    assert r.status_code == 403
    assert "held by otto (operator) in another session" in r.json()["detail"]["message"]
