"""`inbetrieb assist ... --json` as a subprocess, its numbers against the manuals
[004 §3.4, §3.6.1, 000 §2.2.4, §2.8.4]."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]


def assist(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "backend.cli", "assist", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )


def answer(*args: str) -> dict[str, Any]:
    done = assist(*args, "--json")
    assert done.returncode == 0, done.stderr
    out: dict[str, Any] = json.loads(done.stdout)
    return out


def after(out: dict[str, Any]) -> dict[str, Any]:
    return {c["parameter"]: c["after"] for c in out["changes"]}


def figure(out: dict[str, Any], name: str) -> float:
    return float(next(f["value"] for f in out["figures"] if f["name"] == name))


def test_resolution_with_gear() -> None:
    out = answer("resolution", "--increments", "4096", "--pitch", "5", "--gear-ratio", "10")
    assert after(out) == {"getriebe[0].wegaufz": 4096, "getriebe[0].wegaufn": 5000}


def test_multi_gain_calc_terminal_spindle_and_sercos_rotary() -> None:
    out = answer(
        "multi-gain-calc",
        "--full-scale-digits",
        "32767",
        "--full-scale-rpm",
        "9000",
        "--gear-ratio",
        "5",
    )
    assert figure(out, "multi_gain") == pytest.approx(50.5668, rel=2e-5)
    out = answer("multi-gain-calc", "--weighting-rpm", "1e-4", "--axis", "S1")
    assert after(out) == {"getriebe[0].multi_gain_z": 10000000, "getriebe[0].multi_gain_n": 360}


def test_speed_scaling() -> None:
    out = answer("speed-scaling", "--increments", "32767", "--rpm", "3000")
    assert after(out)["antr.v_reso_num"] == 32767
    assert after(out)["antr.v_reso_denom"] == 1080000000


def test_curve_fit_reproduces_the_manuals_polynomial() -> None:
    out = answer(
        "curve-fit", "--type", "2", "--points", "12000:16000,24000:8000,36000:4000,48000:2000"
    )
    assert figure(out, "b3") == pytest.approx(-1.92901234e-10, rel=1e-7)
    assert figure(out, "b2") == pytest.approx(2.08333333e-5, rel=1e-7)
    assert figure(out, "b1") == pytest.approx(-0.88888888, rel=1e-7)
    assert after(out)["getriebe[0].beschl_kennlinie.n_grenz"] == 12000000


def test_curve_run_up_on_the_demo_with_overrides() -> None:
    curve: dict[str, float] = {"typ": 2, "a_min": 2000, "n_grenz": 12000000, "a_konst": 16000}
    curve |= {"b1": -0.88888888, "b2": 2.08333333e-5, "b3": -1.92901234e-10}
    sets = [
        a for k, v in curve.items() for a in ("--set", f"S1.getriebe[5].beschl_kennlinie.{k}={v}")
    ]
    out = answer("curve-run-up", "--spindle", "S1", "--gear", "6", *sets)
    assert figure(out, "a_konst") == pytest.approx(16000, rel=0.02)
    assert figure(out, "n_limit") == pytest.approx(12000, rel=0.03)
    assert out["series"][0]["name"] == "points" and len(out["series"][0]["x"]) > 20


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["curve-fit", "--type", "2", "--points", "12000:16000,oops"], "n:a pairs"),
        (["curve-fit", "--type", "2", "--points", "12000:16000,24000:8000"], "3 to 500 rows"),
        (
            ["curve-fit", "--type", "2", "--points", "12000:16000,24000:8000,36000:4000"],
            "at least 4",
        ),
        (["multi-gain-calc", "--full-scale-rpm", "9000"], "both digits and rpm"),
        (["curve-run-up", "--gear", "6", "--set", "S1.nonsense=1"], "nonsense"),
        (["curve-run-up", "--gear", "6", "--set", "S1-no-dot"], "TARGET.PARAM=VALUE"),
        (["curve-run-up", "--gear", "6", "--machine", "no/such/dir"], "no/such/dir"),
        (
            ["resolution", "--increments", "4096", "--pitch", "0"],
            "pitch_mm: 0 is out of range (> 0",
        ),
        (["loop-gain", "--axis", "X", "--kv", "10,fast"], "separated by commas"),
        (
            ["loop-gain", "--axis", "X", "--kv", "0,20"],
            "kvs: 0 is out of range (> 0 and ≤ 10000 1/s)",
        ),
        (["loop-gain", "--axis", "S1"], "spindle"),
    ],
)
def test_bad_options_are_a_message_and_exit_2(args: list[str], message: str) -> None:
    done = assist(*args)
    assert done.returncode == 2
    assert message in done.stderr
    assert "Traceback" not in done.stderr


def test_the_issues_multi_gain_experiment_from_the_command_line() -> None:
    """`inbetrieb assist multi-gain --axis X --feed 200 --set X.sim.drive_gain=22857 --json`:
    the drive gives 22857 digits per 1 m/min where the NC assumes 10000, so f = 2.2857."""
    out = answer("multi-gain", "--axis", "X", "--feed", "200", "--set", "X.sim.drive_gain=22857")
    assert out["ok"] and figure(out, "f") == pytest.approx(2.2857, rel=0.01)
    new = after(out)
    ratio = new["getriebe[0].multi_gain_z"] / new["getriebe[0].multi_gain_n"]
    assert ratio == pytest.approx(22857, rel=0.01)
    assert new["getriebe[0].kv"] == pytest.approx(875, abs=1)


def test_the_sign_check_from_the_command_line() -> None:
    out = answer("sign-check", "--axis", "X", "--set", "X.sim.motor_inverted=1")
    assert after(out) == {"lr_hw[0].vz_stellgr": 1}
    bad = assist("multi-gain", "--axis", "X", "--json")
    assert bad.returncode == 2 and "Traceback" not in bad.stderr


def test_the_loop_gain_sweep_from_the_command_line() -> None:
    """X on the ideal drive with T = 20 ms (`--set X.sim.drive_t=20000`): the second-order loop
    overshoots 0.09 % at kv 15/s and 7.0 % at 30/s (ζ = 1/(2√(kv·T))), so with 5 % allowed
    the highest of 10,15,30 is 15 (the axis has 20); at constant feed the lag is v/kv."""
    out = answer(
        "loop-gain", "--axis", "X", "--kv", "30,10,15", "--overshoot-pct", "5",
        "--settle-ms", "300", "--feed", "600",
        "--set", "X.sim.plant=IDEAL", "--set", "X.sim.drive_t=20000",
    )  # fmt: skip
    assert out["ok"] and figure(out, "kv_new") == 15.0
    assert after(out) == {"getriebe[0].kv": 1500}
    assert figure(out, "lag@10") == pytest.approx(10.0 / 10.0, abs=1e-4)  # 600 mm/min = 10 mm/s
    assert figure(out, "overshoot_pct@30") > 5.0


def test_an_assistant_gets_its_options_from_its_descriptor() -> None:
    """The resolution check's options come from the registry alone: Z moves -50 mm on a copy,
    the dial gauge said 49.9 mm, so k = 50/49.9 and wegaufz/wegaufn (1/1) becomes k."""
    out = answer("resolution-check", "--axis", "Z", "--distance", "-50", "--measured", "-49.9")
    assert figure(out, "k") == pytest.approx(50 / 49.9, rel=5e-6)
    pair = after(out)
    assert pair["getriebe[0].wegaufz"] / pair["getriebe[0].wegaufn"] == pytest.approx(
        50 / 49.9, rel=5e-6
    )
