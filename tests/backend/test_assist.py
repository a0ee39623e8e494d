"""The assistants over real HTTP on a live service: they run on a copy of the machine with its
parameters as written, the live machine does not move, and bad requests get a clear 422.

The plant is made wrong through the simulated drive (`sim.drive_gain` 22857 digits per 1 m/min
where the NC assumes multi_gain 10000): physics gives f = 22857 / 10000 [004 §3.6.2].
"""

from __future__ import annotations

from typing import Any

import pytest

from tests.backend.server import Server


def _assist(srv: Server, mid: str, name: str, body: dict[str, Any]) -> Any:
    return srv.http.post(f"/api/machines/{mid}/assist/{name}", json=body, timeout=120)


def test_multi_gain_on_a_copy_proposes_the_correction_and_the_machine_stays(
    srv: Server, lathe: str
) -> None:
    body = {"changes": [{"scope": "axis", "target": "X", "name": "sim.drive_gain", "value": 22857}]}
    r = srv.http.patch(f"/api/machines/{lathe}/parameters", json=body)
    assert r.status_code == 200, r.text
    x0 = srv.axis("X", lathe)["pos_cmd"]
    r = _assist(srv, lathe, "multi-gain", {"axis": "X", "feed_mm_min": 200})
    assert r.status_code == 200, r.text
    res = r.json()
    fig = {f["name"]: f["value"] for f in res["figures"]}
    assert res["ok"] and fig["f"] == pytest.approx(2.2857, rel=0.01)
    assert fig["k"] == pytest.approx(20.0 / 2.2857, rel=0.01)
    after = {c["parameter"]: c["after"] for c in res["changes"]}
    assert after["getriebe[0].kv"] == pytest.approx(2000 / 2.2857, abs=1)
    assert after["getriebe[0].multi_gain_z"] / after["getriebe[0].multi_gain_n"] == pytest.approx(
        22857, rel=0.01
    )
    assert srv.axis("X", lathe)["pos_cmd"] == x0  # the live machine did not move


def test_the_sign_check_finds_an_inverted_encoder(srv: Server, lathe: str) -> None:
    body = {
        "changes": [{"scope": "axis", "target": "X", "name": "sim.encoder_inverted", "value": 1}]
    }
    assert srv.http.patch(f"/api/machines/{lathe}/parameters", json=body).status_code == 200
    # the plant's wiring takes effect with the restart (effect "restart"), on the copy as well
    assert srv.http.post(f"/api/machines/{lathe}/restart").status_code == 200
    srv.wait_powered(lathe)
    r = _assist(srv, lathe, "sign-check", {"axis": "X"})
    assert r.status_code == 200, r.text
    assert [c["parameter"] for c in r.json()["changes"]] == ["lr_hw[0].vz_istw"]


def test_bad_requests_are_422_and_say_why(srv: Server, lathe: str) -> None:
    r = _assist(srv, lathe, "multi-gain", {"axis": "X"})
    assert r.status_code == 422 and "feed" in r.text
    r = _assist(srv, lathe, "multi-gain", {"axis": "Q", "feed_mm_min": 100})
    assert r.status_code == 422 and "Q" in r.text
    r = _assist(srv, lathe, "multi-gain", {"axis": "X", "feed_mm_min": -5})
    assert r.status_code == 422 and "feed_mm_min" in r.text
    assert _assist(srv, "nope", "sign-check", {"axis": "X"}).status_code == 404


def test_the_loop_gain_sweep_proposes_kv_and_the_machine_stays(srv: Server, lathe: str) -> None:
    """X on a 20 ms drive: the second-order loop's step overshoots 0.09 % at kv 15/s and
    7.0 % at 30/s (ζ = 1/(2√(kv·T))); with 5 % allowed 15 is proposed; the ramp's lag at
    600 mm/min (10 mm/s) is v/kv."""
    body = {
        "changes": [
            {"scope": "axis", "target": "X", "name": "sim.plant", "value": "IDEAL"},
            {"scope": "axis", "target": "X", "name": "sim.drive_t", "value": 20000},
        ]
    }
    assert srv.http.patch(f"/api/machines/{lathe}/parameters", json=body).status_code == 200
    x0 = srv.axis("X", lathe)["pos_cmd"]
    req = {"axis": "X", "kvs": [10, 15, 30], "settle_ms": 300, "feed_mm_min": 600}
    r = _assist(srv, lathe, "loop-gain", req)
    assert r.status_code == 200, r.text
    res = r.json()
    fig = {f["name"]: f["value"] for f in res["figures"]}
    assert res["ok"] and fig["kv_new"] == 15.0
    assert fig["lag@15"] == pytest.approx(10.0 / 15.0, abs=1e-4)
    assert fig["overshoot_pct@30"] > 5.0 >= fig["overshoot_pct@15"]
    assert [(c["parameter"], c["after"]) for c in res["changes"]] == [("getriebe[0].kv", 1500)]
    assert srv.axis("X", lathe)["pos_cmd"] == x0  # the live machine did not move


def test_bad_loop_gain_requests_are_422_and_say_why(srv: Server, lathe: str) -> None:
    r = _assist(srv, lathe, "loop-gain", {"axis": "X", "kvs": [10, -5]})
    assert r.status_code == 422 and "kvs" in r.text
    r = _assist(srv, lathe, "loop-gain", {"axis": "X", "kvs": list(range(1, 20))})
    assert r.status_code == 422 and "kvs" in r.text
    r = _assist(srv, lathe, "loop-gain", {"axis": "S1"})
    assert r.status_code == 422 and "spindle" in r.text


def test_the_frequency_response_of_a_two_mass_axis_over_http(srv: Server, lathe: str) -> None:
    """X on the drive cascade with a coupling: anti-resonance 70 Hz, J_L = 2·J_M (p0342 = 3),
    so the resonance sits at 70·√3 = 121.2 Hz; the Bode data come back thinned on a log
    frequency grid with the coherence; the IDEAL plant is refused with a 422 that says why."""
    ideal = [{"scope": "axis", "target": "X", "name": "sim.plant", "value": "IDEAL"}]
    r = srv.http.patch(f"/api/machines/{lathe}/parameters", json={"changes": ideal})
    assert r.status_code == 200, r.text
    r = _assist(srv, lathe, "frequency-response", {"axis": "X"})
    assert r.status_code == 422 and "IDEAL" in r.text
    values = {"sim.plant": "DRIVE_CASCADE", "drive.inertia_ratio": 3.0}
    values["sim.mech.anti_resonance"] = 70.0
    changes = [{"scope": "axis", "target": "X", "name": k, "value": v} for k, v in values.items()]
    r = srv.http.patch(f"/api/machines/{lathe}/parameters", json={"changes": changes})
    assert r.status_code == 200, r.text
    r = _assist(srv, lathe, "frequency-response", {"axis": "X", "measurement": 1})
    assert r.status_code == 200, r.text
    res = r.json()
    fig = {f["name"]: f["value"] for f in res["figures"]}
    assert fig["anti_resonance_1_hz"] == pytest.approx(70.0, rel=0.02)
    assert fig["resonance_1_hz"] == pytest.approx(70.0 * 3**0.5, rel=0.02)
    series = {s["name"]: s for s in res["series"]}
    assert set(series) == {"magnitude_db", "phase_deg", "coherence"}
    f = series["magnitude_db"]["x"]
    assert len(f) <= 600 and f == sorted(f) and f[-1] / f[0] > 500  # 5 Hz to 4 kHz, log-spaced
