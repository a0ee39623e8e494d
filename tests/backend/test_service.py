"""The service over real HTTP: machines, commands, status, pacing, refusals.

One uvicorn process for the module (demo lathe, its own SQLite file). Motion is judged in
simulated time: the machine is paused and stepped by whole cycles, so positions and lags are
exact functions of the cycle count, whatever the wall clock does.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import pytest

from nc_sim.config import demo_lists
from tests.backend.server import Server

KV_X = 20.0  # 1/s, demo X: getriebe[0].kv 2000 [0.01/s], no feedforward


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("svc") / "svc.sqlite").start()
    yield s
    s.close()


def wait_for(pred: Callable[[], object], timeout_s: float = 10.0) -> None:
    """Poll a condition of the running machine (real-time pacing, no speed judged)."""
    deadline = time.monotonic() + timeout_s
    while not pred():
        if time.monotonic() > deadline:
            raise AssertionError("condition not reached")
        time.sleep(0.02)


def test_demo_machine_runs_in_real_time(srv: Server) -> None:
    machines = srv.http.get("/api/machines").json()
    assert [m["id"] for m in machines] == ["demo"]
    assert machines[0]["axes"] == ["X", "Z", "S1"]
    st = srv.status("demo")
    assert st["simulation"]["mode"] == "run"
    assert st["plc"]["drives_powered"]
    assert all(a["enabled"] for a in st["axes"])
    c0 = st["simulation"]["cycle"]
    wait_for(lambda: srv.status("demo")["simulation"]["cycle"] > c0 + 200)


def test_mdi_spindle_reaches_programmed_speed(srv: Server, mid: str) -> None:
    r = srv.command(mid, {"type": "mdi", "block": "M3 S1000"})
    assert r.status_code == 200, r.text
    assert r.json()["block_id"] >= 1
    wait_for(lambda: srv.axis("S1", mid)["speed_reached"])
    s1 = srv.axis("S1", mid)
    assert s1["state"] == "ENDLESS"
    assert abs(s1["vel_act"] - 1000.0) <= 100.0  # reached: inside the ±10 % band (vb_prozent)
    wait_for(lambda: srv.axis("S1", mid)["vel_cmd"] == pytest.approx(1000.0))
    srv.command(mid, {"type": "spindle", "m": 5})
    wait_for(lambda: srv.axis("S1", mid)["state"] == "STANDSTILL")


def test_bad_block_is_refused_with_its_column(srv: Server, mid: str) -> None:
    block = "G01 X10 F500 &"
    r = srv.command(mid, {"type": "mdi", "block": block})
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert detail["column"] == block.index("&") + 1
    assert detail["code"] == 90010


def test_a_block_that_fails_while_starting_is_409_with_its_job_error(srv: Server, mid: str) -> None:
    """S20000 fits no gear stage (M45 up to 7000 rpm, P-CHAN-00055): the block parses but is
    refused as it starts, 90017 naming the limit; the spindle stays at rest."""
    r = srv.command(mid, {"type": "mdi", "block": "M3 S20000"})
    assert r.status_code == 409, r.text
    detail = r.json()["detail"]
    assert detail["code"] == 90017 and detail["error"]["axis"] == "S1"
    assert "7000 rpm" in detail["message"] and "P-CHAN-00055" in detail["message"]
    assert srv.axis("S1", mid)["state"] == "STANDSTILL"


def test_a_command_naming_no_axis_is_422_naming_it(srv: Server, mid: str) -> None:
    r = srv.command(mid, {"type": "home", "axis": "Q"})
    assert r.status_code == 422, r.text
    assert r.json()["detail"]["message"] == "no axis or spindle 'Q'"


def test_out_of_range_command_fields_are_422(srv: Server, mid: str) -> None:
    r = srv.command(mid, {"type": "gear", "m": 47})
    assert r.status_code == 422
    assert "m" in r.text
    r = srv.command(mid, {"type": "nonsense"})
    assert r.status_code == 422


@pytest.mark.parametrize(
    ("command", "text"),
    [
        # the bounds and units of api/commands.py: F of a move ≤ 1e6 mm/min, a jog feed > 0
        (
            {"type": "move", "axis": "X", "target": 1.0, "rapid": False, "feed_mm_min": 2e6},
            "Feed must be at most 1e+06 mm/min.",
        ),
        (
            {"type": "jog", "axis": "X", "action": "step", "distance": 1, "feed_mm_min": -5},
            "Jog feed must be greater than 0 mm/min.",
        ),
        (
            {"type": "override", "axis": "X", "percent": 250},
            "Override percent must be at most 200 %.",
        ),
        ({"type": "gear", "m": 47}, "M function must be at most 45."),
        ({"type": "jog", "action": "start"}, "Axis or spindle name is required."),
    ],
)
def test_schema_violations_read_as_sentences_with_meaning_and_unit(
    srv: Server, mid: str, command: dict[str, object], text: str
) -> None:
    r = srv.command(mid, command)
    assert r.status_code == 422
    (issue,) = r.json()["detail"]
    assert issue["text"] == text
    assert "Input should" not in issue["text"]


@pytest.mark.parametrize(
    ("path", "body", "text"),
    [
        # a unit the name spells in parts (°/s, not the "s" of its last part)
        (
            "assist/curve-run-up",
            {"axis": "S1", "n_limit_deg_s": 2e7},
            "Limit speed must be at most 1e+07 °/s.",
        ),
        # the unit of each value of a list, named by the schema (x-unit)
        (
            "assist/loop-gain",
            {"axis": "X", "kvs": [0]},
            "Kv values to try must be greater than 0 1/s.",
        ),
        # the schema's unit before the name's last part (digits per rpm, not rpm)
        (
            "assist/multi-gain-calc",
            {"axis": "X", "digits_per_rpm": 0},
            "Digits per motor rpm must be greater than 0 digits/rpm.",
        ),
        # within a list of points: °/s (the description's parse gave "s")
        (
            "assist/curve-fit",
            {
                "axis": "S1",
                "points": [{"n_deg_s": 2e7, "a_deg_s2": 1}] + [{"n_deg_s": 1, "a_deg_s2": 1}] * 2,
            },
            "Speed n must be at most 1e+07 °/s.",
        ),
    ],
)
def test_refusals_name_the_unit_the_schema_gives(
    srv: Server, mid: str, path: str, body: dict[str, object], text: str
) -> None:
    r = srv.http.post(f"/api/machines/{mid}/{path}", json=body)
    assert r.status_code == 422, r.text
    (issue,) = r.json()["detail"]
    assert issue["text"] == text


def test_lag_of_a_feed_move_is_v_over_kv(srv: Server, mid: str) -> None:
    """G1 at F600 (10 mm/s) without feedforward: steady lag = v/kv = 0.5 mm."""
    srv.pace(mid, mode="pause")
    x0 = srv.axis("X", mid)["pos_cmd"]
    r = srv.command(
        mid,
        {"type": "move", "axis": "X", "target": x0 + 100, "rapid": False, "feed_mm_min": 600},
    )
    assert r.status_code == 200, r.text
    srv.step(mid, 2000)  # 2 s: the 0.3 s ramp is long over, 80 mm still to go
    x = srv.axis("X", mid)
    assert x["state"] == "MOVING"
    assert x["vel_cmd"] == pytest.approx(600.0)
    assert x["lag"] == pytest.approx(10.0 / KV_X, rel=1e-3)
    srv.step(mid, 12000)
    x = srv.axis("X", mid)
    assert x["state"] == "STANDSTILL"
    assert x["pos_act"] == pytest.approx(x0 + 100, abs=1e-3)
    srv.pace(mid, mode="run")


def test_status_has_the_hli_target_distance_to_go_and_drive_status(srv: Server, mid: str) -> None:
    """[000 §2.9] target position and distance to go; [004 §4.2] the drive status that SERCOS
    drives report (X) and terminal drives do not (S1)."""
    srv.pace(mid, mode="pause")
    x0 = srv.axis("X", mid)["pos_cmd"]
    move = {"type": "move", "axis": "X", "target": x0 + 100, "rapid": False, "feed_mm_min": 600}
    assert srv.command(mid, move).status_code == 200
    srv.step(mid, 2000)
    x = srv.axis("X", mid)
    assert x["target_pos"] == pytest.approx(x0 + 100)
    assert x["distance_to_go"] == pytest.approx(x0 + 100 - x["pos_cmd"])
    assert 70.0 < x["distance_to_go"] < 90.0  # 10 mm/s for about 2 s
    assert x["ready_for_power_on"] is True and x["ready_for_control_loop_on"] is True
    s1 = srv.axis("S1", mid)
    assert s1["ready_for_power_on"] is None and s1["ready_for_control_loop_on"] is None
    srv.step(mid, 12000)
    x = srv.axis("X", mid)
    assert x["state"] == "STANDSTILL" and x["distance_to_go"] == 0.0
    srv.pace(mid, mode="run")


def test_jog_step_and_continuous_jog(srv: Server, mid: str) -> None:
    srv.pace(mid, mode="pause")
    z0 = srv.axis("Z", mid)["pos_cmd"]
    r = srv.command(mid, {"type": "jog", "axis": "Z", "action": "step", "distance": 2.5})
    assert r.status_code == 200, r.text
    srv.step(mid, 3000)
    assert srv.axis("Z", mid)["pos_cmd"] == pytest.approx(z0 + 2.5, abs=1e-9)
    r = srv.command(mid, {"type": "jog", "axis": "Z", "action": "start", "direction": -1})
    assert r.json()["state"]["Z"] == "JOG"
    srv.step(mid, 500)
    assert srv.axis("Z", mid)["vel_cmd"] < 0
    srv.command(mid, {"type": "jog", "axis": "Z", "action": "stop"})
    srv.step(mid, 3000)
    assert srv.axis("Z", mid)["state"] == "STANDSTILL"
    srv.pace(mid, mode="run")


def test_a_jog_feed_above_the_axis_limit_is_refused_by_the_nc_naming_it(
    srv: Server, mid: str
) -> None:
    """Not the schema's bound: the axis' G200 maximum (P-AXIS-00213, 166666 µm/s in the demo
    list = 9999.96 mm/min) decides, and the refusal says so in mm/min."""
    for action in ("start", "step"):
        jog = {"type": "jog", "axis": "X", "action": action, "distance": 1.0}
        r = srv.command(mid, {**jog, "feed_mm_min": 99999999})
        assert r.status_code == 409, r.text
        detail = r.json()["detail"]
        assert detail["code"] == 90025
        assert "maximum 9999.96 mm/min (handbetrieb.hb.vb_max, P-AXIS-00213)" in detail["message"]
        assert "Input should" not in r.text
    assert srv.axis("X", mid)["state"] == "STANDSTILL"


def test_held_jog_stops_when_its_dead_man_lease_runs_out(srv: Server, mid: str) -> None:
    """A UI renews `hold_s` while the key is held; when renewals stop (released key, lost
    connection) the jog brakes in the cycle the lease ends, in simulated time."""
    srv.pace(mid, mode="pause")
    hold = {"type": "jog", "axis": "Z", "action": "start", "direction": 1, "hold_s": 0.2}
    assert srv.command(mid, hold).status_code == 200
    srv.step(mid, 150)
    assert srv.command(mid, hold).status_code == 200  # renewed at 150 ms: runs to 350 ms
    srv.step(mid, 199)
    assert srv.axis("Z", mid)["state"] == "JOG"
    srv.step(mid, 1)
    assert srv.axis("Z", mid)["state"] != "JOG"  # braking with the manual-mode deceleration
    srv.step(mid, 3000)
    assert srv.axis("Z", mid)["state"] == "STANDSTILL"
    srv.pace(mid, mode="run")


def test_motion_without_enables_is_a_job_error(srv: Server, mid: str) -> None:
    assert srv.command(mid, {"type": "hli", "unit": "DriveOn", "axis": "X", "value": 0}).is_success
    r = srv.command(mid, {"type": "jog", "axis": "X", "action": "start"})
    assert r.status_code == 409
    detail = r.json()["detail"]
    assert detail["code"] == 90001  # drive enables missing
    assert detail["error"]["axis"] == "X"
    x = srv.axis("X", mid)
    assert not x["enabled"] and x["missing_enables"] == ["DriveOn"]
    srv.command(mid, {"type": "hli", "unit": "DriveOn", "axis": "X", "value": 1})
    srv.command(mid, {"type": "reset"})
    assert srv.axis("X", mid)["job_error"] == 0


def test_override_and_gear_change(srv: Server, mid: str) -> None:
    r = srv.command(mid, {"type": "override", "axis": "S1", "percent": 50})
    assert r.is_success
    assert srv.axis("S1", mid)["control_units"]["override"] == 500  # HLI counts in ‰
    srv.command(mid, {"type": "override", "axis": "S1", "percent": 100})
    r = srv.command(mid, {"type": "gear", "m": 44})
    assert r.is_success, r.text
    # M40..M45 select gear records 1..6 (getriebe[0..5]); M44 is the fifth
    wait_for(
        lambda: srv.axis("S1", mid)["gear"] == 5 and srv.axis("S1", mid)["state"] == "STANDSTILL"
    )
    events = srv.status(mid)["recent_events"]
    assert any(e["axis"] == "S1" and e["m"] == 44 for e in events)


def test_plc_manual_acknowledgement(srv: Server, mid: str) -> None:
    srv.command(mid, {"type": "plc_mode", "mode": "manual"})
    srv.command(mid, {"type": "mdi", "block": "M8"})
    wait_for(lambda: [p["m"] for p in srv.status(mid)["plc"]["pending"]] == [8])
    r = srv.command(mid, {"type": "plc_ack", "m": 8})
    assert r.json()["acknowledged"] == 1
    assert srv.status(mid)["plc"]["pending"] == []
    srv.command(mid, {"type": "plc_mode", "mode": "auto"})


def test_plc_acknowledge_after_the_timeout_acknowledges_nothing(srv: Server, mid: str) -> None:
    """Timed out means gone: no longer pending in the status, a late ack answers 0."""
    srv.pace(mid, mode="pause")
    srv.command(mid, {"type": "plc_mode", "mode": "manual"})
    srv.command(mid, {"type": "mdi", "block": "M8"})
    srv.step(mid, 100)
    assert [p["m"] for p in srv.status(mid)["plc"]["pending"]] == [8]
    srv.step(mid, 5000)  # demo plc.m_ack_timeout: 5 s
    st = srv.status(mid)
    assert st["plc"]["pending"] == []
    assert 90004 in {e["code"] for e in st["recent_events"]}
    r = srv.command(mid, {"type": "plc_ack", "m": 8})
    assert r.is_success and r.json()["acknowledged"] == 0


def test_emergency_stop_and_reset(srv: Server, mid: str) -> None:
    srv.emergency_stop(mid)
    st = srv.status(mid)
    assert st["emergency_stop"]
    assert {a["state"] for a in st["axes"]} == {"ERROR"}
    assert {e["code"] for e in st["job_errors"]} == {90005}
    # at rest, the PLC takes every drive's enables at once: nothing is powered, no loop closed
    assert not st["plc"]["drives_powered"]
    assert {a["loop"] for a in st["axes"]} == {"open"}
    srv.command(mid, {"type": "reset"})
    st = srv.status(mid)
    assert not st["emergency_stop"] and st["job_errors"] == []
    srv.wait_powered(mid)  # the PLC's start-up again
    assert {a["loop"] for a in srv.status(mid)["axes"]} == {"closed"}


def test_fast_mode_stops_exactly_at_the_cycle(srv: Server, mid: str) -> None:
    c0 = srv.pace(mid, mode="pause")["cycle"]
    srv.pace(mid, mode="fast", until_cycle=c0 + 30000)
    wait_for(lambda: srv.status(mid)["simulation"]["mode"] == "pause")
    assert srv.status(mid)["simulation"]["cycle"] == c0 + 30000
    srv.pace(mid, mode="run")


def test_emergency_stop_ends_a_long_step_instead_of_waiting_for_it(srv: Server, mid: str) -> None:
    """A step of a million cycles runs in one request thread; status and an emergency stop
    from another thread get in while it runs: the stop acts at a cycle inside the step's span
    and the step ends there."""
    srv.pace(mid, mode="pause")
    srv.command(mid, {"type": "mdi", "block": "M3 S1000"})  # something to simulate
    c0 = srv.status(mid)["simulation"]["cycle"]
    n = 1_000_000
    with ThreadPoolExecutor(1) as pool:
        stepping = pool.submit(
            srv.http.post, f"/api/machines/{mid}/simulation/step", json={"cycles": n}
        )
        # status answers between the step's slices (before: only after the whole step)
        wait_for(lambda: srv.status(mid)["simulation"]["cycle"] > c0)
        stop = srv.emergency_stop(mid)
        assert stop.status_code == 200, stop.text
        stepped = stepping.result(timeout=120)
    assert stepped.status_code == 200, stepped.text
    stop_cycle, end_cycle = stop.json()["cycle"], stepped.json()["cycle"]
    assert c0 < stop_cycle < c0 + n  # the stop acted inside the step's span ...
    assert end_cycle < c0 + n  # ... and ended the step
    st = srv.status(mid)
    assert st["emergency_stop"] and st["simulation"]["mode"] == "pause"
    assert st["simulation"]["cycle"] == end_cycle


def test_a_step_longer_than_one_request_may_take_is_422(srv: Server, mid: str) -> None:
    r = srv.http.post(f"/api/machines/{mid}/simulation/step", json={"cycles": 1_000_001})
    assert r.status_code == 422
    assert "cycles" in r.text and "1000000" in r.text
    assert srv.status(mid)["simulation"]["mode"] == "run"  # nothing happened


def test_create_from_lists_and_delete(srv: Server) -> None:
    channel, axes = demo_lists()
    body = {"id": "lathe2", "name": "Second lathe", "channel_list": channel, "axis_lists": axes}
    r = srv.http.post("/api/machines", json=body)
    assert r.status_code == 201, r.text
    assert r.json()["axes"] == ["X", "Z", "S1"]
    assert srv.status("lathe2")["simulation"]["mode"] == "run"
    assert srv.http.post("/api/machines", json=body).status_code == 409
    bad = {**body, "id": "lathe3", "axis_lists": {**axes, 1: axes[1] + "getriebe[0].kv -5\n"}}
    r = srv.http.post("/api/machines", json=bad)
    assert r.status_code == 422
    line = axes[1].count("\n") + 1
    assert r.json()["detail"]["problems"][0]["line"] == line
    assert srv.http.delete("/api/machines/lathe2").status_code == 204
    assert srv.http.get("/api/machines/lathe2/status").status_code == 404


def test_service_status(srv: Server, mid: str) -> None:
    def service() -> dict[str, Any]:
        data: dict[str, Any] = srv.http.get("/api/service/status").json()
        return data

    wait_for(lambda: all(w["loop"] is not None for w in service()["workers"]))
    st = service()
    assert st["transport"] == "local" and len(st["workers"]) >= 1
    assert all(w["alive"] and w["loop"]["ticks"] > 0 for w in st["workers"])
    (home,) = [w for w in st["workers"] if mid in w["machines"]]  # on exactly one worker
    assert st["machines"][mid]["worker"] == home["id"]

    def period_s() -> float:
        (w,) = [w for w in service()["workers"] if w["id"] == home["id"]]
        return float(w["loop"]["period_s"])

    # at rest its worker ticks every 10 ms; a turning spindle brings back the configured 2 ms
    wait_for(lambda: period_s() == pytest.approx(0.01))
    assert srv.command(mid, {"type": "mdi", "block": "M3 S1000"}).status_code == 200
    wait_for(lambda: period_s() == pytest.approx(0.002))
    srv.command(mid, {"type": "spindle", "m": 5})
    wait_for(lambda: period_s() == pytest.approx(0.01))

    def rt_factor() -> float:
        return float(srv.http.get("/api/service/status").json()["machines"][mid]["rt_factor"])

    # running: simulated time advances; paused: once the factor's window holds only the
    # pause, no simulated time passes at all (no speed judged either way)
    wait_for(lambda: rt_factor() > 0)
    srv.pace(mid, mode="pause")
    wait_for(lambda: rt_factor() == 0.0)


def test_openapi_lists_the_contract(srv: Server) -> None:
    spec = srv.http.get("/openapi.json").json()
    assert "/api/machines/{mid}/commands" in spec["paths"]
    assert "MachineStatus" in spec["components"]["schemas"]
    # the websocket messages are part of the contract the browser's types come from
    assert {"Hello", "Subscribe", "FrameHeader", "EventMessage"} <= set(
        spec["components"]["schemas"]
    )
    assert srv.http.get("/docs").status_code == 200


def test_every_command_gets_the_machine_s_next_serial(srv: Server, mid: str) -> None:
    """Accepted, refused and invalid commands are numbered in the order they reached the
    machine, so a client can match an answer to its command."""
    first = srv.command(mid, {"type": "mdi", "block": "M3 S500"})
    invalid = srv.command(mid, {"type": "mdi", "block": "G1 X"})
    srv.emergency_stop(mid)
    refused = srv.command(mid, {"type": "mdi", "block": "M3 S500"})  # in E-stop: 90015
    assert (first.status_code, invalid.status_code, refused.status_code) == (200, 422, 409)
    n = first.json()["serial"]
    assert invalid.json()["detail"]["serial"] == n + 1
    assert refused.json()["detail"]["serial"] == n + 3
