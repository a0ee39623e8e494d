"""Parameters over real HTTP: validated writes, pending values, audit in SQLite, import and
export of the native list format, and everything surviving a restart of the service."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from nc_sim.params import registry
from tests.backend.server import USER, Server

OWN_SERVICE = True  # restarts the service

DATA = Path(__file__).resolve().parents[1] / "nc_sim" / "params" / "data"
KV = registry().by_id("P-AXIS-00099")  # getriebe[i].kv


def values(srv: Server, mid: str, target: str | None = "X", scope: str = "axis") -> dict[str, Any]:
    params: dict[str, Any] = {"scope": scope}
    if target:
        params["target"] = target
    r = srv.http.get(f"/api/machines/{mid}/parameters", params=params)
    r.raise_for_status()
    return {p["name"]: p for p in r.json()}


def write(srv: Server, mid: str, *changes: tuple[str, str | None, str, Any]) -> Any:
    body = {"changes": [{"scope": s, "target": t, "name": n, "value": v} for s, t, n, v in changes]}
    return srv.http.patch(f"/api/machines/{mid}/parameters", json=body)


def import_list(srv: Server, mid: str, target: str, text: str) -> Any:
    return srv.http.post(
        f"/api/machines/{mid}/parameters/import",
        params={"scope": "axis", "target": target},
        content=text,
        headers={"content-type": "text/plain"},
    )


def lag_at_feed(srv: Server, mid: str, feed_mm_min: float) -> float:
    """Steady position lag of X in a G1 move (machine paused and stepped in simulated time)."""
    srv.pace(mid, mode="pause")
    x0 = srv.axis("X", mid)["pos_cmd"]
    r = srv.command(
        mid,
        {
            "type": "move",
            "axis": "X",
            "target": x0 + 50,
            "rapid": False,
            "feed_mm_min": feed_mm_min,
        },
    )
    assert r.status_code == 200, r.text
    srv.step(mid, 2000)
    lag = float(srv.axis("X", mid)["lag"])
    srv.step(mid, 6000)
    srv.pace(mid, mode="run")
    return lag


def test_registry_and_values_per_gear_record(srv: Server, mid: str) -> None:
    defs = {d["id"]: d for d in srv.http.get("/api/parameters").json()}
    assert defs["P-AXIS-00099"]["name"] == "getriebe[i].kv"
    assert defs["P-AXIS-00099"]["per_gear"]
    # a parameter the simulation takes without effect says why, in the registry and in the
    # machine's list; one that acts says nothing
    assert "floating-point" in defs["P-CHAN-00078"]["without_effect"]
    assert defs["P-AXIS-00099"]["without_effect"] == ""
    channel = values(srv, mid, None, "channel")
    assert channel["rund_aufloes"]["without_effect"] == defs["P-CHAN-00078"]["without_effect"]
    v = values(srv, mid, "S1")
    assert [v[f"getriebe[{g}].kv"]["gear"] for g in range(6)] == [1, 2, 3, 4, 5, 6]
    x = values(srv, mid)["getriebe[0].kv"]
    assert x["value"] == 2000 and x["set"] and x["unit"] == "0.01/s"
    assert x["effect"] == "now" and x["id"] == "P-AXIS-00099"
    # engineering value: kv 2000 × 0.01/s = 20 1/s; the manual's range 1 … 2^32-1
    assert (x["eng_factor"] * x["value"], x["eng_unit"]) == (pytest.approx(20.0), "1/s")
    assert (x["min"], x["max"]) == (1, 2**32 - 1)
    # one unit per quantity, as the machine view shows it: a velocity in µm/s reads in mm/min
    # (the F word's unit; 333333 µm/s = 20 m/min), a spindle's in rpm (3360000 0.001°/s =
    # 3360 °/s = 560 rpm), a weight in 0.1 % in % (r_trans_weight 1000 = 100 %)
    for target, name, shown in (
        ("X", "getriebe[0].vb_eilgang", (19999.98, "mm/min")),
        ("S1", "getriebe[0].vb_eilgang", (560.0, "rpm")),
        ("X", "getriebe[0].dynamik.r_trans_weight", (100.0, "%")),
    ):
        p = values(srv, mid, target)[name]
        assert (p["value"] * p["eng_factor"], p["eng_unit"]) == (pytest.approx(shown[0]), shown[1])
    # a bound that names another entry is resolved from the list: a_emergency ≤ 2·a_max
    a_max = values(srv, mid)["getriebe[0].dynamik.a_max"]["value"]
    assert values(srv, mid)["getriebe[0].dynamik.a_emergency"]["max"] == 2 * a_max
    # the sign parameters of 004 §3.5 are in the axis list before anyone wrote them
    x_list = values(srv, mid)
    for sign in ("lr_hw[0].vz_stellgr", "lr_hw[0].vz_istw"):
        assert (x_list[sign]["value"], x_list[sign]["set"], x_list[sign]["effect"]) == (
            0,
            False,
            "restart",
        )


def test_write_applies_now_and_the_loop_follows(srv: Server, mid: str) -> None:
    """kv 20/s -> 10/s: at 10 mm/s the steady lag doubles from 0.5 to 1.0 mm (lag = v/kv)."""
    assert lag_at_feed(srv, mid, 600) == pytest.approx(0.5, rel=1e-3)
    r = write(srv, mid, ("axis", "X", "getriebe[0].kv", 1000))
    assert r.status_code == 200, r.text
    change = r.json()["changes"][0]
    assert (change["old"], change["new"], change["pending"]) == (2000, 1000, False)
    assert lag_at_feed(srv, mid, 600) == pytest.approx(1.0, rel=1e-3)


def test_out_of_range_is_422_with_range_and_unit_and_nothing_changes(srv: Server, mid: str) -> None:
    before = values(srv, mid)
    r = write(
        srv, mid, ("axis", "X", "getriebe[0].lag_max", 60000), ("axis", "X", "getriebe[0].kv", 0)
    )
    assert r.status_code == 422
    detail = r.json()["detail"]
    (problem,) = detail["problems"]
    assert problem["parameter"] == "getriebe[0].kv" and problem["id"] == "P-AXIS-00099"
    assert (problem["min"], problem["unit"]) == (KV.lo, "0.01/s")
    assert "out of range" in problem["message"]
    after = values(srv, mid)
    assert after["getriebe[0].kv"]["value"] == before["getriebe[0].kv"]["value"]
    assert after["getriebe[0].lag_max"]["value"] == before["getriebe[0].lag_max"]["value"]
    r = write(srv, mid, ("axis", "X", "getriebe[0].nonsense", 1))
    assert r.status_code == 422 and "nonsense" in r.text
    r = write(srv, mid, ("axis", "Q", "getriebe[0].kv", 1000))
    assert r.status_code == 422 and "X, Z, S1" in r.text


def test_a_curve_that_cannot_accelerate_is_422_naming_it_and_nothing_changes(
    srv: Server, mid: str
) -> None:
    """Each coefficient is within the manual's REAL64 range; the curve they make is not."""
    pre = "getriebe[2].beschl_kennlinie."
    changes: list[tuple[str, str | None, str, Any]] = [("axis", "S1", pre + "typ", 2)]
    changes += [("axis", "S1", pre + b, 1e308) for b in ("b1", "b2", "b3")]
    r = write(srv, mid, *changes)
    assert r.status_code == 422, r.text
    (problem,) = r.json()["detail"]["problems"]
    assert problem["parameter"] == pre + "typ" and "at 0 rpm" in problem["message"]
    assert values(srv, mid, "S1")[pre + "typ"]["value"] == 0


