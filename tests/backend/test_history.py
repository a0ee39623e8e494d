"""A machine's history over real HTTP and websockets: job errors put down to the command that
raised them, kept across a restart of the service with the stop, the start and the power-on
marked; notes, acknowledgements and resets; filters, pages and exports; the live stream; the
retention on a real SQLite file."""

from __future__ import annotations

import asyncio
import csv
import io
import json
import os
import signal
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from websockets.asyncio.client import connect

from api.auth import CSRF_COOKIE, CSRF_HEADER, Role
from backend.services.accounts import Accounts
from backend.services.history import History
from backend.services.machine_log import LogRow
from backend.services.shares import Shares
from backend.services.store import Store
from tests.backend.server import Server, add_users, bearer
from tests.backend.test_scope import rrd_chunks

TOP_STAGE_RPM = 7000  # the demo spindle's M45 reaches 7000 rpm (range_table[5].max_speed)


TOKENS: dict[str, str] = {}  # the module service's other users' API tokens


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    db = tmp_path_factory.mktemp("history") / "history.sqlite"
    TOKENS.update(add_users(db, {"olga": Role.OBSERVER, "otto": Role.OPERATOR}))
    s = Server(db).start()
    yield s
    s.close()


def _history(srv: Server, mid: str, **params: Any) -> list[dict[str, Any]]:
    r = srv.http.get(f"/api/machines/{mid}/history", params=params)
    assert r.status_code == 200, r.text
    rows: list[dict[str, Any]] = r.json()["rows"]
    return rows


