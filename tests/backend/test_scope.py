"""Scope and traces over real HTTP: triggered captures, the library in SQLite, CSV, Rerun .rrd
read by the real `rerun` CLI, the loopback-only Rerun web viewer, continuous recording."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from api.telemetry import decode_frame
from backend.services.viewer import rerun_cli
from nc_sim.errors import Code
from nc_sim.snapshot import AxisState
from tests.backend.server import Server

CH = ["S1.speed_cmd_rpm", "S1.pos_act_deg", "S1.lag_deg", "S1.state"]


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("scope") / "scope.sqlite").start()
    yield s
    s.close()


@pytest.fixture
def mid(srv: Server, mid: str) -> str:
    """The test's own machine, paused with half a second of history for pre-triggers."""
    srv.pace(mid, mode="pause")
    srv.step(mid, 500)
    return mid


def arm(srv: Server, mid: str, **setup: Any) -> dict[str, Any]:
    r = srv.http.put(f"/api/machines/{mid}/scope", json=setup)
    assert r.status_code == 200, r.text
    data: dict[str, Any] = r.json()
    return data


def scope(srv: Server, mid: str) -> dict[str, Any]:
    data: dict[str, Any] = srv.http.get(f"/api/machines/{mid}/scope").json()
    return data


def samples(srv: Server, tid: str) -> tuple[Any, np.ndarray]:
    r = srv.http.get(f"/api/traces/{tid}/data")
    r.raise_for_status()
    return decode_frame(r.content)


def cycle(srv: Server, mid: str) -> int:
    return int(scope(srv, mid)["cycle"])


def m19_capture(srv: Server, mid: str) -> dict[str, Any]:
    trig = {"type": "event", "event": "m_start", "axis": "S1", "m": 19}
    st = arm(srv, mid, channels=CH, length_s=0.5, pretrigger_pct=40, mode="single", trigger=trig)
    assert st["state"] == "armed" and st["pre_cycles"] == 200 and st["length_cycles"] == 500
    srv.step(mid, 37)
    at = cycle(srv, mid)
    r = srv.command(mid, {"type": "spindle_position", "spindle": "S1", "position_deg": 90})
    assert r.status_code == 200, r.text
    srv.step(mid, 600)
    st = scope(srv, mid)
    assert st["state"] == "done"
    cap: dict[str, Any] = st["captures"][0]
    assert cap["trigger_cycle"] == at + 1
    return cap


def test_m19_capture_has_the_asked_pretrigger_and_its_trigger_at_the_first_m19_cycle(
    srv: Server,
    mid: str,
) -> None:
    cap = m19_capture(srv, mid)
    assert cap["first_cycle"] == cap["trigger_cycle"] - 200 and cap["count"] == 500
    assert cap["trigger"] == "M19 start on S1" and not cap["stored"]
    header, data = samples(srv, cap["id"])
    assert header.signals == CH and header.first_cycle == cap["first_cycle"]
    state = data[3]
    assert state[200] == AxisState.POSITIONING and state[199] != AxisState.POSITIONING
    detail = srv.http.get(f"/api/traces/{cap['id']}").json()
    m19 = [e for e in detail["events"] if e["code"] == Code.EV_M_START and e["m"] == 19]
    assert [e["axis"] for e in m19] == ["S1"]


def test_level_trigger_fires_once_in_single_mode(srv: Server, mid: str) -> None:
    trig = {"type": "level", "signal": "S1.speed_cmd_rpm", "level": 300, "edge": "rising"}
    before = len(scope(srv, mid)["captures"])
    arm(srv, mid, channels=["S1.speed_cmd_rpm"], length_s=0.2, pretrigger_pct=50, trigger=trig)
    for m in (3, 5, 3, 5):
        srv.command(mid, {"type": "spindle", "spindle": "S1", "m": m, "speed_rpm": 600})
        srv.step(mid, 1500)
    st = scope(srv, mid)
    assert st["state"] == "done" and len(st["captures"]) == before + 1
    _, data = samples(srv, st["captures"][0]["id"])
    assert data[0][100] >= 300 > data[0][99]  # the trigger sample is the first one above