def test_reset_effect_is_pending_until_reset(srv: Server, mid: str) -> None:
    r = write(srv, mid, ("axis", "X", "kenngr.swe_pos", 2500000))
    assert r.json()["changes"][0]["pending"]
    p = values(srv, mid)["kenngr.swe_pos"]
    assert (p["value"], p["pending"], p["effect"]) == (3000000, 2500000, "reset")
    srv.command(mid, {"type": "reset"})
    p = values(srv, mid)["kenngr.swe_pos"]
    assert (p["value"], p["pending"]) == (2500000, None)


def test_restart_effect_is_pending_until_restart(srv: Server, mid: str) -> None:
    write(srv, mid, ("axis", "X", "getriebe[0].wegaufz", 2))
    srv.command(mid, {"type": "reset"})
    assert values(srv, mid)["getriebe[0].wegaufz"]["pending"] == 2
    r = srv.http.post(f"/api/machines/{mid}/restart")
    assert r.status_code == 200 and r.json()["cycle"] < 1000
    p = values(srv, mid)["getriebe[0].wegaufz"]
    assert (p["value"], p["pending"]) == (2, None)


def test_a_restart_is_a_new_epoch_and_keeps_the_version_of_the_value_it_took_in(
    srv: Server, mid: str
) -> None:
    """The HMI reloads parameters when the build changes (the epoch), and tells its own
    trial value taken in by the restart (same version) from someone else's write (new one)."""
    epoch = srv.status(mid)["simulation"]["epoch"]
    r = write(srv, mid, ("axis", "X", "lr_hw[0].vz_stellgr", 1))
    (change,) = r.json()["changes"]
    assert (change["pending"], change["effect"]) == (True, "restart")
    assert values(srv, mid)["lr_hw[0].vz_stellgr"]["version"] == change["version"]
    assert srv.http.post(f"/api/machines/{mid}/restart").status_code == 200
    assert srv.status(mid)["simulation"]["epoch"] == epoch + 1
    p = values(srv, mid)["lr_hw[0].vz_stellgr"]
    assert (p["value"], p["pending"], p["version"]) == (1, None, change["version"])
    (again,) = write(srv, mid, ("axis", "X", "lr_hw[0].vz_stellgr", 0)).json()["changes"]
    assert again["version"] > change["version"]
    assert values(srv, mid)["lr_hw[0].vz_stellgr"]["version"] == again["version"]


