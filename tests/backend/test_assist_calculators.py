"""The calculators, the curve run-up and the gear-range preview over real HTTP, against the
manuals' worked examples: resolution [004 §3.4], multi_gain by calculation [004 §3.6.1],
speed scaling [000 §2.2.4], the acceleration curve [000 §2.8.4, DOMAIN §4.1] and automatic
gear selection [000 §2.8.2, DOMAIN §4.2]. The expected numbers are the manuals' (or worked
out here by hand from their formulas), the values "before" the parameter list's own.
"""

from __future__ import annotations

import subprocess
import sys
import time
from fractions import Fraction
from typing import Any

import pytest

from tests.backend.server import Server

MANUAL_POINTS = [(12000, 16000), (24000, 8000), (36000, 4000), (48000, 2000)]  # 000 §2.8.4
# the manual's speed table (000 §2.8.2), which the demo lathe's S1 carries
TABLE = [(50, 560), (400, 800), (700, 3500), (3501, 4000), (3800, 5500), (5400, 7000)]


def post(srv: Server, mid: str, name: str, body: dict[str, Any]) -> Any:
    return srv.http.post(f"/api/machines/{mid}/assist/{name}", json=body, timeout=120)


def ok(srv: Server, mid: str, name: str, body: dict[str, Any]) -> dict[str, Any]:
    r = post(srv, mid, name, body)
    assert r.status_code == 200, r.text
    out: dict[str, Any] = r.json()
    return out


def after(res: dict[str, Any]) -> dict[str, Any]:
    return {c["parameter"].split(".", 1)[-1]: c["after"] for c in res["changes"]}


def figures(res: dict[str, Any]) -> dict[str, float]:
    return {f["name"]: f["value"] for f in res["figures"]}


def listed(srv: Server, mid: str, scope: str, target: str | None = None) -> dict[str, Any]:
    params = {"scope": scope} | ({"target": target} if target else {})
    r = srv.http.get(f"/api/machines/{mid}/parameters", params=params)
    assert r.status_code == 200, r.text
    return {p["name"]: p["value"] for p in r.json()}


@pytest.mark.parametrize(
    ("body", "pair"),
    [
        ({"pitch_mm": 5}, (4096, 50000)),  # 4096 increments per 5 mm spindle pitch
        ({"pitch_mm": 5, "gear_ratio": 10}, (4096, 5000)),  # with the gear i = 10
    ],
)
def test_resolution_of_the_manuals_linear_axis(
    srv: Server, lathe: str, body: dict[str, Any], pair: tuple[int, int]
) -> None:
    res = ok(srv, lathe, "resolution", {"axis": "X", "increments_per_rev": 4096, **body})
    assert (after(res)["wegaufz"], after(res)["wegaufn"]) == pair
    now = listed(srv, lathe, "axis", "X")  # before: the list's values, to Apply against
    assert {c["parameter"]: c["before"] for c in res["changes"]} == {
        "getriebe[0].wegaufz": now["getriebe[0].wegaufz"],
        "getriebe[0].wegaufn": now["getriebe[0].wegaufn"],
    }


def test_resolution_of_a_rotary_encoder_in_gear_3(srv: Server, lathe: str) -> None:
    res = ok(
        srv,
        lathe,
        "resolution",
        {"axis": "S1", "gear": 3, "increments_per_rev": 65536, "rotary": True},
    )  # 65536 increments per 360° in 0.0001°
    assert {c["parameter"]: c["after"] for c in res["changes"]} == {
        "getriebe[2].wegaufz": 65536,
        "getriebe[2].wegaufn": 3600000,
    }


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        # terminal spindle: 32767 digits at 10 V = 9000 rpm, 1000 °/min = 2.7778 rpm
        ({"full_scale_digits": 32767, "full_scale_rpm": 9000}, 10.1134),
        ({"full_scale_digits": 32767, "full_scale_rpm": 9000, "gear_ratio": 5}, 50.5668),
        # Lightbus: 1048576·32/(4000·60) digits per rpm, 1 m/min at 5 mm = 200 rpm
        ({"digits_per_rpm": 1048576 * 32 / (4000 * 60), "pitch_mm": 5}, 27962.02),
    ],
)
def test_multi_gain_by_calculation_gives_the_manuals_values(
    srv: Server, lathe: str, body: dict[str, Any], expected: float
) -> None:
    res = ok(srv, lathe, "multi-gain-calc", {"axis": "S1", **body})
    z, n = after(res)["multi_gain_z"], after(res)["multi_gain_n"]
    assert z / n == pytest.approx(expected, abs=6e-5 * expected)
    assert figures(res)["multi_gain"] == pytest.approx(z / n)