def test_bad_setups_are_refused_with_what_is_wrong(srv: Server, mid: str) -> None:
    r = srv.http.put(f"/api/machines/{mid}/scope", json={"channels": ["S1.nope"]})
    assert r.status_code == 422 and "S1.nope" in r.text
    r = srv.http.put(f"/api/machines/{mid}/scope", json={"channels": CH, "length_s": 61})
    assert r.status_code == 422 and "length_s" in r.text
    r = srv.http.put(f"/api/machines/{mid}/scope", json={"channels": CH, "mode": "normal"})
    assert r.status_code == 422 and "needs a trigger" in r.text
    r = srv.http.put(f"/api/machines/{mid}/scope", json={"channels": CH * 5})
    assert r.status_code == 422 and "channels" in r.text


def rrd_chunks(path: Path) -> Counter[str]:
    """Rows of data per entity path as the real `rerun rrd print` reports them (the static
    names of an axis' series apart)."""
    out = subprocess.run(
        [rerun_cli(), "rrd", "print", str(path)], capture_output=True, text=True, check=True
    ).stdout
    rows: Counter[str] = Counter()
    for m in re.finditer(r"with (\d+) rows .*? - (/\S+) - data columns: \[(.*)\]", out):
        if not m[3].startswith("SeriesLines"):
            rows[m[2]] += int(m[1])
    return rows


def test_capture_as_rrd_read_by_the_rerun_cli(srv: Server, mid: str, tmp_path: Path) -> None:
    cap = m19_capture(srv, mid)
    r = srv.http.get(f"/api/traces/{cap['id']}/trace.rrd")
    assert r.status_code == 200
    path = tmp_path / "m19.rrd"
    path.write_bytes(r.content)
    rows = rrd_chunks(path)
    assert rows[f"/{mid}/S1"] == 500  # one row per cycle: the axis' signals in one batch
    _, data = samples(srv, cap["id"])
    changes = 1 + int(np.count_nonzero(np.diff(data[3])))
    assert rows[f"/{mid}/S1/state"] == changes  # the state as text at each change
    detail = srv.http.get(f"/api/traces/{cap['id']}").json()
    assert rows[f"/{mid}/events"] == len(detail["events"]) > 0
    recorded = {k for k in rows if not k.startswith(("/view", "/container", "/viewport"))}
    assert recorded == {f"/{mid}", f"/{mid}/S1", f"/{mid}/S1/state", f"/{mid}/events"}
    verbose = subprocess.run(
        [rerun_cli(), "rrd", "print", "-vvv", str(path)], capture_output=True, text=True
    ).stdout
    assert "sim_time" in verbose
    # the default blueprint: the spindle's speed and lag, its position
    assert "S1 position" in verbose and "S1 speed" in verbose


def test_csv_round_trip_is_exact(srv: Server, mid: str) -> None:
    cap = m19_capture(srv, mid)
    text = srv.http.get(f"/api/traces/{cap['id']}/csv").text
    r = srv.http.post(
        "/api/traces/import",
        params={"name": "m19 again"},
        content=text.encode(),
        headers={"content-type": "text/csv"},
    )
    assert r.status_code == 201, r.text
    imp = r.json()
    assert imp["source"] == "import" and imp["stored"] and imp["name"] == "m19 again"
    h1, d1 = samples(srv, cap["id"])
    h2, d2 = samples(srv, imp["id"])
    assert h2.signals == h1.signals and h2.first_cycle == h1.first_cycle
    assert d1.tobytes() == d2.tobytes()  # bit for bit
    again = srv.http.get(f"/api/traces/{imp['id']}/csv").text
    assert again.split("\n")[2:] == text.split("\n")[2:]  # same header and rows
    bad = srv.http.post("/api/traces/import", content=b"cycle,a\n1,x\n2,3\n")
    assert bad.status_code == 422 and "not a number" in bad.text


