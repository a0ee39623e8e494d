"""The authorization matrix over real HTTP and websockets: every route of the OpenAPI schema
(and the websocket and the viewer proxy, which the schema does not list) × every role ×
holder / non-holder of the machine's control.

The expected rule of each route is written here from the issue's roles, not read from the
service: observers watch, capture and save traces and read programs; operators also command,
jog and write parameters while holding control, record, delete traces, write programs, sign
reports off and ask for control; instructors also pace the simulation and take control; admins
also manage machines, users and the whole audit trail. A route missing from RULES (a new one)
fails `test_every_route_has_a_rule`.
"""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from websockets.asyncio.client import connect
from websockets.exceptions import InvalidStatus

from api.auth import CSRF_COOKIE, CSRF_HEADER, Role
from tests.backend.server import Server, add_users

ROLES = ["observer", "operator", "instructor", "admin"]
HELD = "held"  # only the control holder (a free machine is taken by the first such request)
FREE = "free"

# (method, path) -> (the least role that may, whether only the control holder may)
RULES: dict[tuple[str, str], tuple[str, str]] = {
    ("GET", "/api/auth/me"): ("observer", FREE),
    ("GET", "/api/service/status"): ("observer", FREE),
    ("GET", "/metrics"): ("observer", FREE),
    ("GET", "/api/machines"): ("observer", FREE),
    ("GET", "/api/assistants"): ("observer", FREE),
    ("POST", "/api/machines"): ("admin", FREE),
    ("GET", "/api/machines/{mid}/status"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/service-axes"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/signals"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/restart"): ("operator", HELD),
    ("DELETE", "/api/machines/{mid}"): ("admin", FREE),
    ("POST", "/api/machines/{mid}/simulation"): ("instructor", FREE),
    ("POST", "/api/machines/{mid}/simulation/step"): ("instructor", FREE),
    ("POST", "/api/machines/{mid}/commands"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/emergency-stop"): ("operator", FREE),
    ("GET", "/api/machines/{mid}/control"): ("observer", FREE),
    # observers may ask for control (with a message); taking, granting, releasing: operators
    ("POST", "/api/machines/{mid}/control"): ("observer", FREE),
    ("GET", "/api/parameters"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/parameters"): ("observer", FREE),
    ("PATCH", "/api/machines/{mid}/parameters"): ("operator", HELD),
    ("GET", "/api/machines/{mid}/parameters/export"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/parameters/import"): ("operator", HELD),
    ("GET", "/api/machines/{mid}/parameters/audit"): ("observer", FREE),
    # versions change no value (a rollback writes values: held, as a parameter write)
    ("GET", "/api/machines/{mid}/versions"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/versions"): ("operator", FREE),
    ("GET", "/api/machines/{mid}/versions/diff"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/versions/{vid}/baseline"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/versions/{vid}/rollback"): ("operator", HELD),
    ("DELETE", "/api/machines/{mid}/versions/{vid}"): ("operator", FREE),
    ("GET", "/api/machines/{mid}/scope"): ("observer", FREE),
    ("PUT", "/api/machines/{mid}/scope"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/scope/force"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/scope/stop"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/scope/roll"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/recording"): ("operator", FREE),
    ("DELETE", "/api/machines/{mid}/recording"): ("operator", FREE),
    ("GET", "/api/recordings/{rid}/recording.rrd"): ("observer", FREE),
    ("GET", "/api/recordings/{rid}/viewer"): ("observer", FREE),
    ("GET", "/api/traces"): ("observer", FREE),
    ("GET", "/api/traces/compare"): ("observer", FREE),
    ("POST", "/api/traces/import"): ("observer", FREE),
    ("GET", "/api/traces/{tid}"): ("observer", FREE),
    ("PATCH", "/api/traces/{tid}"): ("observer", FREE),
    ("DELETE", "/api/traces/{tid}"): ("operator", FREE),
    ("GET", "/api/traces/{tid}/data"): ("observer", FREE),
    ("GET", "/api/traces/{tid}/csv"): ("observer", FREE),
    ("GET", "/api/traces/{tid}/trace.rrd"): ("observer", FREE),
    ("GET", "/api/traces/{tid}/viewer"): ("observer", FREE),
    ("GET", "/api/traces/{tid}/measure"): ("observer", FREE),
    ("POST", "/api/traces/{tid}/save"): ("observer", FREE),
    ("GET", "/api/programs"): ("observer", FREE),
    ("GET", "/api/programs/{name}"): ("observer", FREE),
    ("PUT", "/api/programs/{name}"): ("operator", FREE),  # programs are service-wide
    ("DELETE", "/api/programs/{name}"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/program-preview"): ("observer", FREE),  # changes nothing
    # on a copy of the machine: changes nothing, but runs a process for seconds
    ("POST", "/api/machines/{mid}/assist/multi-gain"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/sign-check"): ("operator", FREE),
    ("GET", "/api/machines/{mid}/assist/runs"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/assist/runs/{run_id}"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/report"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/report.pdf"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/report/sign-offs"): ("observer", FREE),
    # a statement about the machine, not a change to it: no control needed
    ("POST", "/api/machines/{mid}/report/sign-off"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/loop-gain"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/curve-run-up"): ("operator", FREE),
    # the calculators and the gear-range preview: pure arithmetic, proposals to apply
    ("POST", "/api/machines/{mid}/assist/resolution"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/multi-gain-calc"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/speed-scaling"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/curve-fit"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/gear-ranges"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/live/multi-gain"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/live/sign-check"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/resolution-check"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/live/resolution-check"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/frequency-response"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/live/frequency-response"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/step-response"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/live/step-response"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/drive-trace"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/circle"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/live/circle"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/autotune"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/assist/live/autotune"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/live/drive-trace"): ("operator", HELD),
    ("POST", "/api/machines/{mid}/assist/live/cancel"): ("operator", FREE),
    ("GET", "/api/machines/{mid}/audit"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/audit.csv"): ("observer", FREE),
    # the history: everyone who watches reads it, writes in its logbook, acknowledges errors
    ("GET", "/api/machines/{mid}/history"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/history/export"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/history/notes"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/history/acknowledge"): ("observer", FREE),
    # the flight recorder and bundles: read-only data; saving traces is the scope's right
    ("GET", "/api/machines/{mid}/flight-recorder"): ("observer", FREE),
    ("POST", "/api/machines/{mid}/flight-recorder/save"): ("observer", FREE),
    ("GET", "/api/machines/{mid}/bundle"): ("observer", FREE),
    ("POST", "/api/bundles"): ("observer", FREE),
    ("GET", "/api/bundles"): ("observer", FREE),
    ("GET", "/api/bundles/{bid}"): ("observer", FREE),
    ("GET", "/api/bundles/{bid}/history"): ("observer", FREE),
    ("GET", "/api/bundles/{bid}/lists/{name}"): ("observer", FREE),
    ("DELETE", "/api/bundles/{bid}"): ("operator", FREE),
    # share links for guests: an operator's to make, list and revoke (no control needed)
    ("POST", "/api/machines/{mid}/share"): ("operator", FREE),
    ("GET", "/api/machines/{mid}/share"): ("operator", FREE),
    ("DELETE", "/api/machines/{mid}/share/{lid}"): ("operator", FREE),
    ("GET", "/api/fleet"): ("observer", FREE),
    ("GET", "/api/audit"): ("admin", FREE),
    ("GET", "/api/audit.csv"): ("admin", FREE),
    ("GET", "/api/audit/verify"): ("admin", FREE),
    ("POST", "/api/auth/ws-ticket"): ("observer", FREE),
    ("GET", "/api/auth/tokens"): ("observer", FREE),  # everyone's (?all=true): admins
    ("POST", "/api/auth/tokens"): ("observer", FREE),
    ("DELETE", "/api/auth/tokens/{tid}"): ("observer", FREE),  # another's: admins
    # training: instructors run classes, inject faults (a student must not read them), take
    # and restore snapshots (pacing); a seat's student reads their exercise and takes hints
    ("GET", "/api/exercises"): ("instructor", FREE),
    ("POST", "/api/exercises"): ("instructor", FREE),
    ("GET", "/api/classes"): ("instructor", FREE),
    ("POST", "/api/classes"): ("instructor", FREE),
    ("GET", "/api/classes/{cid}"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/end"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/freeze"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/next"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/present"): ("instructor", FREE),
    ("GET", "/api/classes/{cid}/seats/{n}/replay"): ("instructor", FREE),
    ("GET", "/api/roster"): ("instructor", FREE),
    ("POST", "/api/exercises/dry-run"): ("instructor", FREE),
    ("GET", "/api/exercises/{eid}/text"): ("instructor", FREE),
    ("DELETE", "/api/exercises/{eid}"): ("instructor", FREE),
    ("GET", "/api/roster/{pid}"): ("instructor", FREE),
    ("DELETE", "/api/roster/{pid}"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/broadcast"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/faults"): ("instructor", FREE),
    ("GET", "/api/classes/{cid}/seats/{n}"): ("instructor", FREE),
    ("GET", "/api/classes/{cid}/seats/{n}/history"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/seats/{n}/link"): ("instructor", FREE),
    ("POST", "/api/classes/{cid}/seats/{n}/reset"): ("instructor", FREE),
    ("DELETE", "/api/classes/{cid}"): ("instructor", FREE),
    ("GET", "/api/classes/{cid}/results.csv"): ("instructor", FREE),
    ("GET", "/api/classes/{cid}/results.pdf"): ("instructor", FREE),
    ("GET", "/api/machines/{mid}/faults"): ("instructor", FREE),
    ("POST", "/api/machines/{mid}/faults"): ("instructor", FREE),
    ("DELETE", "/api/machines/{mid}/faults/{fid}"): ("instructor", FREE),
    ("GET", "/api/machines/{mid}/snapshots"): ("instructor", FREE),
    ("POST", "/api/machines/{mid}/snapshots"): ("instructor", FREE),
    ("POST", "/api/machines/{mid}/snapshots/{sid}/restore"): ("instructor", FREE),
    ("GET", "/api/machines/{mid}/exercise"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/exercise/hints"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/exercise/findings"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/exercise/hand"): ("operator", FREE),
    ("POST", "/api/machines/{mid}/exercise/next"): ("operator", FREE),
    ("GET", "/api/users"): ("admin", FREE),
    ("POST", "/api/users"): ("admin", FREE),
    ("PATCH", "/api/users/{name}"): ("admin", FREE),
    ("DELETE", "/api/users/{name}"): ("admin", FREE),
}
OPEN = {
    ("GET", "/api/health"),
    ("POST", "/api/auth/login"),
    ("POST", "/api/auth/logout"),
    ("GET", "/api/auth/seat-result"),
}
MACHINE = "m1"  # the machine whose control matters; other routes name ones that do not exist


def allowed(role: str, least: str) -> bool:
    return ROLES.index(role) >= ROLES.index(least)


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Server, dict[str, str]]]:
    """A service with a user of every role (and a second operator), each with a token."""
    db = tmp_path_factory.mktemp("authz") / "db.sqlite"
    tokens = add_users(
        db,
        {
            "olga": Role.OBSERVER,
            "otto": Role.OPERATOR,
            "ona": Role.OPERATOR,
            "ida": Role.INSTRUCTOR,
            "ada": Role.ADMIN,
        },
    )
    s = Server(db, "--no-demo").start()
    s.http.post("/api/machines", json={"id": MACHINE, "demo": True}).raise_for_status()
    try:
        yield s, tokens
    finally:
        s.close()


USER_OF = {"observer": "olga", "operator": "otto", "instructor": "ida", "admin": "ada"}


def _filled(path: str, mid: str) -> str:
    return (
        path.replace("{mid}", mid)
        .replace("{tid}", "nope")
        .replace("{rid}", "nope")
        .replace("{id}", "nope")
        .replace("{run_id}", "1")
        .replace("{vid}", "nope")
        .replace("{name}", "nobody")
        .replace("{cid}", "nope")
        .replace("{n}", "1")
        .replace("{fid}", "1")
        .replace("{sid}", "1")
        .replace("{pid}", "999")
        .replace("{eid}", "nope")
        .replace("{bid}", "0123456789ab")
        .replace("{lid}", "0123456789ab")
    )


def call(s: Server, token: str, method: str, path: str, mid: str) -> httpx.Response:
    """The route with placeholders filled and a body that fails validation (nothing is
    changed by an allowed call: it stops at 422, or at 404 for an unknown id)."""
    url = _filled(path, mid)
    kw: dict[str, Any] = {"headers": {"Authorization": f"Bearer {token}"}}
    if method in ("POST", "PUT", "PATCH"):
        kw["json"] = {"bad": True}
    return s.http.request(method, url, **kw)


def control(s: Server, token: str, action: str) -> dict[str, Any]:
    r = s.http.post(
        f"/api/machines/{MACHINE}/control",
        json={"action": action},
        headers={"Authorization": f"Bearer {token}"},
    )
    assert r.status_code == 200, r.text
    body: dict[str, Any] = r.json()
    return body


def test_every_route_has_a_rule(srv: tuple[Server, dict[str, str]]) -> None:
    s, _ = srv
    schema = s.http.get("/openapi.json").json()
    routes = {(m.upper(), p) for p, ops in schema["paths"].items() for m in ops}
    assert routes - set(RULES) - OPEN == set(), "routes without a rule in this matrix"
    assert set(RULES) - routes == set(), "rules of routes that are gone"


@pytest.mark.parametrize(("method", "path"), sorted(RULES), ids=lambda v: str(v))
def test_each_role_gets_what_its_rule_says(
    srv: tuple[Server, dict[str, str]], method: str, path: str
) -> None:
    s, tokens = srv
    least, held = RULES[(method, path)]
    if held == HELD:
        _check_held(s, tokens, method, path, least)
        return
    for role in ROLES:
        r = call(s, tokens[USER_OF[role]], method, path, "gone")
        if allowed(role, least):
            assert r.status_code not in (401, 403), f"{role}: {r.status_code} {r.text}"
        else:
            assert r.status_code == 403, f"{role} was let through: {r.status_code} {r.text}"
            assert USER_OF[role] in r.json()["detail"]["message"]


def _check_held(s: Server, tokens: dict[str, str], method: str, path: str, least: str) -> None:
    """Role first; then only the holder; a free machine goes to the first who acts."""
    observer = call(s, tokens["olga"], method, path, MACHINE)
    assert observer.status_code == 403 and "olga" in observer.text
    assert control(s, tokens["otto"], "take")["holder"]["user"] == "otto"
    try:
        for other in ("ona", "ida", "ada"):  # another operator, and those who may take it
            r = call(s, tokens[other], method, path, MACHINE)
            assert r.status_code == 403, f"{other} acted without control: {r.text}"
            assert "held by otto (operator)" in r.json()["detail"]["message"]
        mine = call(s, tokens["otto"], method, path, MACHINE)
        assert mine.status_code not in (401, 403), mine.text
    finally:
        control(s, tokens["otto"], "release")
    free = call(s, tokens["ida"], method, path, MACHINE)
    assert free.status_code not in (401, 403), free.text
    state = s.http.get(f"/api/machines/{MACHINE}/control").json()
    assert state["holder"]["user"] == "ida"  # the free machine went to who acted
    control(s, tokens["ida"], "release")


# observer-level routes a share link's guest may not use: it only watches (api/auth.py),
# and offline machines are nobody's through a link
GUEST_REFUSED = {
    ("PUT", "/api/machines/{mid}/scope"),
    ("POST", "/api/machines/{mid}/scope/force"),
    ("POST", "/api/machines/{mid}/scope/stop"),
    ("POST", "/api/machines/{mid}/control"),
    ("POST", "/api/machines/{mid}/history/notes"),
    ("POST", "/api/machines/{mid}/history/acknowledge"),
    ("POST", "/api/machines/{mid}/flight-recorder/save"),
    ("GET", "/api/machines/{mid}/bundle"),
    ("GET", "/api/recordings/{rid}/viewer"),
    ("POST", "/api/traces/import"),
    ("PATCH", "/api/traces/{tid}"),
    ("POST", "/api/traces/{tid}/save"),
    ("GET", "/api/traces/{tid}/viewer"),
    ("POST", "/api/auth/tokens"),
    ("DELETE", "/api/auth/tokens/{tid}"),
    ("POST", "/api/bundles"),
    ("GET", "/api/bundles"),
    ("GET", "/api/bundles/{bid}"),
    ("GET", "/api/bundles/{bid}/history"),
    ("GET", "/api/bundles/{bid}/lists/{name}"),
}


def test_a_share_link_guest_only_watches_its_machine(srv: tuple[Server, dict[str, str]]) -> None:
    """Through a share link: what an observer may, minus every change (and offline
    machines); the machine of the link only; everything above observer refused."""
    s, _ = srv
    made = s.http.post(f"/api/machines/{MACHINE}/share", json={"hours": 1}).json()
    with httpx.Client(base_url=s.base, timeout=10) as guest:
        assert guest.get(made["url"].removeprefix(s.base)).status_code == 303
        csrf = {CSRF_HEADER: guest.cookies[CSRF_COOKIE]}
        for (method, path), (least, _) in sorted(RULES.items()):
            url = _filled(path, MACHINE)
            kw: dict[str, Any] = {"headers": csrf}
            if method in ("POST", "PUT", "PATCH"):
                kw["json"] = {"bad": True}
            r = guest.request(method, url, **kw)
            refused = least != "observer" or (method, path) in GUEST_REFUSED
            if refused:
                assert r.status_code in (403, 404), f"{method} {path}: {r.status_code} {r.text}"
            else:
                assert r.status_code not in (401, 403), f"{method} {path}: {r.text}"
        other = guest.get("/api/machines/demo-elsewhere/status")
        assert other.status_code == 404


def test_a_stranger_gets_401_on_every_route(srv: tuple[Server, dict[str, str]]) -> None:
    s, _ = srv
    with httpx.Client(base_url=s.base, timeout=10) as c:
        for method, path in RULES:
            r = c.request(
                method,
                path.replace("{mid}", MACHINE)
                .replace("{tid}", "x")
                .replace("{rid}", "x")
                .replace("{id}", "x")
                .replace("{run_id}", "1")
                .replace("{vid}", "x")
                .replace("{name}", "x")
                .replace("{cid}", "x")
                .replace("{n}", "1")
                .replace("{fid}", "1")
                .replace("{sid}", "1"),
            )
            assert r.status_code == 401, (method, path, r.status_code)
        assert c.get("/rerun/").status_code == 401


def test_every_role_may_watch_the_telemetry_websocket_and_a_stranger_may_not(
    srv: tuple[Server, dict[str, str]],
) -> None:
    s, tokens = srv

    async def hello(headers: dict[str, str]) -> str:
        url = f"{s.ws_base}/api/machines/{MACHINE}/telemetry"
        async with connect(url, additional_headers=headers) as ws:
            return str(await asyncio.wait_for(ws.recv(), 10))

    for role, user in USER_OF.items():
        text = asyncio.run(hello({"Authorization": f"Bearer {tokens[user]}"}))
        assert '"type":"hello"' in text, role
    with pytest.raises(InvalidStatus) as refused:
        asyncio.run(hello({}))
    assert refused.value.response.status_code == 403


def test_the_viewer_proxy_needs_a_role_that_may_capture(
    srv: tuple[Server, dict[str, str]],
) -> None:
    s, tokens = srv
    r = s.http.get(
        "/rerun", headers={"Authorization": f"Bearer {tokens['olga']}"}, follow_redirects=False
    )
    assert r.status_code == 307  # an observer may open the viewer (watching traces)


def test_an_observer_cannot_take_grant_or_release_control(
    srv: tuple[Server, dict[str, str]],
) -> None:
    """... but may ask its holder (test_control.py); a free machine has nobody to ask."""
    s, tokens = srv
    for action in ("take", "grant", "refuse", "release", "request"):
        r = s.http.post(
            f"/api/machines/{MACHINE}/control",
            json={"action": action},
            headers={"Authorization": f"Bearer {tokens['olga']}"},
        )
        if action == "request":
            assert r.status_code == 409 and "nobody holds" in r.text
        else:
            assert r.status_code == 403 and "may not take or hand over control" in r.text


def test_a_refusal_says_the_action_in_words_and_the_role_it_takes(
    srv: tuple[Server, dict[str, str]],
) -> None:
    """An observer deleting a trace: 'may not delete traces: that takes the role operator or
    above', never the internal action name (it read 'may not delete_trace')."""
    s, tokens = srv
    r = s.http.delete("/api/traces/nope", headers={"Authorization": f"Bearer {tokens['olga']}"})
    assert r.status_code == 403
    message = r.json()["detail"]["message"]
    assert "may not delete traces: that takes the role operator or above" in message
    assert "delete_trace" not in message


def test_a_student_reaches_their_seats_recordings_only(
    srv: tuple[Server, dict[str, str]],
) -> None:
    """A class's student (an operator of their seat) gets their seat machine's recording;
    another seat's is a 404, as if it did not exist (the .rrd and the viewer alike)."""
    s, tokens = srv
    ida = {"Authorization": f"Bearer {tokens['ida']}"}
    r = s.http.post(
        "/api/classes", json={"id": "rec", "exercises": ["sign-error"], "seats": 2}, headers=ida
    )
    assert r.status_code == 201, r.text
    link = r.json()["links"][0]["url"].replace(s.base, "")
    rids = []
    for mid in ("rec-s01", "rec-s02"):
        sigs = [g["name"] for g in s.http.get(f"/api/machines/{mid}/signals").json()][:4]
        started = s.http.post(f"/api/machines/{mid}/recording", json={"signals": sigs})
        assert started.status_code == 201, started.text
        rids.append(started.json()["id"])
    with httpx.Client(base_url=s.base, timeout=30) as student:
        assert student.get(link, follow_redirects=False).status_code == 303
        assert student.get(f"/api/recordings/{rids[0]}/recording.rrd").status_code == 200
        other = student.get(f"/api/recordings/{rids[1]}/recording.rrd")
        assert other.status_code == 404, other.text
        viewer = student.get(f"/api/recordings/{rids[1]}/viewer", follow_redirects=False)
        assert viewer.status_code == 404, viewer.text
        mine = student.get(f"/api/recordings/{rids[0]}/viewer", follow_redirects=False)
        assert mine.status_code == 307, mine.text
    # the instructor reaches both
    assert s.http.get(f"/api/recordings/{rids[1]}/recording.rrd", headers=ida).status_code == 200
    assert s.http.post("/api/classes/rec/end", headers=ida).status_code == 200


def test_a_student_writes_and_deletes_only_their_seats_programs(
    srv: tuple[Server, dict[str, str]],
) -> None:
    """The probe's seat listed every program, wrote its own and deleted one an admin wrote.
    A student reads the service-wide programs (the instructor's) and their seat's own; what
    they write is their seat's (another seat never sees it, nor does the shared list); they
    delete only their own (the shared one: 403)."""
    s, tokens = srv
    ida = {"Authorization": f"Bearer {tokens['ida']}"}
    shared = "%MAIN\nG01 X10 F100\nM30\n"
    assert s.http.put("/api/programs/CON", json={"text": shared}).status_code == 200
    r = s.http.post(
        "/api/classes", json={"id": "prg", "exercises": ["sign-error"], "seats": 2}, headers=ida
    )
    assert r.status_code == 201, r.text
    links = [link["url"].replace(s.base, "") for link in r.json()["links"]]
    with (
        httpx.Client(base_url=s.base, timeout=30) as one,
        httpx.Client(base_url=s.base, timeout=30) as two,
    ):
        for client, link in ((one, links[0]), (two, links[1])):
            assert client.get(link, follow_redirects=False).status_code == 303
            client.headers[CSRF_HEADER] = client.cookies[CSRF_COOKIE]
        assert [p["name"] for p in one.get("/api/programs").json()] == ["CON"]
        mine = "%MAIN\nG01 X20 F100\nM30\n"
        written = one.put("/api/programs/con", json={"text": mine})  # shadows the shared CON
        assert written.status_code == 200 and written.json()["seat"] == "prg-s01"
        assert one.get("/api/programs/CON").json()["text"] == mine  # their own first
        assert two.get("/api/programs/CON").json()["text"] == shared  # not seat 1's
        assert s.http.get("/api/programs/CON").json()["text"] == shared  # nor the service's
        assert [p["seat"] for p in s.http.get("/api/programs").json()] == [None]
        assert two.delete("/api/programs/CON").status_code == 403  # the shared one
        assert one.delete("/api/programs/CON").status_code == 204  # their own
        assert one.get("/api/programs/CON").json()["text"] == shared  # the shared one again
        assert one.delete("/api/programs/CON").status_code == 403
    assert s.http.get("/api/programs/CON").status_code == 200  # still there
    assert s.http.post("/api/classes/prg/end", headers=ida).status_code == 200