def test_multi_gain_of_a_sercos_rotary_drive(srv: Server, lathe: str) -> None:
    res = ok(srv, lathe, "multi-gain-calc", {"axis": "S1", "speed_weighting_rpm": 1e-4})
    assert (after(res)["multi_gain_z"], after(res)["multi_gain_n"]) == (10000000, 360)


def test_speed_scaling_of_the_manuals_spindle(srv: Server, lathe: str) -> None:
    res = ok(srv, lathe, "speed-scaling", {"axis": "S1", "increments": 32767, "speed_rpm": 3000})
    # 3000 rpm · 360000 (0.001°) per revolution per minute
    assert (after(res)["v_reso_num"], after(res)["v_reso_denom"]) == (32767, 1080000000)
    assert after(res)["v_time_base"] == 0
    one = ok(srv, lathe, "speed-scaling", {"axis": "S1", "increments": 1, "speed_rpm": 1})
    assert (after(one)["v_reso_num"], after(one)["v_reso_denom"]) == (1, 360000)


def test_speed_scaling_per_cycle_takes_the_machines_cycle_time(srv: Server, lathe: str) -> None:
    cycle_ms = listed(srv, lathe, "channel")["cycle_time"] / 1000  # listed in µs
    res = ok(
        srv,
        lathe,
        "speed-scaling",
        {"axis": "S1", "increments": 32767, "speed_rpm": 3000, "time_base": 2},
    )
    # 3000 rpm = 50 rev/s: 50 · 360000 · cycle (s) in 0.001°
    per_cycle = Fraction(50 * 360000) * Fraction(str(cycle_ms)) / 1000
    z, n = after(res)["v_reso_num"], after(res)["v_reso_denom"]
    assert Fraction(z, n) == Fraction(32767) / per_cycle


def test_curve_fit_reproduces_the_manuals_polynomial(srv: Server, lathe: str) -> None:
    points = [{"n_deg_s": n, "a_deg_s2": a} for n, a in MANUAL_POINTS]
    res = ok(srv, lathe, "curve-fit", {"axis": "S1", "gear": 2, "typ": 2, "points": points})
    f = figures(res)
    assert f["b3"] == pytest.approx(-1.92901234e-10, rel=1e-7)
    assert f["b2"] == pytest.approx(2.08333333e-5, rel=1e-7)
    assert f["b1"] == pytest.approx(-0.88888888, rel=1e-7)
    changes = {c["parameter"]: c for c in res["changes"]}
    assert changes["getriebe[1].beschl_kennlinie.n_grenz"]["after"] == 12000000  # 0.001 °/s
    assert changes["getriebe[1].beschl_kennlinie.a_konst"]["after"] == 16000
    now = listed(srv, lathe, "axis", "S1")
    assert (
        changes["getriebe[1].beschl_kennlinie.typ"]["before"]
        == now["getriebe[1].beschl_kennlinie.typ"]
    )
    assert {s["name"] for s in res["series"]} == {"points", "fit"}


def test_curve_fit_reproduces_the_manuals_hyperbola(srv: Server, lathe: str) -> None:
    points = [{"n_deg_s": n, "a_deg_s2": a} for n, a in MANUAL_POINTS[:3]]
    f = figures(ok(srv, lathe, "curve-fit", {"axis": "S1", "typ": 1, "points": points}))
    assert (f["b1"], f["b2"], f["b3"]) == pytest.approx((2.285714e4, 4.166666e-1, 2.857142e-2))


def test_curve_fit_of_an_asynchronous_drive(srv: Server, lathe: str) -> None:
    # a_max 10000 °/s² up to N1 6000 °/s, a_max·N1/n to N2 20000, a_max·N1·N2/n² above
    pts = [(3000, 10000), (12000, 5000), (30000, 10000 * 6000 * 20000 / 30000**2), (40000, 750)]
    points = [{"n_deg_s": n, "a_deg_s2": a} for n, a in pts]
    f = figures(ok(srv, lathe, "curve-fit", {"axis": "S1", "typ": 3, "points": points}))
    assert (f["a_max"], f["n1"], f["n2"]) == pytest.approx((10000, 6000, 20000))