def test_library_keeps_parameters_renames_compares_deletes(
    srv: Server, mid: str, tmp_path: Path
) -> None:
    kv = "getriebe[2].kv"  # S1 runs in M42
    first = m19_capture(srv, mid)
    saved = srv.http.post(f"/api/traces/{first['id']}/save", json={"name": "kv default"}).json()
    assert saved["stored"] and saved["name"] == "kv default"
    body = {"changes": [{"scope": "axis", "target": "S1", "name": kv, "value": 1500}]}
    assert srv.http.patch(f"/api/machines/{mid}/parameters", json=body).status_code == 200
    second = m19_capture(srv, mid)
    srv.http.post(f"/api/traces/{second['id']}/save", json={"notes": "kv 15/s"})
    detail = srv.http.get(f"/api/traces/{second['id']}").json()
    at_capture = {(p["scope"], p["target"], p["name"]): p["value"] for p in detail["params"]}
    assert at_capture[("axis", "S1", kv)] == 1500
    cmp = srv.http.get("/api/traces/compare", params={"a": first["id"], "b": second["id"]}).json()
    # the first capture ran with kv at its default, 1000 (10/s): the value then, not "default"
    assert [(p["name"], p["a"], p["b"]) for p in cmp["params"]] == [(kv, 1000, 1500)]
    assert cmp["common_channels"] == CH

    r = srv.http.patch(f"/api/traces/{first['id']}", json={"name": "before", "notes": "kv 20"})
    assert r.json()["name"] == "before"
    lib = srv.http.get("/api/traces", params={"machine": mid}).json()
    names = {t["id"]: t["name"] for t in lib}
    assert names[first["id"]] == "before" and second["id"] in names
    assert srv.http.delete(f"/api/traces/{second['id']}").status_code == 204
    again = srv.http.get(f"/api/traces/{second['id']}")  # still one of the recent captures
    assert again.status_code == 200 and again.json()["stored"] is False
    recent = {c["id"]: c["stored"] for c in scope(srv, mid)["captures"]}
    assert recent[second["id"]] is False and recent[first["id"]] is True
    assert second["id"] not in {t["id"] for t in srv.http.get("/api/traces").json()}
    assert not (srv.db.parent / "traces" / f"{second['id']}.npy").exists()


def test_measurements_of_a_feed_move_match_v_over_kv(srv: Server, mid: str) -> None:
    trig = {"type": "level", "signal": "X.vel_cmd_mm_min", "level": 1, "edge": "rising"}
    arm(
        srv,
        mid,
        channels=["X.lag_mm", "X.vel_act_mm_min"],
        length_s=3,
        pretrigger_pct=5,
        trigger=trig,
    )
    x = srv.axis("X", mid)["pos_cmd"]
    srv.command(
        mid, {"type": "move", "axis": "X", "target": x + 25, "rapid": False, "feed_mm_min": 600}
    )
    srv.step(mid, 3500)
    cap = scope(srv, mid)["captures"][0]
    m = srv.http.get(
        f"/api/traces/{cap['id']}/measure", params={"channel": "X.lag_mm", "t1_s": 2.0}
    ).json()
    # steady lag of a position loop without feedforward: v/kv = (600/60 mm/s)/(20/s)
    assert m["final"] == pytest.approx(0.5, abs=0.002)
    assert m["unit"] == "mm" and m["t0_s"] == pytest.approx(-0.15)
    v = srv.http.get(
        f"/api/traces/{cap['id']}/measure",
        params={"channel": "X.vel_act_mm_min", "t0_s": 0, "t1_s": 2.0},
    ).json()
    assert v["final"] == pytest.approx(600, rel=1e-3)
    assert v["rise_time_s"] is not None and 0 < v["rise_time_s"] < 1.0
    r = srv.http.get(f"/api/traces/{cap['id']}/measure", params={"channel": "Z.lag_mm"})
    assert r.status_code == 422 and "Z.lag_mm" in r.text


def test_roll_mode_gives_the_newest_window(srv: Server, mid: str) -> None:
    arm(srv, mid, channels=["X.pos_act_mm"], length_s=2, mode="roll")
    srv.step(mid, 2500)
    now = cycle(srv, mid)
    header, data = decode_frame(srv.http.get(f"/api/machines/{mid}/scope/roll").content)
    assert header.first_cycle == now - 1999 and data.shape == (1, 2000)
    header, data = decode_frame(
        srv.http.get(f"/api/machines/{mid}/scope/roll", params={"max_points": 500}).content
    )
    assert header.stride == 4 and data.shape == (1, 500)
    srv.http.post(f"/api/machines/{mid}/scope/stop")


