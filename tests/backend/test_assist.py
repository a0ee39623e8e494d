"""The assistants over real HTTP on a live service: they run on a copy of the machine with its
parameters as written, the live machine does not move, and bad requests get a clear 422.

The plant is made wrong through the simulated drive (`sim.drive_gain` 22857 digits per 1 m/min
where the NC assumes multi_gain 10000): physics gives f = 22857 / 10000 [004 §3.6.2].
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from tests.backend.server import Server


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("assist") / "assist.sqlite").start()
    yield s
    s.close()


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