@pytest.mark.parametrize(
    ("name", "body", "says"),
    [
        (
            "resolution",
            {"axis": "X", "increments_per_rev": -4096, "pitch_mm": 5},
            "increments_per_rev",
        ),
        ("resolution", {"axis": "X", "increments_per_rev": 4096}, "pitch"),
        ("resolution", {"axis": "Q", "increments_per_rev": 4096, "pitch_mm": 5}, "Q"),
        ("resolution", {"axis": "X", "increments_per_rev": 4096, "pitch_mm": 5, "gear": 7}, "gear"),
        ("multi-gain-calc", {"axis": "X", "full_scale_digits": 32767}, "full scale"),
        ("multi-gain-calc", {"axis": "X", "pitch_mm": 5}, "exactly one"),
        ("speed-scaling", {"axis": "S1", "increments": 1, "speed_rpm": 0}, "speed_rpm"),
        ("speed-scaling", {"axis": "X", "increments": 1, "speed_rpm": 1}, "not a spindle"),
        ("curve-fit", {"axis": "S1", "typ": 2, "points": []}, "points"),
        (
            "curve-fit",
            {"axis": "S1", "typ": 4, "points": [{"n_deg_s": 1, "a_deg_s2": 1}] * 4},
            "typ",
        ),
        (
            "curve-fit",
            {"axis": "S1", "typ": 2, "points": [{"n_deg_s": n, "a_deg_s2": 5} for n in (1, 2, 3)]},
            "at least 4",
        ),
        (
            "curve-fit",
            {"axis": "X", "typ": 3, "points": [{"n_deg_s": n, "a_deg_s2": 5} for n in (1, 2, 3)]},
            "not a spindle",
        ),
        ("gear-ranges", {"ranges": [{"min_rpm": 900, "max_rpm": 800}] * 6}, "min_rpm"),
        ("gear-ranges", {"ranges": [{"min_rpm": 0, "max_rpm": 70000}] * 6}, "max_rpm"),
        ("gear-ranges", {"speeds_rpm": [1e9]}, "speeds_rpm"),
        ("curve-run-up", {"axis": "X", "gear": 1}, "not a spindle"),
    ],
)
def test_bad_inputs_are_422_naming_the_field(
    srv: Server, lathe: str, name: str, body: dict[str, Any], says: str
) -> None:
    r = post(srv, lathe, name, body)
    assert r.status_code == 422, r.text
    assert says in r.text


def gears(res: dict[str, Any]) -> list[tuple[int | None, bool]]:
    return [(s["m"], s["change"]) for s in res["steps"]]


def test_gear_selection_follows_the_manuals_rule(srv: Server, lathe: str) -> None:
    """000 §2.8.2 automatic, bottom-up, from M40: S650 -> M41, S750 stays (M41 holds it),
    S950 -> M42, S1050 stays, S8000 above every range -> error."""
    body = {"speeds_rpm": [650, 750, 950, 1050, 8000], "current_gear": 1}
    res = ok(srv, lathe, "gear-ranges", body)
    assert [(r["min_rpm"], r["max_rpm"]) for r in res["ranges"]] == TABLE
    assert res["automatic"] and res["range_way"] == 0 and res["spindle"] == "S1"
    assert gears(res)[:4] == [(41, True), (41, False), (42, True), (42, False)]
    assert res["steps"][4]["gear"] is None and "GEAR_NO_RANGE" in res["steps"][4]["error"]
    assert res["changes"] == []


@pytest.mark.parametrize(
    ("current", "way", "speed", "m"),
    [
        (2, 0, 750, 41),  # the overlap 700-800 of M41/M42: the current stage holds S, kept
        (3, 0, 750, 42),
        (1, 0, 750, 41),  # M40 does not hold S: bottom-up the first holding range is M41
        (1, 1, 750, 42),  # top-down it is M42
        (1, 0, 3900, 43),  # the overlap 3800-4000 of M43/M44
        (1, 1, 3900, 44),
    ],
)
def test_gear_selection_at_an_overlap(
    srv: Server, lathe: str, current: int, way: int, speed: float, m: int
) -> None:
    body = {"speeds_rpm": [speed], "current_gear": current, "range_way": way}
    assert gears(ok(srv, lathe, "gear-ranges", body)) == [(m, m != 39 + current)]