def test_continuous_recording_writes_every_cycle(srv: Server, mid: str, tmp_path: Path) -> None:
    sigs = [s["name"] for s in srv.http.get(f"/api/machines/{mid}/signals").json()][:16]
    r = srv.http.post(f"/api/machines/{mid}/recording", json={"signals": sigs})
    assert r.status_code == 201, r.text
    assert (
        srv.http.post(f"/api/machines/{mid}/recording", json={"signals": sigs}).status_code == 409
    )
    srv.command(mid, {"type": "spindle", "spindle": "S1", "m": 3, "speed_rpm": 800})
    srv.step(mid, 5000)
    info = srv.http.delete(f"/api/machines/{mid}/recording").json()
    assert not info["active"] and info["cycles"] == 5000
    path = tmp_path / "rec.rrd"
    path.write_bytes(srv.http.get(f"/api/recordings/{info['id']}/recording.rrd").content)
    rows = rrd_chunks(path)
    axes = {s.rsplit(".", 1)[0] for s in sigs if not s.endswith(".state")}
    for axis in axes:  # each axis' signals in one batch per cycle
        assert rows[f"/{mid}/" + axis.replace(".", "/")] == 5000
    srv.command(mid, {"type": "spindle", "spindle": "S1", "m": 5})


def test_a_running_recording_downloads_as_far_as_it_is_written(srv: Server, mid: str) -> None:
    """The file grows while it is sent: each download is whole up to the size it had, with
    that size as its Content-Length (a file response read on and broke the answer)."""
    sigs = [s["name"] for s in srv.http.get(f"/api/machines/{mid}/signals").json()][:16]
    rid = srv.http.post(f"/api/machines/{mid}/recording", json={"signals": sigs}).json()["id"]
    srv.pace(mid, mode="run")  # in real time: it grows between and during the downloads
    sizes = []
    for _ in range(12):
        r = srv.http.get(f"/api/recordings/{rid}/recording.rrd")
        assert r.status_code == 200
        assert len(r.content) == int(r.headers["content-length"]) > 0
        assert r.headers["content-disposition"] == f'attachment; filename="{rid}.rrd"'
        sizes.append(len(r.content))
        time.sleep(0.05)
    assert sizes == sorted(sizes) and sizes[-1] > sizes[0]  # it grew in real time
    srv.http.delete(f"/api/machines/{mid}/recording")


def listening(port: int) -> list[str]:
    """Local addresses of listening TCP sockets on `port` (from /proc/net/tcp and tcp6)."""
    out = []
    for f in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(f).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            addr, p = local.split(":")
            if state == "0A" and int(p, 16) == port:
                out.append(addr)
    return out


def test_rerun_viewer_is_served_through_the_service_and_listens_on_loopback_only(
    srv: Server,
    mid: str,
) -> None:
    cap = m19_capture(srv, mid)
    r = srv.http.get(f"/api/traces/{cap['id']}/viewer", follow_redirects=False)
    assert r.status_code == 307 and r.headers["location"].startswith("/rerun/?")
    page = srv.http.get(r.headers["location"], timeout=60)
    assert page.status_code == 200 and "re_viewer.js" in page.text
    assert "connect-src 'self'" in page.headers["content-security-policy"]
    wasm = srv.http.get("/rerun/re_viewer_bg.wasm", timeout=60)
    assert wasm.status_code == 200 and wasm.content[:4] == b"\0asm"
    log = (srv.db.parent / "traces" / "rerun-viewer.log").read_text()
    ports = {int(p) for p in re.findall(r"127\.0\.0\.1:(\d+)", log)}
    assert len(ports) >= 2  # the web viewer and its gRPC server
    for port in ports:
        assert listening(port) == ["0100007F"], f"port {port} is not loopback-only"
    # the viewer runs with its own configuration, in which its usage analytics are off
    cfg = srv.db.parent / "traces" / "rerun-home" / "config" / "rerun" / "analytics.json"
    assert json.loads(cfg.read_text())["analytics_enabled"] is False


