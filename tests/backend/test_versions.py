"""Parameter versions over real HTTP: take a version, compare it with the live parameters, the
manuals' defaults and other versions, roll back through the parameter write (and back again),
the baseline, the audit trail, bad input, and everything surviving a restart of the service."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import httpx
import pytest

from api.parameters import ParameterChange
from api.versions import ParamDiff
from backend.services import parameters
from backend.services.versions import Versions
from nc_sim.params import Scope, registry
from nc_sim.params.listfile import resolve
from tests.backend.inprocess import INSTRUCTOR, machine_service, paused_demo
from tests.backend.server import USER, Server

KV = registry().by_id("P-AXIS-00099")  # getriebe[i].kv, in 0.01/s (004 §3.6)
SIGN = resolve(Scope.AXIS, "lr_hw[0].vz_stellgr")  # 004 §3.5, takes effect at restart


def url(mid: str, path: str = "") -> str:
    return f"/api/machines/{mid}/versions{path}"


def write(srv: Server, mid: str, name: str, value: Any, target: str = "X") -> httpx.Response:
    change = {"scope": "axis", "target": target, "name": name, "value": value}
    r = srv.http.patch(f"/api/machines/{mid}/parameters", json={"changes": [change]})
    assert r.status_code == 200, r.text
    return r


def value(srv: Server, mid: str, name: str, target: str = "X") -> dict[str, Any]:
    r = srv.http.get(f"/api/machines/{mid}/parameters", params={"scope": "axis", "target": target})
    return next(p for p in r.json() if p["name"] == name)


def take(srv: Server, mid: str, name: str, **kw: Any) -> dict[str, Any]:
    r = srv.http.post(url(mid), json={"name": name, **kw})
    assert r.status_code == 201, r.text
    body: dict[str, Any] = r.json()
    return body


def diff(srv: Server, mid: str, a: str | int, b: str | int) -> list[dict[str, Any]]:
    r = srv.http.get(url(mid, "/diff"), params={"from": str(a), "to": str(b)})
    assert r.status_code == 200, r.text
    changes: list[dict[str, Any]] = r.json()["changes"]
    return changes


def audit_actions(srv: Server, mid: str, kind: str) -> list[str]:
    """What was done (refusals left out), oldest first."""
    rows = srv.http.get(f"/api/machines/{mid}/audit", params={"kind": kind}).json()["rows"]
    return [r["action"] for r in reversed(rows) if r["outcome"] == "ok"]


def test_take_change_compare_roll_back_and_revert(srv: Server, lathe: str) -> None:
    write(srv, lathe, "getriebe[0].kv", 250)
    v1 = take(srv, lathe, "kv 2.5", note="before tuning X")
    assert (v1["name"], v1["note"], v1["created_by"], v1["baseline"]) == (
        "kv 2.5",
        "before tuning X",
        USER,
        False,
    )
    write(srv, lathe, "getriebe[0].kv", 300)
    (kv,) = diff(srv, lathe, v1["id"], "live")
    assert (kv["target"], kv["parameter"], kv["id"]) == ("X", "getriebe[0].kv", "P-AXIS-00099")
    assert (kv["before"], kv["after"], kv["unit"]) == (250, 300, "0.01/s")
    # the parameter page's engineering column: kv in 0.01/s → 1/s
    assert (kv["before_eng"], kv["after_eng"], kv["eng_unit"]) == (
        pytest.approx(2.5),
        pytest.approx(3.0),
        "1/s",
    )
    # the other way round is the same change backwards
    (back,) = diff(srv, lathe, "live", v1["id"])
    assert (back["before"], back["after"]) == (300, 250)

    r = srv.http.post(url(lathe, f"/{v1['id']}/rollback"), json={"comment": "too lively"})
    assert r.status_code == 200, r.text
    assert [
        (c["target"], c["name"], c["old"], c["new"], c["pending"]) for c in r.json()["changes"]
    ] == [("X", "getriebe[0].kv", 300, 250, False)]
    assert value(srv, lathe, "getriebe[0].kv")["value"] == 250
    assert diff(srv, lathe, v1["id"], "live") == []
    # Revert of the trial: the HMI writes the old values back through the same write
    write(srv, lathe, "getriebe[0].kv", 300)
    assert value(srv, lathe, "getriebe[0].kv")["value"] == 300

    assert audit_actions(srv, lathe, "version") == [
        f"took version 'kv 2.5' ({v1['values']} written values)",
        "rolled back to version 'kv 2.5' (1 value changed)",
    ]
    kv_rows = [
        (a["old"], a["new"], a["comment"])
        for a in srv.http.get(f"/api/machines/{lathe}/parameters/audit").json()
        if a["name"] == "getriebe[0].kv" and a["target"] == "X"
    ]
    assert kv_rows[-3:] == [
        (250, 300, ""),
        (300, 250, "rollback to version 'kv 2.5': too lively"),
        (250, 300, ""),
    ]


def test_a_rollback_of_a_restart_value_is_pending_like_any_write(srv: Server, lathe: str) -> None:
    v = take(srv, lathe, "signs as delivered")
    write(srv, lathe, "lr_hw[0].vz_stellgr", 1)
    (sign,) = diff(srv, lathe, v["id"], "live")  # pending values are part of the live state
    assert (sign["parameter"], sign["before"], sign["after"], sign["effect"]) == (
        "lr_hw[0].vz_stellgr",
        SIGN.default,
        1,
        "restart",
    )
    assert srv.http.post(f"/api/machines/{lathe}/restart").status_code == 200  # 1 in force
    r = srv.http.post(url(lathe, f"/{v['id']}/rollback"), json={})
    (c,) = r.json()["changes"]
    assert (c["name"], c["old"], c["new"], c["pending"], c["effect"]) == (
        "lr_hw[0].vz_stellgr",
        1,
        SIGN.default,
        True,
        "restart",
    )
    assert value(srv, lathe, "lr_hw[0].vz_stellgr")["pending"] == SIGN.default


def test_against_the_manuals_defaults(srv: Server, lathe: str) -> None:
    write(srv, lathe, "getriebe[0].kv", 250)
    changes = diff(srv, lathe, "defaults", "live")
    kv = next(c for c in changes if c["parameter"] == "getriebe[0].kv" and c["target"] == "X")
    assert (kv["before"], kv["after"]) == (KV.default, 250)
    # a value nobody wrote is its default on both sides: no difference
    assert not [c for c in changes if c["parameter"] == "lr_hw[0].vz_istw"]
    # nor is a symbol's code: X is linear, achs_typ 1 = the default ACHSTYP_TRANSLATOR
    assert value(srv, lathe, "kenngr.achs_typ")["value"] == 1
    assert resolve(Scope.AXIS, "kenngr.achs_typ").symbols["ACHSTYP_TRANSLATOR"] == 1
    assert not [c for c in changes if c["parameter"] == "kenngr.achs_typ" and c["target"] == "X"]
    assert all(c["before"] != c["after"] for c in changes)


def test_the_baseline(srv: Server, lathe: str) -> None:
    r = srv.http.get(url(lathe, "/diff"))  # from the baseline to live by default
    assert r.status_code == 404 and "baseline" in r.json()["detail"]["message"]
    start = take(srv, lathe, "as delivered", baseline=True)
    assert start["baseline"] and diff(srv, lathe, "baseline", "live") == []
    write(srv, lathe, "getriebe[0].kv", 1500)
    later = take(srv, lathe, "kv 15")
    (kv,) = srv.http.get(url(lathe, "/diff")).json()["changes"]
    assert (kv["parameter"], kv["after"]) == ("getriebe[0].kv", 1500)

    r = srv.http.delete(url(lathe, f"/{start['id']}"))
    assert r.status_code == 409 and "baseline" in r.json()["detail"]["message"]
    r = srv.http.post(url(lathe, f"/{later['id']}/baseline"))
    assert r.status_code == 200 and r.json()["baseline"]
    listed = srv.http.get(url(lathe)).json()
    assert [(v["name"], v["baseline"]) for v in listed] == [  # newest first
        ("kv 15", True),
        ("as delivered", False),
    ]
    assert diff(srv, lathe, "baseline", "live") == []
    assert srv.http.delete(url(lathe, f"/{start['id']}")).status_code == 204
    assert srv.http.delete(url(lathe, f"/{start['id']}")).status_code == 404
    assert audit_actions(srv, lathe, "version")[-3:] == [
        f"took version 'kv 15' ({later['values']} written values)",
        "set baseline: version 'kv 15'",
        "deleted version 'as delivered'",
    ]


def test_bad_input_is_refused_clearly_and_changes_nothing(srv: Server, lathe: str) -> None:
    v = take(srv, lathe, "Tuned")
    r = srv.http.post(url(lathe), json={"name": "tuned"})  # the same name in another case
    assert r.status_code == 409 and "already has a version named 'tuned'" in r.text
    for body in (
        {"name": ""},
        {"name": "   "},
        {"name": "x" * 81},
        {"name": "a", "note": "n" * 1001},
    ):
        assert srv.http.post(url(lathe), json=body).status_code == 422, body
    assert srv.http.get(url(lathe, "/diff"), params={"from": "yesterday"}).status_code == 422
    gone = 10**9
    assert srv.http.get(url(lathe, "/diff"), params={"from": gone}).status_code == 404
    assert srv.http.post(url(lathe, f"/{gone}/rollback"), json={}).status_code == 404
    assert srv.http.post(url(lathe, f"/{gone}/baseline")).status_code == 404
    assert srv.http.delete(url(lathe, f"/{gone}")).status_code == 404
    assert srv.http.get(url("nosuchmachine")).status_code == 404
    assert [x["name"] for x in srv.http.get(url(lathe)).json()] == [v["name"]]
    refused = srv.http.get(
        f"/api/machines/{lathe}/audit", params={"kind": "version", "text": "refused"}
    ).json()["rows"]
    assert any("take version 'tuned'" in r["action"] for r in refused)


def test_versions_survive_a_restart_and_go_with_their_machine(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    s = Server(tmp_path_factory.mktemp("versions-restart") / "db.sqlite").start()
    try:
        s.wait_powered("demo")
        write(s, "demo", "getriebe[0].kv", 250)
        v = take(s, "demo", "kept", baseline=True, note="survives")
        write(s, "demo", "getriebe[0].kv", 300)
        s.stop()
        s.start()
        (kept,) = s.http.get(url("demo")).json()
        assert kept == v
        (kv,) = diff(s, "demo", "baseline", "live")
        assert (kv["before"], kv["after"]) == (250, 300)
        s.wait_powered("demo")
        r = s.http.post(url("demo", f"/{v['id']}/rollback"), json={})
        assert r.status_code == 200 and value(s, "demo", "getriebe[0].kv")["value"] == 250

        assert s.http.post("/api/machines", json={"id": "m2", "demo": True}).status_code == 201
        take(s, "m2", "of m2")
        assert s.http.delete("/api/machines/m2").status_code == 204
        assert s.http.post("/api/machines", json={"id": "m2", "demo": True}).status_code == 201
        assert s.http.get(url("m2")).json() == []  # a new machine of the same name has none
    finally:
        s.close()


def test_baseline_diff_for_the_commissioning_report(tmp_path: Path) -> None:
    """`Versions.baseline_diff`, as the report calls it: None without a baseline, else the
    live parameters against it."""
    with machine_service(tmp_path) as service:
        m = paused_demo(service, "lathe")
        versions = Versions(service.store, service)
        assert asyncio.run(versions.baseline_diff("lathe")) is None
        versions.take(INSTRUCTOR, "lathe", "as delivered", "", baseline=True)
        assert asyncio.run(versions.baseline_diff("lathe")) == []
        kv = ParameterChange(scope="axis", target="X", name="getriebe[0].kv", value=2500)
        parameters.write(INSTRUCTOR, m, service.store, [kv])
        (change,) = asyncio.run(versions.baseline_diff("lathe")) or []
        assert isinstance(change, ParamDiff)
        assert (change.target, change.parameter, change.before, change.after, change.unit) == (
            "X",
            "getriebe[0].kv",
            2000,
            2500,
            "0.01/s",
        )
