"""Assistants live, over real HTTP: the experiment runs on the machine itself in its worker,
paced in real time; everyone watching sees its progress in the status; it can be cancelled,
an E-stop ends it; each run is audited.

Physics for the numbers: X's drive gives 22857 digits per 1 m/min where the NC assumes 10000,
so f = 2.2857 [004 §3.6.2]; the axis moves at 200 mm/min for the run's planned time.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import httpx
import pytest

from tests.backend.server import Server


def _live(srv: Server, mid: str, name: str, body: dict[str, Any]) -> httpx.Response:
    return srv.http.post(f"/api/machines/{mid}/assist/live/{name}", json=body, timeout=120)


class _Background:
    """A live run whose answer comes later (the test looks at the machine meanwhile)."""

    def __init__(self, srv: Server, mid: str, name: str, body: dict[str, Any]) -> None:
        self.answer: httpx.Response | None = None
        self.thread = threading.Thread(target=self._run, args=(srv, mid, name, body))
        self.thread.start()

    def _run(self, srv: Server, mid: str, name: str, body: dict[str, Any]) -> None:
        self.answer = _live(srv, mid, name, body)

    def result(self) -> httpx.Response:
        self.thread.join(60)
        assert self.answer is not None
        return self.answer


def _progress(srv: Server, mid: str) -> dict[str, Any]:
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        running = srv.status(mid)["assist"]
        if running is not None:
            return dict(running)
        time.sleep(0.05)
    raise AssertionError("the status never showed the run")


def test_live_multi_gain_moves_the_machine_and_proposes_the_correction(
    srv: Server, lathe: str
) -> None:
    body = {"changes": [{"scope": "axis", "target": "X", "name": "sim.drive_gain", "value": 22857}]}
    assert srv.http.patch(f"/api/machines/{lathe}/parameters", json=body).status_code == 200
    x0 = srv.axis("X", lathe)["pos_act"]
    run = _Background(srv, lathe, "multi-gain", {"axis": "X", "feed_mm_min": 200})
    seen = _progress(srv, lathe)
    assert seen["name"] == "multi-gain" and seen["axis"] == "X" and seen["by"]
    # the plan: 2 s ramp allowance + 5·3/kv (kv 20/s) + 1 s window, and the move goes on
    # 2 s more to its target
    planned_s = 2 + 15 / 20 + 1 + 2
    assert seen["planned_s"] == pytest.approx(planned_s)
    r = run.result()
    assert r.status_code == 200, r.text
    fig = {f["name"]: f["value"] for f in r.json()["figures"]}
    assert fig["f"] == pytest.approx(2.2857, rel=0.01)
    # the machine itself moved: 200 mm/min for the planned time, to its target
    assert srv.axis("X", lathe)["pos_cmd"] - x0 == pytest.approx(200 / 60 * planned_s, 1e-6)
    assert srv.status(lathe)["assist"] is None
    audit = srv.http.get(f"/api/machines/{lathe}/audit").json()["rows"]
    live = [a for a in audit if a["action"] == "assist live multi-gain"]
    assert live and live[0]["outcome"] == "ok" and live[0]["kind"] == "assist"
    assert live[0]["detail"]["figures"]["f"] == pytest.approx(2.2857, rel=0.01)
    # stored for the commissioning report, as measured on the machine itself
    runs = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    assert runs[0]["assistant"] == "multi-gain" and runs[0]["live"] is True


def test_cancel_ends_the_run_and_the_axis_stops(srv: Server, lathe: str) -> None:
    run = _Background(srv, lathe, "multi-gain", {"axis": "X", "feed_mm_min": 300})
    _progress(srv, lathe)
    # one run at a time
    again = _live(srv, lathe, "multi-gain", {"axis": "Z", "feed_mm_min": 100})
    assert again.status_code == 409 and "multi-gain runs" in again.text
    r = srv.http.post(f"/api/machines/{lathe}/assist/live/cancel", json={})
    assert r.status_code == 204, r.text
    answer = run.result()
    assert answer.status_code == 409 and "cancelled" in answer.text
    deadline = time.monotonic() + 5
    while srv.axis("X", lathe)["state"] != "STANDSTILL" and time.monotonic() < deadline:
        time.sleep(0.05)
    assert srv.axis("X", lathe)["state"] == "STANDSTILL"
    r = srv.http.post(f"/api/machines/{lathe}/assist/live/cancel", json={})
    assert r.status_code == 409  # nothing runs now


def test_an_emergency_stop_ends_the_run(srv: Server, lathe: str) -> None:
    run = _Background(srv, lathe, "multi-gain", {"axis": "Z", "feed_mm_min": 300})
    _progress(srv, lathe)
    assert srv.emergency_stop(lathe).status_code == 200
    answer = run.result()
    assert answer.status_code == 409 and "emergency stop" in answer.text


def test_a_refused_motion_is_a_422_in_the_ncs_words(srv: Server, lathe: str) -> None:
    s0 = srv.axis("S1", lathe)
    r = _live(srv, lathe, "multi-gain", {"axis": "S1", "speed_rpm": 50000})
    assert r.status_code == 422 and "refused" in r.text
    assert srv.axis("S1", lathe)["state"] == s0["state"]


def test_an_assistant_from_its_descriptor_alone_runs_live_and_is_listed(
    srv: Server, lathe: str
) -> None:
    """The resolution check exists only as its procedure and its registry entry: the
    catalogue lists it with its request schema, the live route runs it on the machine (with
    an encoder delivering 1.02 × the increments per unit set, the NC counts 1.02 × the true
    travel, k = 1.02), the run list and its summary come from the descriptor."""
    listed = {a["name"]: a for a in srv.http.get("/api/assistants").json()}
    check = listed["resolution-check"]
    assert check["kind"] == "experiment" and check["live"] and check["section"] == "004 §3.4"
    assert check["request"]["properties"]["distance"]["x-unit"] == "mm"
    fault = {"fault": {"kind": "encoder_resolution_wrong", "axis": "X", "factor": 1.02}}
    assert srv.http.post(f"/api/machines/{lathe}/faults", json=fault).status_code == 201
    x0 = srv.axis("X", lathe)["pos_act"]
    r = _live(srv, lathe, "resolution-check", {"axis": "X", "distance": 20})
    assert r.status_code == 200, r.text
    fig = {f["name"]: f["value"] for f in r.json()["figures"]}
    assert fig["k"] == pytest.approx(1.02, abs=50e-6)
    assert srv.axis("X", lathe)["pos_cmd"] - x0 == pytest.approx(20, abs=1e-9)
    runs = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    assert runs[0]["assistant"] == "resolution-check" and runs[0]["summary"].startswith("k = 1.02")
    bad = _live(srv, lathe, "resolution-check", {"axis": "X", "distance": 5000})
    assert bad.status_code == 422 and "1000 mm" in bad.text


def test_a_live_frequency_response_excites_the_drive_in_its_worker(srv: Server, lathe: str) -> None:
    """X's mechanics measured on the machine itself, paced in real time by its worker: the
    coupling's frequencies come out as physics has them (anti-resonance 80 Hz, J_L = 2·J_M:
    resonance 80·√3 = 138.6 Hz); after the offset motion the run put the axis back where it
    started, at rest in its exact-stop window."""
    values = {"sim.plant": "DRIVE_CASCADE", "drive.inertia_ratio": 3.0}
    values["sim.mech.anti_resonance"] = 80.0
    changes = [{"scope": "axis", "target": "X", "name": k, "value": v} for k, v in values.items()]
    assert srv.http.patch(f"/api/machines/{lathe}/parameters", json={"changes": changes}).is_success
    x0 = srv.axis("X", lathe)["pos_act"]
    body = {"axis": "X", "f_min_hz": 20.0, "averages": 3, "offset_rpm": 30.0}
    run = _Background(srv, lathe, "frequency-response", body)
    seen = _progress(srv, lathe)
    assert seen["name"] == "frequency-response" and seen["axis"] == "X"
    r = run.result()
    assert r.status_code == 200, r.text
    fig = {f["name"]: f["value"] for f in r.json()["figures"]}
    assert fig["anti_resonance_1_hz"] == pytest.approx(80.0, rel=0.02)
    assert fig["resonance_1_hz"] == pytest.approx(80.0 * 3**0.5, rel=0.02)
    x = srv.axis("X", lathe)
    assert x["pos_act"] == pytest.approx(x0, abs=0.01) and x["state"] == "STANDSTILL"
    assert srv.status(lathe)["assist"] is None
    runs = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    assert runs[0]["assistant"] == "frequency-response" and runs[0]["live"] is True


def test_a_live_circle_runs_the_ncs_own_program_and_comes_back(srv: Server, lathe: str) -> None:
    """The circularity test on the machine itself: G03 then G02 about where Z and X stand,
    paced in real time; the axes end where they started, the run is stored for the plane
    (ZX) and audited. A P loop at kv 20/s shrinks R5 at F2000 by about
    R(1 − 1/√(1 + (ω/kv)²)) = 34.5 µm (ω = F/R = 6.67/s)."""
    z0, x0 = srv.axis("Z", lathe)["pos_cmd"], srv.axis("X", lathe)["pos_cmd"]
    body = {"radius_mm": 5.0, "feed_mm_min": 2000.0, "overrun_deg": 45}
    run = _Background(srv, lathe, "circle", body)
    assert _progress(srv, lathe)["axis"] == "ZX"  # everyone watching sees the plane
    r = run.result()
    assert r.status_code == 200, r.text
    assert r.json()["run_id"] == srv.http.get(f"/api/machines/{lathe}/assist/runs").json()[0]["id"]
    fig = {f["name"]: f["value"] for f in r.json()["figures"]}
    omega = 2000 / 60 / 5
    shrink_um = 5 * (1 - 1 / (1 + (omega / 20) ** 2) ** 0.5) * 1000
    assert -fig["radius_change_ccw_um"] == pytest.approx(shrink_um, rel=0.2)
    assert [s["name"] for s in r.json()["series"]] == ["CCW", "CW"]
    assert srv.axis("Z", lathe)["pos_cmd"] == pytest.approx(z0, abs=1e-4)
    assert srv.axis("X", lathe)["pos_cmd"] == pytest.approx(x0, abs=1e-4)
    runs = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    assert runs[0]["assistant"] == "circle" and runs[0]["axis"] == "ZX" and runs[0]["live"]
    audit = srv.http.get(f"/api/machines/{lathe}/audit").json()["rows"]
    assert any(a["action"] == "assist live circle" and a["outcome"] == "ok" for a in audit)


def test_a_live_run_does_not_start_on_a_paused_machine(srv: Server, lathe: str) -> None:
    """Paused, the machine would hold the run before its first cycle while the request
    waits: it is refused at once instead, and nothing moves."""
    srv.pace(lathe, mode="pause")
    z0 = srv.axis("Z", lathe)["pos_cmd"]
    r = _live(srv, lathe, "circle", {"radius_mm": 1.0})
    assert r.status_code == 409 and "paused" in r.text
    assert srv.axis("Z", lathe)["pos_cmd"] == z0
    assert srv.status(lathe)["assist"] is None


def test_a_live_autotune_measures_on_the_machine_and_leaves_its_values_alone(
    srv: Server, lathe: str
) -> None:
    """The autotune on the machine itself (paced fast): measured and tuned there, the new
    values proposed, not tried (no validation on the machine: apply on trial, measure
    again); the drive's values as they were, X back where it started."""
    change = {"scope": "axis", "target": "X", "name": "drive.speed_kp", "value": 0.125}
    assert srv.http.patch(
        f"/api/machines/{lathe}/parameters", json={"changes": [change]}
    ).is_success
    srv.pace(lathe, mode="fast")
    x0 = srv.axis("X", lathe)["pos_act"]
    r = _live(srv, lathe, "autotune", {"axis": "X", "template": 1})
    assert r.status_code == 200, r.text
    fig = {f["name"]: f["value"] for f in r.json()["figures"]}
    assert fig["pm_deg"] >= 45.0 and fig["gm_db"] >= 8.0 and fig["kp"] > 0.125
    assert "pm_achieved_deg" not in fig
    assert any("apply on trial" in n for n in r.json()["notes"])
    rows = srv.http.get(f"/api/machines/{lathe}/parameters?scope=axis&target=X").json()
    assert next(p["value"] for p in rows if p["name"] == "drive.speed_kp") == 0.125
    assert srv.axis("X", lathe)["pos_act"] == pytest.approx(x0, abs=0.01)
    runs = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    assert runs[0]["assistant"] == "autotune" and runs[0]["live"] is True