def test_a_foreign_csv_is_read_from_its_header_and_bad_ones_are_refused(srv: Server) -> None:
    rows = ["t_s,X.lag_mm [mm],note"] + [f"{(k - 2) * 0.002!r},{k * 0.1!r},{k}" for k in range(6)]
    r = srv.http.post("/api/traces/import", content="\n".join(rows).encode())
    assert r.status_code == 201, r.text
    info = r.json()
    assert info["cycle_s"] == 0.002 and info["trigger_cycle"] == 2  # the row at t = 0
    assert [c["name"] for c in info["channels"]] == ["X.lag_mm", "note"]
    assert info["channels"][0]["unit"] == "mm"
    _, data = samples(srv, info["id"])
    assert data[0].tolist() == [k * 0.1 for k in range(6)]
    ragged = srv.http.post("/api/traces/import", content=b"cycle,a\n1,2\n2,3,4\n3,4\n")
    assert ragged.status_code == 422 and "data row 2 has 3 columns" in ragged.text
    meta = srv.http.post("/api/traces/import", content=b"# meta: {}\ncycle,a\n1,2\n2,3\n")
    assert meta.status_code == 422 and "# meta line" in meta.text


def test_the_viewer_stops_with_the_service(tmp_path: Path) -> None:
    s = Server(tmp_path / "viewer.sqlite").start()
    try:
        assert s.http.get("/rerun/", timeout=60).status_code == 200
        log = (tmp_path / "traces" / "rerun-viewer.log").read_text()
        ports = {int(p) for p in re.findall(r"127\.0\.0\.1:(\d+)", log)}
        assert ports and all(listening(p) for p in ports)
    finally:
        s.close()
    assert not any(listening(p) for p in ports)  # no viewer left behind


def children(pid: int) -> list[int]:
    """Processes whose parent is `pid` (from /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # ended while we looked
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def alive(pid: int) -> bool:
    """Running (a zombie waiting for a reaper counts as ended)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_the_viewer_dies_when_the_service_is_killed(tmp_path: Path) -> None:
    s = Server(tmp_path / "kill.sqlite").start()
    assert s.proc is not None
    service = s.proc.pid
    viewers: list[int] = []
    try:
        assert s.http.get("/rerun/", timeout=60).status_code == 200
        viewers = [p for p in children(service) if "--serve-web" in cmdline(p)]
        assert len(viewers) == 1
        # idle request threads end after 10 s; the viewer must outlive the one that asked
        time.sleep(12)
        assert alive(viewers[0]) and s.http.get("/rerun/", timeout=60).status_code == 200
        assert [p for p in children(service) if "--serve-web" in cmdline(p)] == viewers
        s.proc.send_signal(signal.SIGKILL)
        s.proc.wait(timeout=10)
        s.proc = None
        deadline = time.monotonic() + 10
        while alive(viewers[0]) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not alive(viewers[0])  # no orphan left behind
    finally:
        for pid in viewers:  # only on failure: do not leave what this test started
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
        s.close()


def cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def test_recordings_stop_at_their_disk_quota(tmp_path: Path) -> None:
    """All recordings together may take --recordings-quota-mb: a running one stops when it is
    used up, and no new one starts (507 naming the use and the quota)."""
    s = Server(tmp_path / "quota.sqlite", "--no-demo", "--recordings-quota-mb", "0.2").start()
    try:
        r = s.http.post("/api/machines", json={"id": "q", "name": "q", "demo": True})
        assert r.status_code == 201, r.text
        s.wait_powered("q")
        s.pace("q", mode="pause")
        sigs = [x["name"] for x in s.http.get("/api/machines/q/signals").json()][:16]
        started = s.http.post("/api/machines/q/recording", json={"signals": sigs})
        assert started.status_code == 201, started.text
        for _ in range(20):  # 20 s of 16 signals every millisecond: far beyond 200 kB
            s.step("q", 1000)
            rec = s.http.get("/api/machines/q/scope").json()["recording"]
            if not rec["active"]:
                break
            time.sleep(0.3)
        assert not rec["active"] and "quota of 0.2 MB" in rec["stopped_reason"]
        assert rec["bytes"] >= 0.2e6 and rec["cycles"] < 20_000
        again = s.http.post("/api/machines/q/recording", json={"signals": sigs})
        assert again.status_code == 507
        assert re.search(r"use \d+\.\d MB of their 0\.2 MB", again.json()["detail"]["message"])
    finally:
        s.close()


