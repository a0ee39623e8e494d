"""The machine's simulated plant made as a test needs it, through the API, before the browser
acts: the engineer's starting point, not a step of the test."""

from __future__ import annotations

from typing import Any

from tests.backend.server import Server

DRIVE_GAIN = 22857  # digits for 1 m/min, the X drive as it really is in the wrong-drive tests
MULTI_GAIN = 10000  # getriebe[0].multi_gain_z / _n of the demo's X: what the NC assumes
KV_RAW = 2000  # getriebe[0].kv of the demo's X, 0.01/s


def set_up(
    srv: Server, mid: str, target: str, values: dict[str, Any], restart: bool = False
) -> None:
    """Write `values` into `target`'s list, power-cycle when they take effect at restart (the
    plant's wiring), and release the control the write took, for the browser's user."""
    changes = [
        {"scope": "axis", "target": target, "name": k, "value": v} for k, v in values.items()
    ]
    r = srv.http.patch(f"/api/machines/{mid}/parameters", json={"changes": changes})
    assert r.status_code == 200, r.text
    if restart:
        assert srv.http.post(f"/api/machines/{mid}/restart").status_code == 200
        srv.wait_powered(mid)
    r = srv.http.post(f"/api/machines/{mid}/control", json={"action": "release"})
    assert r.status_code == 200, r.text