def test_writing_back_the_value_in_force_cancels_the_pending_one(srv: Server, mid: str) -> None:
    """A revert before the restart: nothing waits for a restart any more."""
    write(srv, mid, ("axis", "X", "lr_hw[0].vz_stellgr", 1))
    assert values(srv, mid)["lr_hw[0].vz_stellgr"]["pending"] == 1
    (back,) = write(srv, mid, ("axis", "X", "lr_hw[0].vz_stellgr", 0)).json()["changes"]
    assert (back["old"], back["new"], back["pending"]) == (1, 0, False)
    p = values(srv, mid)["lr_hw[0].vz_stellgr"]
    assert (p["value"], p["pending"]) == (0, None)


def test_import_manual_excerpt_and_reject_bad_line(srv: Server, mid: str) -> None:
    text = (DATA / "axis_excerpt.lis").read_text()
    r = import_list(srv, mid, "S1", text)
    assert r.status_code == 200, r.text
    v = values(srv, mid, "S1")
    assert v["getriebe[0].beschl_kennlinie.typ"]["value"] == 2  # polynomial
    assert v["getriebe[0].beschl_kennlinie.b3"]["value"] == pytest.approx(-1.92901234e-10)
    lines = text.splitlines()
    lines.insert(4, "getriebe[0].dynamik.a_max   banana")
    r = import_list(srv, mid, "S1", "\n".join(lines))
    assert r.status_code == 422
    assert r.json()["detail"]["problems"][0]["line"] == 5


def test_export_round_trips(srv: Server, mid: str) -> None:
    assert write(srv, mid, ("axis", "X", "getriebe[0].kv", 1500)).status_code == 200
    r = srv.http.get(f"/api/machines/{mid}/parameters/export", params={"target": "X"})
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/plain")
    assert any(line.split()[:2] == ["getriebe[0].kv", "1500"] for line in r.text.splitlines())
    before = values(srv, mid)
    audit = srv.http.get(f"/api/machines/{mid}/parameters/audit").json()
    r2 = import_list(srv, mid, "X", r.text)
    assert r2.status_code == 200, r2.text
    after = values(srv, mid)
    assert {k: v["value"] for k, v in after.items()} == {k: v["value"] for k, v in before.items()}
    # the list as exported changes nothing, so nothing is reported or audited as a change
    assert r2.json()["changes"] == []
    assert srv.http.get(f"/api/machines/{mid}/parameters/audit").json() == audit
    edited = re.sub(r"^(getriebe\[0\]\.kv\s+)1500", r"\g<1>1600", r.text, flags=re.M)
    r3 = import_list(srv, mid, "X", edited)
    assert [(c["name"], c["old"], c["new"]) for c in r3.json()["changes"]] == [
        ("getriebe[0].kv", 1500, 1600)
    ]


def test_audit_trail_and_restart_of_the_service(srv: Server, mid: str) -> None:
    """Values written (now, at reset, by import) and their audit survive a service restart."""
    assert write(srv, mid, ("axis", "X", "getriebe[0].kv", 1000)).status_code == 200
    assert write(srv, mid, ("axis", "X", "kenngr.swe_pos", 2500000)).status_code == 200
    srv.command(mid, {"type": "reset"})
    assert import_list(srv, mid, "S1", (DATA / "axis_excerpt.lis").read_text()).is_success
    audit = srv.http.get(f"/api/machines/{mid}/parameters/audit").json()
    kv = [a for a in audit if a["name"] == "getriebe[0].kv" and a["target"] == "X"]
    assert (kv[0]["old"], kv[0]["new"], kv[0]["actor"]) == (2000, 1000, USER)  # who it was
    assert any(a["comment"] == "import axis list" for a in audit)
    srv.stop()
    srv.start()
    assert values(srv, mid)["getriebe[0].kv"]["value"] == 1000
    assert values(srv, mid)["kenngr.swe_pos"]["value"] == 2500000
    assert values(srv, mid, "S1")["getriebe[0].beschl_kennlinie.typ"]["value"] == 2
    assert srv.http.get(f"/api/machines/{mid}/parameters/audit").json() == audit
    srv.wait_powered(mid)
    assert lag_at_feed(srv, mid, 600) == pytest.approx(1.0, rel=1e-3)