DRIVE_CH = ["X.drive.speed_motor_rpm", "X.drive.torque_nm", "X.drive.pos_load_mm"]


def test_a_drive_rate_capture_samples_every_drive_step_around_the_ncs_trigger(
    srv: Server, mid: str, tmp_path: Path
) -> None:
    """X (drive cascade, p0115 125 µs, 10 mm per motor revolution) jogs at 1000 mm/min: the
    capture holds 8 samples per NC cycle, the pre-trigger at rest, then the motor at
    100 rpm, the load 2.083 µm further each sample, and the torque the friction takes:
    Coulomb 0.15 Nm + viscous 0.0005 Nm·s/rad × 10.47 rad/s."""
    trig = {"type": "level", "signal": "X.vel_cmd_mm_min", "level": 50, "edge": "rising"}
    st = arm(
        srv, mid, channels=DRIVE_CH, length_s=0.5, pretrigger_pct=10, trigger=trig, rate="drive"
    )
    assert st["state"] == "armed"
    assert {c["name"] for c in st["drive_channels"]} >= set(DRIVE_CH)
    srv.step(mid, 100)  # the drive's ring fills the pre-trigger
    jog = {"type": "jog", "axis": "X", "action": "start", "direction": 1, "feed_mm_min": 1000}
    assert srv.command(mid, {**jog, "hold_s": 5}).status_code == 200
    srv.step(mid, 700)
    st = scope(srv, mid)
    assert st["state"] == "done"
    cap = st["captures"][0]
    assert cap["cycle_s"] == pytest.approx(125e-6)
    # 50 cycles of pre-trigger, and the steps of the first cycle before the NC's first
    # sample (the state at its end)
    assert cap["count"] == 4000 and cap["trigger_cycle"] - cap["first_cycle"] == 408
    header, data = samples(srv, cap["id"])
    assert header.signals == DRIVE_CH and header.cycle_s == pytest.approx(125e-6)
    speed, torque, pos = data
    assert np.max(np.abs(speed[:400])) < 0.1  # at rest before the trigger
    steady = slice(-800, None)  # the last 100 ms
    assert np.mean(speed[steady]) == pytest.approx(100.0, rel=0.005)
    assert np.mean(np.diff(pos[steady])) == pytest.approx(1000 / 60 * 125e-6, rel=0.005)
    assert np.mean(torque[steady]) == pytest.approx(0.15 + 0.0005 * 100 * 2 * np.pi / 60, rel=0.03)
    r = srv.http.get(f"/api/traces/{cap['id']}/trace.rrd")
    path = tmp_path / "drive.rrd"
    path.write_bytes(r.content)
    rows = rrd_chunks(path)
    assert rows[f"/{mid}/" + DRIVE_CH[0].rsplit(".", 1)[0].replace(".", "/")] == 4000  # per step


def test_drive_rate_captures_refuse_what_a_drive_cannot_record(srv: Server, mid: str) -> None:
    def put(**setup: Any) -> Any:
        trig = {"type": "event", "event": "m_start"}
        body = {"length_s": 0.2, "trigger": trig, "rate": "drive", **setup}
        return srv.http.put(f"/api/machines/{mid}/scope", json=body)

    r = put(channels=["S1.drive.speed_motor_rpm"])  # the demo's spindle: the ideal plant
    assert r.status_code == 422 and "IDEAL" in r.text
    r = put(channels=["X.drive.torque_nm", "Z.drive.torque_nm"])
    assert r.status_code == 422 and "one axis" in r.text
    r = put(channels=["X.lag_mm"])
    assert r.status_code == 422 and "X.lag_mm" in r.text
    r = put(channels=["X.drive.torque_nm"], length_s=3.0)
    assert r.status_code == 422 and "2 s" in r.text
    assert scope(srv, mid)["state"] == "idle"  # nothing armed by any of them
