"""The service-axis view over real HTTP: the demo's X at constant feed shows the lag the loop
should give, v/kv, and the measured gain k = v/lag equal to kv (the demo's drive matches
multi_gain); an unknown machine is a 404."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest

from tests.backend.server import Server

KV_X = 20.0  # getriebe[0].kv 2000 in 0.01/s (nc_sim/config/demo/axis_1.lis)


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("svc") / "svc.sqlite").start()
    yield s
    s.close()


def _x(srv: Server) -> dict[str, Any]:
    r = srv.http.get("/api/machines/demo/service-axes")
    assert r.status_code == 200, r.text
    axes = {a["name"]: a for a in r.json()["axes"]}
    assert set(axes) >= {"X", "Z", "S1"}
    x: dict[str, Any] = axes["X"]
    return x


def test_demo_x_at_constant_feed(srv: Server) -> None:
    deadline = time.monotonic() + 30
    while "standstill" not in (x := _x(srv))["k_why_not"]:  # once 0.5 s of records exist
        assert x["k_measured_per_s"] is None, x
        assert time.monotonic() < deadline, x
        time.sleep(0.1)
    r = srv.command("demo", {"type": "mdi", "block": "G01 G91 X150 F1000"})
    assert r.status_code in (200, 202), r.text
    deadline = time.monotonic() + 30
    while (x := _x(srv))["k_measured_per_s"] is None:
        assert time.monotonic() < deadline, x
        time.sleep(0.1)
    v = 1000.0 / 60.0  # mm/s
    assert x["kv_per_s"] == pytest.approx(KV_X)
    assert x["lag_expected"] == pytest.approx(v / KV_X)
    assert x["k_measured_per_s"] == pytest.approx(KV_X, rel=0.01)
    assert x["velocity"]["source"] == "F (path) × 1" and x["velocity"]["unit"] == "mm/min"
    assert x["velocity"]["value"] == pytest.approx(1000.0)  # X alone: all of F
    assert x["acceleration"]["param_id"] == "P-AXIS-00001"  # a_beschl below a_max


def test_unknown_machine(srv: Server) -> None:
    assert srv.http.get("/api/machines/nope/service-axes").status_code == 404