def import_bytes(srv: Server, mid: str, body: bytes) -> Any:
    return srv.http.post(
        f"/api/machines/{mid}/parameters/import",
        params={"scope": "axis", "target": "X"},
        content=body,
        headers={"content-type": "text/plain"},
    )


@pytest.mark.parametrize(
    "value",
    [True, "２０００", "2_000", "M3", 10**400, "9" * 400, "0x" + "F" * 300],
    ids=["true", "full-width", "grouped", "text", "int-400-digits", "400-digits", "hex-300"],
)
def test_loose_and_huge_values_are_422_and_change_nothing(
    srv: Server, mid: str, value: Any
) -> None:
    before = values(srv, mid)["getriebe[0].kv"]["value"]
    r = write(srv, mid, ("axis", "X", "getriebe[0].kv", value))
    assert r.status_code == 422, r.text
    assert len(r.content) < 4000  # the echo of a 400-digit value is cut
    assert values(srv, mid)["getriebe[0].kv"]["value"] == before


@pytest.mark.parametrize("value", [10**400, -5])
def test_values_beyond_the_type_name_the_parameters_range(
    srv: Server, mid: str, value: int
) -> None:
    """Beyond UNS32 or not, kv's range is 1 … 4294967295 0.01/s [004 P-AXIS-00099], as the
    editor shows it: a list import names that, not the data type's 0 … 4294967295."""
    r = write(srv, mid, ("axis", "X", "getriebe[0].kv", value))
    (problem,) = r.json()["detail"]["problems"]
    assert "out of range 1 … 4294967295 0.01/s" in problem["message"]
    assert (problem["min"], problem["max"]) == (1, 4294967295)
    r = import_list(srv, mid, "X", f"getriebe[0].kv {value}\n")
    (problem,) = r.json()["detail"]["problems"]
    assert "out of range 1 … 4294967295 0.01/s" in problem["message"]


def test_a_name_twice_in_one_write_or_list_is_refused(srv: Server, mid: str) -> None:
    before = values(srv, mid)["getriebe[0].kv"]["value"]
    kv = ("axis", "X", "getriebe[0].kv")
    r = write(srv, mid, (*kv, 1500), (*kv, 1600))
    assert r.status_code == 422 and "twice" in r.json()["detail"]["problems"][0]["message"]
    r = import_bytes(srv, mid, b"getriebe[0].kv 1500\ngetriebe[0].kv 1600\n")
    assert r.status_code == 422
    (problem,) = r.json()["detail"]["problems"]
    assert problem["line"] == 2 and "already set in line 1" in problem["message"]
    assert values(srv, mid)["getriebe[0].kv"]["value"] == before


@pytest.mark.parametrize(
    ("body", "why"),
    [
        (b"getriebe[0].kv 2000\n# K\xfchlung\n", "not UTF-8 text (byte 23 is 0xfc)"),
        ("getriebe[0].kv ２０００\n".encode(), "is not a number"),
        (b"getriebe[0].kv 2_000\n", "is not a number"),
        (b"getriebe[0].kv " + b"9" * 400 + b"\n", "out of range"),
        (b"getriebe[0].kv 0x" + b"F" * 300 + b"\n", "out of range"),
    ],
    ids=["latin-1", "full-width", "grouped", "400-digits", "hex-300"],
)
def test_bad_list_files_are_422_naming_the_problem(
    srv: Server, mid: str, body: bytes, why: str
) -> None:
    r = import_bytes(srv, mid, body)
    assert r.status_code == 422, r.text
    assert why in r.text


def test_a_refused_1_mb_value_is_not_echoed_and_a_50_mb_body_not_read(
    srv: Server, mid: str
) -> None:
    # a name far over its 120 characters: pydantic reports the input with the problem
    body = {"changes": [{"scope": "axis", "target": "X", "name": "n" * 1_000_000, "value": 1}]}
    r = srv.http.patch(f"/api/machines/{mid}/parameters", json=body, timeout=120)
    assert r.status_code == 422
    assert len(r.content) < 2000
    (issue,) = r.json()["detail"]
    assert issue["loc"] == ["body", "changes", 0, "name"] and issue["input"].endswith("…")
    # 50 MB is far over what 5000 changes take: refused by its size, before it is parsed
    body["changes"][0]["name"] = "n" * 50_000_000
    r = srv.http.patch(f"/api/machines/{mid}/parameters", json=body, timeout=120)
    assert r.status_code == 413
    assert r.json()["detail"]["message"] == (
        f"request body larger than this route's limit of {2 * 1024 * 1024} bytes"
    )