def _until(srv: Server, mid: str, what: str, timeout_s: float = 30.0, **params: Any) -> list[Any]:
    """The history's rows once one matches (`what` in its text): a safety net, no measure."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        rows = _history(srv, mid, **params)
        if any(what in r["text"] or what in r["outcome"] for r in rows):
            return rows
        time.sleep(0.05)
    raise AssertionError(f"no history entry with {what!r}")


def _mdi(srv: Server, mid: str, block: str) -> dict[str, Any]:
    r = srv.command(mid, {"type": "mdi", "block": block})
    assert r.status_code == 200, r.text
    data: dict[str, Any] = r.json()
    return data


def test_a_job_error_names_the_block_that_raised_it_and_survives_a_restart(
    tmp_path: Path,
) -> None:
    """M3 S20000 queued behind M3 S1500 is accepted (the audit says ok), but S20000 is above
    the top gear stage: once S1500 is reached it raises 90017. The history puts the error
    down to that block and its sender, and marks the block as dropped; a bad arc is refused
    at once with 90026 (422). After a restart of the service both are still there with their
    wall clock, after them the stop, the start and the power-on, and a viewer is told."""
    before = time.time()
    srv = Server(tmp_path / "db.sqlite").start()
    try:
        srv.wait_powered("demo")
        srv.pace("demo", mode="pause")  # both blocks queue before the first has run
        _mdi(srv, "demo", "M3 S1500")
        _mdi(srv, "demo", f"M3 S{3 * TOP_STAGE_RPM - 1000}")
        # at real pace: run fast on a loaded machine, the sample ring may be lapped before the
        # error is heard, and its flight window is lost (the history says so)
        srv.pace("demo", mode="run")
        rows = _until(srv, "demo", "dropped by job error 90017", kind=["job_error", "command"])
        arc = srv.command("demo", {"type": "mdi", "block": "G18 G03 X0 Z12 I-10 F100"})
        assert arc.status_code == 422 and arc.json()["detail"]["code"] == 90026
    finally:
        srv.close()
    error = next(r for r in rows if r["code"] == 90017)
    assert error["severity"] == "error" and error["axis"] == "S1"
    assert error["cause"] == f"raised by MDI block 'M3 S{3 * TOP_STAGE_RPM - 1000}' sent by tester"
    assert error["sim_t_s"] > 0 and error["epoch"] == 1
    dropped = next(r for r in rows if r["outcome"] == "dropped by job error 90017")
    assert dropped["actor"] == "tester" and dropped["text"] == "MDI M3 S20000"
    accepted = next(r for r in rows if r["id"].startswith("a") and "S20000" in r["text"])
    assert accepted["outcome"] == "ok" and accepted["sim_t_s"] is not None

    srv = Server(tmp_path / "db.sqlite").start()
    try:
        after = _history(srv, "demo", limit=1000)

        async def notice() -> dict[str, Any]:
            url = f"{srv.ws_base}/api/machines/demo/telemetry"
            async with connect(url, **srv.ws_auth) as ws:
                while True:
                    msg = json.loads(await ws.recv())
                    if msg["type"] == "notice":
                        return dict(msg)

        told = asyncio.run(asyncio.wait_for(notice(), 10))
    finally:
        srv.close()
    codes = {r["code"] for r in after if r["kind"] == "job_error"}
    assert {90017, 90026} <= codes
    # refused at once, the arc's error is put down to it, and the command comes first: it is
    # stamped when it was sent, the error in the cycle that ran it
    bad_arc = next(r for r in after if r["code"] == 90026)
    assert bad_arc["cause"] == "after 'G18 G03 X0 Z12 I-10 F100' sent by tester"
    sent = next(r for r in after if r["kind"] == "command" and "G03" in r["text"])
    assert sent["sim_t_s"] <= bad_arc["sim_t_s"] and sent["time_unix"] <= bad_arc["time_unix"]
    assert all(before <= r["time_unix"] <= time.time() for r in after)
    newest_first = [r["text"] for r in after if r["kind"] in ("service", "power")]
    assert newest_first[:4] == [
        "service started (Inbetrieb 0.2.0)",
        "powered on: the service started",
        "service stopping",
        "service started (Inbetrieb 0.2.0)",
    ]
    assert told["kind"] == "restarted" and "powered on again" in told["message"]
    powered = [r["epoch"] for r in after if r["kind"] == "power"]
    assert powered[:2] == [2, 1]  # its builds count on across the restart


def test_a_block_that_fails_at_once_is_named_as_the_cause(srv: Server, lathe: str) -> None:
    """M3 S20000 sent on its own to a lathe at rest: above the top gear stage, it raises
    90017 on S1 as it runs. The error is put down to the block (an MDI block names no axis:
    the channel's last command), and the command is listed before its error."""
    srv.command(lathe, {"type": "mdi", "block": f"M3 S{3 * TOP_STAGE_RPM - 1000}"})
    rows = _until(srv, lathe, "out of reach", kind=["job_error"])
    error = next(r for r in rows if r["code"] == 90017)
    assert error["axis"] == "S1"
    assert error["cause"] == f"after 'M3 S{3 * TOP_STAGE_RPM - 1000}' sent by tester"
    sent = next(r for r in _history(srv, lathe, kind=["command"]) if "S20000" in r["text"])
    assert sent["sim_t_s"] <= error["sim_t_s"] and sent["time_unix"] <= error["time_unix"]


def test_notes_acknowledgements_and_resets_go_into_the_history(srv: Server, lathe: str) -> None:
    """An observer writes in the logbook and acknowledges the job errors in force (none: 409);
    the reset that clears them is the holder's."""
    olga = bearer(TOKENS["olga"])
    url = f"/api/machines/{lathe}/history"
    assert srv.http.post(f"{url}/acknowledge", headers=olga).status_code == 409
    note = srv.http.post(f"{url}/notes", json={"text": "replaced the encoder cable of X"},
                         headers=olga)  # fmt: skip
    assert note.status_code == 201, note.text
    assert note.json()["actor"] == "olga" and note.json()["kind"] == "note"
    assert srv.http.post(f"{url}/notes", json={"text": ""}, headers=olga).status_code == 422
    assert srv.http.post(f"{url}/notes", json={"text": "x" * 2001}, headers=olga).status_code == 422
    assert srv.emergency_stop(lathe).status_code == 200
    _until(srv, lathe, "emergency stop", kind=["job_error"])
    ack = srv.http.post(f"{url}/acknowledge", headers=olga)
    assert ack.status_code == 201 and ack.json()["text"].startswith("acknowledged 90005")
    srv.command(lathe, {"type": "reset"}).raise_for_status()
    cleared = _until(srv, lathe, "reset cleared", kind=["cleared"])[0]
    assert cleared["actor"] == "tester" and "90005" in cleared["text"]


def test_filters_pages_and_exports(srv: Server, lathe: str) -> None:
    """Kind, severity, text and actor filter; pages follow on without gaps or repeats; the
    CSV and JSON exports hold the same entries, oldest first, in a file named after the
    machine."""
    url = f"/api/machines/{lathe}/history"
    for k in range(7):
        srv.http.post(f"{url}/notes", json={"text": f"note {k}"}).raise_for_status()
    notes = _history(srv, lathe, kind=["note"])
    assert [r["text"] for r in notes] == [f"note {k}" for k in reversed(range(7))]
    assert [r["text"] for r in _history(srv, lathe, text="NOTE 3")] == ["note 3"]
    assert _history(srv, lathe, kind=["note"], actor="nobody") == []
    assert all(r["severity"] == "info" for r in _history(srv, lathe, severity=["info"]))
    seen: list[str] = []
    page = _history(srv, lathe, kind=["note"], limit=3)
    while page:
        seen += [r["id"] for r in page]
        last = page[-1]
        page = _history(srv, lathe, kind=["note"], limit=3, before_unix=last["time_unix"],
                        before_id=last["id"])  # fmt: skip
    assert seen == [r["id"] for r in notes]
    r = srv.http.get(f"{url}/export", params={"kind": ["note"], "format": "csv"})
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")
    assert f'filename="{lathe}_history_' in r.headers["content-disposition"]
    table = list(csv.DictReader(io.StringIO(r.text)))
    assert [row["text"] for row in table] == [f"note {k}" for k in range(7)]
    assert table[0]["time_utc"].endswith("Z") and table[0]["actor"] == "tester"
    js = srv.http.get(f"{url}/export", params={"kind": ["note"], "format": "json"}).json()
    assert [e["id"] for e in js] == [row["id"] for row in table]
    bad = srv.http.get(url, params={"before_id": "x1", "before_unix": 1})
    assert bad.status_code == 422


def test_viewers_get_new_entries_live(srv: Server, lathe: str) -> None:
    """A note written by REST reaches a connected viewer as a history message."""

    async def run() -> dict[str, Any]:
        async with connect(f"{srv.ws_base}/api/machines/{lathe}/telemetry", **srv.ws_auth) as ws:
            await asyncio.to_thread(
                lambda: srv.http.post(
                    f"/api/machines/{lathe}/history/notes", json={"text": "live one"}
                ).raise_for_status()
            )
            while True:
                msg = json.loads(await ws.recv())
                if msg["type"] == "history" and any(
                    e["text"] == "live one" for e in msg["entries"]
                ):
                    return dict(msg)

    msg = asyncio.run(asyncio.wait_for(run(), 10))
    entry = next(e for e in msg["entries"] if e["text"] == "live one")
    assert entry["kind"] == "note" and entry["actor"] == "tester"


def test_the_machine_log_keeps_its_retention(tmp_path: Path) -> None:
    """Rows older than the days kept end, and beyond the rows per machine the oldest end;
    another machine's rows are not touched."""
    store = Store(tmp_path / "db.sqlite")
    history = History(store, days=1.0, rows_per_machine=1000)
    try:
        old = time.time() - 2 * 86400.0
        for k in range(50):
            history.add(LogRow("a", "note", "info", f"old {k}", time=old))
        for k in range(1500):
            history.add(LogRow("a", "event", "info", f"new {k}"))
        for k in range(10):
            history.add(LogRow("b", "event", "info", f"b {k}"))
        history.flush()
        history.prune()  # (the writer prunes too: once at its first rows, then every minute)
        texts = [r["text"] for r in store.query("SELECT text FROM machine_log WHERE machine = 'a'")]
        assert texts == [f"new {k}" for k in range(500, 1500)]
        assert (
            store.query("SELECT count(*) AS n FROM machine_log WHERE machine = 'b'")[0]["n"] == 10
        )
    finally:
        history.stop()
        store.close()


def test_the_flight_recorder_saves_the_seconds_around_a_job_error(
    srv: Server, lathe: str, tmp_path: Path
) -> None:
    """An emergency stop (90005) after more than 8 s of running, the simulation running fast
    (it laps the sample ring's 16 s in well under a second): the recorder saves all of the
    8 s before and 2 s after it at full rate, the error as trigger and on the timeline (also
    in Rerun, with the logbook entry written just before), and the history entry links to
    it. On demand it saves the last 5 s at full rate and the last 60 s one cycle in ten from its
    long tier."""
    srv.pace(lathe, mode="fast")
    deadline = time.monotonic() + 30
    while srv.status(lathe)["simulation"]["cycle"] < 9000:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    srv.pace(lathe, mode="pause")  # the note and the stop at one moment, then fast again
    note = {"text": "checking the X slide"}  # a logbook entry just before: on the timeline
    srv.http.post(f"/api/machines/{lathe}/history/notes", json=note).raise_for_status()
    assert srv.emergency_stop(lathe).status_code == 200
    srv.pace(lathe, mode="fast")
    deadline = time.monotonic() + 30
    while not (rows := _history(srv, lathe, kind=["job_error"])) or rows[0]["trace"] is None:
        assert time.monotonic() < deadline, rows
        time.sleep(0.1)
    error = rows[0]
    assert error["code"] == 90005
    detail = srv.http.get(f"/api/traces/{error['trace']}").json()
    at = round(error["sim_t_s"] / 0.001)  # the error's cycle (1 ms cycles)
    assert detail["source"] == "flight" and detail["stored"] is True
    assert detail["trigger_cycle"] == at and detail["first_cycle"] == at - 8000
    assert detail["count"] == 10_001 and detail["cycle_s"] == 0.001
    names = {c["name"] for c in detail["channels"]}
    assert {"X.lag_mm", "X.pos_act_mm", "S1.speed_act_rpm", "CH.state"} <= names
    assert any(e["code"] == 90005 and e["cycle"] == at for e in detail["events"])
    rrd = tmp_path / "flight.rrd"
    rrd.write_bytes(srv.http.get(f"/api/traces/{error['trace']}/trace.rrd").content)
    chunks = rrd_chunks(rrd)
    assert chunks[f"/{lathe}/events"] >= 1 and chunks[f"/{lathe}/X"] == 10_001
    assert chunks[f"/{lathe}/notes"] == 1

    url = f"/api/machines/{lathe}/flight-recorder"
    deadline = time.monotonic() + 10  # the long tier is fed (and first made) once a second
    while (status := srv.http.get(url).json())["bytes"] == 0:
        assert time.monotonic() < deadline, status
        time.sleep(0.1)
    assert status["decimation"] == 10 and status["full_rate_s"] > 9.0
    assert status["bytes"] == len(names) * 5 * 60 * 100 * 8  # 5 min at 100 Hz, float64
    short = srv.http.post(f"{url}/save", json={"seconds": 5}).json()
    assert short["count"] == 5000 and short["cycle_s"] == 0.001
    long = srv.http.post(f"{url}/save", json={"seconds": 60}).json()
    assert long["cycle_s"] == pytest.approx(0.01) and "1 in 10 cycles" in long["name"]
    assert 900 <= long["count"] <= 6000  # what the tier holds of the lathe's life, ≤ 60 s
    assert srv.http.post(f"{url}/save", json={"seconds": 0}).status_code == 422


def test_a_job_error_while_the_gateway_gets_no_cpu_is_saved_whole(srv: Server, lathe: str) -> None:
    """X's drive drops its ready signals 20 s into a 30 s move (DriveNotReady, triggered 20 s
    after its injection): job error 90008. The simulation runs fast (it laps the sample
    ring's 16 s in a fraction of a second), and the gateway gets no CPU (SIGSTOP) from about
    when the run starts until a second later: long after the error and its 2 s. The trace is
    whole all the same: the 8 s before and the 2 s after at full rate, the command ramping
    at the programmed 200 mm/min before the error."""
    srv.pace(lathe, mode="pause")
    start = srv.status(lathe)["simulation"]["cycle"]
    fault = {"fault": {"kind": "drive_not_ready", "axis": "X"}, "trigger": {"after_s": 20}}
    assert srv.http.post(f"/api/machines/{lathe}/faults", json=fault).status_code == 201
    _mdi(srv, lathe, "G01 X150 F200")  # from X50: 100 mm at 200 mm/min, 30 s
    srv.pace(lathe, mode="fast")
    assert srv.proc is not None
    os.kill(srv.proc.pid, signal.SIGSTOP)
    try:
        time.sleep(1.0)
    finally:
        os.kill(srv.proc.pid, signal.SIGCONT)
    deadline = time.monotonic() + 30
    while not (rows := _history(srv, lathe, kind=["job_error"])) or rows[0]["trace"] is None:
        assert time.monotonic() < deadline, rows
        time.sleep(0.1)
    error = rows[0]
    at = round(error["sim_t_s"] / 0.001)
    assert error["code"] == 90008 and at == start + 20_000
    detail = srv.http.get(f"/api/traces/{error['trace']}").json()
    assert detail["trigger_cycle"] == at and detail["first_cycle"] == at - 8000
    assert detail["count"] == 10_001
    csv_text = srv.http.get(f"/api/traces/{error['trace']}/csv").text
    lines = [line for line in csv_text.splitlines() if not line.startswith("#")]
    rows_csv = list(csv.DictReader(lines))
    assert [int(r["cycle"]) for r in rows_csv] == list(range(at - 8000, at + 2001))
    cmd = [float(r["X.pos_cmd_mm [mm]"]) for r in rows_csv]
    assert cmd[7000] - cmd[6000] == pytest.approx(200 / 60, abs=1e-6)  # mm in 1 s at F200


def test_a_saved_minute_ends_at_the_cycle_the_machine_stands_at(srv: Server, lathe: str) -> None:
    """The long tier is fed once a second; a save from it takes the cycles since then first.
    Stepped 20 s in one request and saved at once, the minute ends at the machine's cycle and
    holds what the sample ring still held safely: its 16384 cycles less the 2000 a writer may
    be writing, one in ten (backend/workers/ring.py)."""
    srv.pace(lathe, mode="pause")
    head = srv.step(lathe, 20_000)["cycle"]
    long = srv.http.post(f"/api/machines/{lathe}/flight-recorder/save", json={"seconds": 60})
    assert long.status_code == 201, long.text
    trace = long.json()
    assert trace["cycle_s"] == pytest.approx(0.01)
    newest = (trace["first_cycle"] + trace["count"] - 1) * 10  # in the machine's 1 ms cycles
    assert head - 10 < newest <= head
    assert trace["count"] >= (16384 - 2000) // 10


def test_the_scope_is_whoever_armed_it_and_never_silently_replaced(srv: Server, lathe: str) -> None:
    """Otto arms the scope: it is his while it waits. Olga (observer) cannot re-arm, force or
    stop it (409 asking her to ask him; taking over: 403); an admin takes it over, and its
    viewers are told."""
    otto, olga = bearer(TOKENS["otto"]), bearer(TOKENS["olga"])
    url = f"/api/machines/{lathe}/scope"
    setup = {"channels": ["S1.speed_act_rpm"], "mode": "single",
             "trigger": {"type": "event", "event": "m_start", "axis": "S1", "m": 3}}  # fmt: skip
    armed = srv.http.put(url, json=setup, headers=otto)
    assert armed.status_code == 200 and armed.json()["armed_by"] == "otto (operator)"
    refused = srv.http.put(url, json=setup, headers=olga)
    assert refused.status_code == 409 and "otto (operator)'s" in refused.text
    taken = srv.http.put(url, json={**setup, "take_over": True}, headers=olga)
    assert taken.status_code == 403 and "take it over" in taken.text
    for act in ("force", "stop"):
        assert srv.http.post(f"{url}/{act}", headers=olga).status_code == 403
    assert srv.http.get(url).json()["armed_by"] == "otto (operator)"  # still his
    over = srv.http.put(url, json={**setup, "take_over": True})
    assert over.status_code == 200 and over.json()["armed_by"] == "tester (admin)"

    async def told() -> str:
        async with connect(f"{srv.ws_base}/api/machines/{lathe}/telemetry", **srv.ws_auth) as ws:
            while True:
                msg = json.loads(await ws.recv())
                if msg["type"] == "notice":
                    return str(msg["message"])

    assert "took over the scope from otto (operator)" in asyncio.run(asyncio.wait_for(told(), 10))


def test_a_bundle_opens_on_another_service_as_the_same_offline_machine(
    srv: Server, lathe: str, tmp_path: Path
) -> None:
    """The bundle of a lathe with a baseline, a change since and a job error with its
    flight-recorder trace: the zip holds what the manifest says; a second service opens it as
    an offline machine whose diff, history, lists and trace are the first one's."""
    base = srv.http.post(f"/api/machines/{lathe}/versions", json={"name": "as delivered",
                                                                   "baseline": True})  # fmt: skip
    assert base.status_code == 201, base.text
    change = {"scope": "axis", "target": "X", "name": "getriebe[0].kv", "value": 1500}
    srv.http.patch(
        f"/api/machines/{lathe}/parameters", json={"changes": [change]}
    ).raise_for_status()
    assert srv.emergency_stop(lathe).status_code == 200
    deadline = time.monotonic() + 30
    while not (errors := _history(srv, lathe, kind=["job_error"])) or not errors[0]["trace"]:
        assert time.monotonic() < deadline
        time.sleep(0.1)
    r = srv.http.get(f"/api/machines/{lathe}/bundle")
    assert r.status_code == 200 and r.headers["content-type"] == "application/zip"
    assert f'filename="{lathe}_bundle_' in r.headers["content-disposition"]
    with zipfile.ZipFile(io.BytesIO(r.content)) as z:
        names = set(z.namelist())
        manifest = json.loads(z.read("manifest.json"))
    tid = errors[0]["trace"]
    assert {"history.json", "history.csv", "diff.json", "versions.json", "status.json"} <= names
    assert {f"traces/{tid}.csv", f"traces/{tid}.rrd", "lists/axis_X.txt"} <= names
    assert manifest["machine_id"] == lathe and tid in manifest["traces"]
    diff_here = srv.http.get(f"/api/machines/{lathe}/versions/diff").json()
    history_here = _history(srv, lathe, limit=1000)

    other = Server(tmp_path / "other.sqlite").start()
    try:
        bad = other.http.post("/api/bundles", content=b"not a zip",
                              headers={"content-type": "application/zip"})  # fmt: skip
        assert bad.status_code == 422 and "not a zip" in bad.text
        opened = other.http.post("/api/bundles", content=r.content,
                                 headers={"content-type": "application/zip"})  # fmt: skip
        assert opened.status_code == 201, opened.text
        bundle = opened.json()
        assert bundle["diff"]["changes"] == diff_here["changes"]
        assert [c["parameter"] for c in bundle["diff"]["changes"]] == ["getriebe[0].kv"]
        there = other.http.get(f"/api/bundles/{bundle['id']}/history").json()["rows"]
        made = manifest["history_entries"]
        assert [(e["id"], e["text"]) for e in there] == [
            (e["id"], e["text"]) for e in history_here[-made:]
        ]
        error_there = next(e for e in there if e["kind"] == "job_error")
        assert error_there["trace"] == bundle["traces"][0]  # the trace as it is here
        assert bundle["trace_infos"][0]["created_unix"] < opened.json()["opened_unix"]
        x_list = other.http.get(f"/api/bundles/{bundle['id']}/lists/axis_X.txt")
        here = srv.http.get(f"/api/machines/{lathe}/parameters/export", params={"target": "X"})
        assert x_list.text == here.text
        trace = other.http.get(f"/api/traces/{bundle['traces'][0]}").json()
        assert trace["trigger"] == "job error 90005" and trace["machine"].startswith("offline-")
        assert any(e["code"] == 90005 for e in trace["events"])
        assert [b["id"] for b in other.http.get("/api/bundles").json()] == [bundle["id"]]
    finally:
        other.close()


def test_a_share_link_shows_one_machine_read_only_until_it_is_revoked(
    srv: Server, lathe: str
) -> None:
    """A guest without an account opens the link: a session that sees the lathe only and
    may only watch (its viewers list names the guest); revoked, the session ends at once and
    the link opens nothing any more. Making, opening and revoking are audited."""
    made = srv.http.post(f"/api/machines/{lathe}/share", json={"hours": 1, "label": "Acme"})
    assert made.status_code == 201, made.text
    link, url = made.json()["link"], made.json()["url"]
    assert url.startswith(f"{srv.base}/share/") and link["active"] and link["uses"] == 0
    guest = httpx.Client(base_url=srv.base, timeout=10)
    try:
        opened = guest.get(url.removeprefix(srv.base))
        assert opened.status_code == 303 and opened.headers["location"] == f"/#{lathe}/operate"
        csrf = {CSRF_HEADER: guest.cookies[CSRF_COOKIE]}
        me = guest.get("/api/auth/me").json()
        assert me["guest"] is True and me["actions"] == ["observe"]
        assert [m["id"] for m in guest.get("/api/machines").json()] == [lathe]
        assert guest.get(f"/api/machines/{lathe}/history").status_code == 200
        assert guest.get("/api/machines/demo/status").status_code == 404
        for path, body in ((f"/api/machines/{lathe}/history/notes", {"text": "hi"}),
                           (f"/api/machines/{lathe}/control", {"action": "request"}),
                           (f"/api/machines/{lathe}/scope/stop", {})):  # fmt: skip
            r = guest.post(path, json=body, headers=csrf)
            assert r.status_code == 403 and "share link only watches" in r.text, path
        ticket = guest.post("/api/auth/ws-ticket", json={}, headers=csrf).json()["ticket"]

        async def viewers() -> list[dict[str, Any]]:
            url = f"{srv.ws_base}/api/machines/{lathe}/telemetry?ticket={ticket}"
            async with connect(url) as ws:
                while True:
                    msg = json.loads(await ws.recv())
                    if msg["type"] == "status" and msg["status"]["control"]["viewers"]:
                        watching = srv.http.get(f"/api/machines/{lathe}/share").json()
                        assert watching[0]["watching"] == 1
                        return list(msg["status"]["control"]["viewers"])

        seen = asyncio.run(asyncio.wait_for(viewers(), 10))
        assert [(v["user"], v["guest"]) for v in seen] == [(link["guest"], True)]
        revoked = srv.http.delete(f"/api/machines/{lathe}/share/{link['id']}")
        assert revoked.status_code == 200 and revoked.json()["active"] is False
        after = guest.get(f"/api/machines/{lathe}/status")
        assert after.status_code == 401
        assert guest.get(url.removeprefix(srv.base)).status_code == 401
    finally:
        guest.close()
    rows = srv.http.get("/api/audit", params={"text": link["id"]}).json()["rows"]
    assert {r["action"].split(" ")[0] for r in rows} >= {"shared", "opened", "revoked"}


def test_a_share_link_ends_when_it_expires(tmp_path: Path) -> None:
    """On a real store: a link valid 0.5 s opens at first, then not; the sweep removes its
    guest's login, which ends every session of it."""
    store = Store(tmp_path / "db.sqlite")
    try:
        accounts = Accounts(store)
        shares = Shares(store, accounts)
        link, token = shares.create("m1", 0.5 / 3600, "", "tester")
        assert shares.redeem(token) is not None and shares.guest(link.guest) is not None
        sid, _ = accounts.new_session(link.guest)
        time.sleep(0.6)
        assert shares.redeem(token) is None
        shares.sweep()
        assert shares.guest(link.guest) is None and accounts.session(sid) is None
    finally:
        store.close()


def test_the_fleet_shows_each_machine_with_its_alarms(srv: Server, lathe: str) -> None:
    """An emergency stop on one lathe: the fleet lists it running, in emergency stop, with
    90005 in force and as its last alarm, and the alarm across the machines names it; a
    reset clears what is in force (the last alarm stays)."""
    assert srv.emergency_stop(lathe).status_code == 200
    _until(srv, lathe, "emergency stop", kind=["job_error"])
    fleet = srv.http.get("/api/fleet").json()
    row = next(m for m in fleet["machines"] if m["id"] == lathe)
    assert row["reachable"] == "running" and row["state"] == "emergency stop"
    assert row["active_errors"] == ["90005"] and row["last_alarm"]["code"] == 90005
    mine = [a for a in fleet["alarms"] if fleet["machine_of"][a["id"]] == lathe]
    assert mine and mine[0]["code"] == 90005
    srv.command(lathe, {"type": "reset"}).raise_for_status()
    _until(srv, lathe, "reset cleared", kind=["cleared"])
    row = next(m for m in srv.http.get("/api/fleet").json()["machines"] if m["id"] == lathe)
    assert row["active_errors"] == [] and row["last_alarm"]["code"] == 90005