def test_edited_ranges_are_previewed_and_proposed(srv: Server, lathe: str) -> None:
    edited = [{"min_rpm": lo, "max_rpm": hi} for lo, hi in TABLE]
    edited[1]["max_rpm"] = 900  # M41 now reaches 900 rpm: S850 from M40 selects M41, not M42
    res = ok(srv, lathe, "gear-ranges", {"ranges": edited, "speeds_rpm": [850], "current_gear": 1})
    assert gears(res) == [(41, True)]
    assert res["changes"] == [
        {
            "target": "channel",
            "parameter": "spindel[0].range_table[1].max_speed",
            "before": 800,
            "after": 900,
            "why": res["changes"][0]["why"],
        }
    ]
    # the machine's own table still selects M42 for S850
    assert gears(ok(srv, lathe, "gear-ranges", {"speeds_rpm": [850], "current_gear": 1})) == [
        (42, True)
    ]


def test_the_gear_preview_matches_the_live_machine(srv: Server, lathe: str) -> None:
    """The rule previewed is the kernel's: the machine, told S300 M3 in the stage it is in,
    changes to the stage the preview names for S300 from there."""
    current = srv.axis("S1", lathe)["gear"]
    res = ok(srv, lathe, "gear-ranges", {"speeds_rpm": [300], "current_gear": current})
    expected = res["steps"][0]["gear"]
    assert expected == 1 != current  # only M40 (50-560) holds 300 rpm
    r = srv.command(lathe, {"type": "mdi", "block": "M3 S300"})
    assert r.status_code in (200, 202), r.text
    deadline = time.monotonic() + 30
    while srv.axis("S1", lathe)["gear"] != expected:
        assert time.monotonic() < deadline, srv.axis("S1", lathe)
        time.sleep(0.05)


def test_the_calculators_do_not_load_the_kernel() -> None:
    """The gateway never imports the numba kernel (only the assistants' process does): the
    routes of the calculators and the gear preview keep it that way."""
    code = (
        "import sys, backend.main, backend.services.gear_ranges;"
        "from nc_sim.assist.run import run; from nc_sim.config import demo_machine;"
        "inputs = {'axis': 'X', 'increments_per_rev': 4096, 'pitch_mm': 5.0};"
        "assert run('resolution', demo_machine(), inputs).changes[0].after == 4096;"
        "bad = [m for m in sys.modules if m == 'numba' or m == 'nc_sim.kernel.step'];"
        "print(bad); sys.exit(1 if bad else 0)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_run_up_on_a_copy_recovers_the_manuals_curve(srv: Server, lathe: str) -> None:
    """S1's gear 6 carries the manual's polynomial (000 §2.8.4); the run-up on a copy measures
    a(n) and the fit gives its points back within 2 %; the live spindle does not turn."""
    poly: dict[str, float] = {"typ": 2, "n_grenz": 12000000, "a_konst": 16000, "a_min": 2000}
    poly |= {"b1": -0.88888888, "b2": 2.08333333e-5, "b3": -1.92901234e-10}
    changes = [
        {"scope": "axis", "target": "S1", "name": f"getriebe[5].beschl_kennlinie.{k}", "value": v}
        for k, v in poly.items()
    ]
    r = srv.http.patch(f"/api/machines/{lathe}/parameters", json={"changes": changes})
    assert r.status_code == 200, r.text
    res = ok(srv, lathe, "curve-run-up", {"axis": "S1", "gear": 6, "typ": 2})
    f = figures(res)
    top = max(res["series"][0]["x"])  # the highest speed measured
    assert top > 36000  # the run reaches three of the four points
    for n, a in MANUAL_POINTS:  # the manual's points, where the run-up measured
        if n <= top:
            dn = n - f["n_limit"]
            fitted = f["a_konst"] + f["b1"] * dn + f["b2"] * dn**2 + f["b3"] * dn**3
            assert fitted == pytest.approx(a, rel=0.02), n
    n_grenz = {c["parameter"]: c for c in res["changes"]}["getriebe[5].beschl_kennlinie.n_grenz"]
    assert n_grenz["before"] == 12000000 and n_grenz["after"] == pytest.approx(12000000, rel=0.03)
    assert srv.axis("S1", lathe)["vel_act"] == 0
