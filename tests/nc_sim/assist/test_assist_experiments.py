"""The experiment assistants on the demo lathe in simulated time [004 §3.5, §3.6.2].

The plants are made wrong on purpose through the simulated drive (`sim.drive_gain`: the
drive's true digits for 1 m/min; `sim.encoder_inverted`, `sim.motor_inverted`), so the right
answer is known from physics: the effective gain is k = kv · multi_gain / drive_gain, and the
correction f = drive_gain / multi_gain.
"""

from __future__ import annotations

from typing import Any

import pytest

from nc_sim.assist.experiments import multi_gain_experiment, sign_check_experiment
from nc_sim.assist.result import ExperimentError, Result
from nc_sim.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.params import Scope


def lathe(**axes: dict[str, Any]) -> MachineConfig:
    cfg = demo_machine()
    for name, values in axes.items():
        apply_overrides(cfg, Scope.AXIS, name, values)
    return cfg


def applied(cfg: MachineConfig, r: Result) -> MachineConfig:
    for c in r.changes:
        apply_overrides(cfg, Scope.AXIS, c.target, {c.parameter: c.after})
    return cfg


def test_the_manuals_example_gives_the_manuals_numbers() -> None:
    """004 §3.6.2: kv = 4/s (400), multi_gain 1/1, a plant whose gain makes s = 1.9 mm at
    200 mm/min: k = 1.75, f = 2.286, multi_gain 2286/1000, kv 175."""
    cfg = lathe(
        X={
            "getriebe[0].kv": 400,
            "getriebe[0].multi_gain_z": 1,
            "getriebe[0].multi_gain_n": 1,
            "sim.drive_gain": 4.0 / 1.75,  # k = kv · 1 / drive_gain = 1.75
        }
    )
    r = multi_gain_experiment(cfg, "X", feed_mm_min=200)
    assert r.ok
    assert r.figure("s") == pytest.approx(1.9, rel=0.01)  # 200 mm/min / 60 / 1.75
    assert r.figure("k") == pytest.approx(1.75, rel=0.01)
    assert r.figure("f") == pytest.approx(2.286, rel=0.01)
    after = {c.parameter: c.after for c in r.changes}
    assert after["getriebe[0].multi_gain_n"] == 1000
    assert after["getriebe[0].multi_gain_z"] == pytest.approx(2286, rel=0.01)
    assert after["getriebe[0].kv"] == pytest.approx(175, abs=1)
    assert r.figure("averaged_s") == pytest.approx(1.0, abs=0.002)  # the 1 s asked for


def test_a_wrong_drive_gain_is_corrected_and_then_k_equals_kv() -> None:
    """The issue's case: X's drive gives 22857 digits per 1 m/min, the NC assumes 10000:
    f = 2.2857 within 1 %; with the new multi_gain alone k equals kv (20/s), with kv/f too
    k equals the new kv."""
    cfg = lathe(X={"sim.drive_gain": 22857})
    r = multi_gain_experiment(cfg, "X", feed_mm_min=200)
    assert r.figure("f") == pytest.approx(22857 / 10000, rel=0.01)
    assert r.figure("k") == pytest.approx(20.0 * 10000 / 22857, rel=0.01)
    only_gain = Result(
        "multi-gain", changes=tuple(c for c in r.changes if "multi_gain" in c.parameter)
    )
    again = multi_gain_experiment(applied(lathe(X={"sim.drive_gain": 22857}), only_gain), "X", 200)
    assert again.figure("k") == pytest.approx(20.0, rel=0.01)
    assert again.figure("f") == pytest.approx(1.0, abs=0.01)
    both = multi_gain_experiment(applied(lathe(X={"sim.drive_gain": 22857}), r), "X", 200)
    assert both.figure("k") == pytest.approx(both.figure("kv"), rel=0.01)
    assert both.figure("kv") == pytest.approx(20.0 / 2.2857, rel=0.01)


def test_a_spindle_position_controlled_at_constant_speed() -> None:
    """S1 at 50 rpm in gear stage 1 (range 50-560) with a drive 10 % stronger than its
    multi_gain: f = 1.1 within 1 %, proposed for getriebe[0]."""
    cfg = lathe(S1={"sim.getriebe[0].drive_gain": 1.1 * 161.8144})
    r = multi_gain_experiment(cfg, "S1", speed_rpm=50)
    assert r.ok, r.notes
    assert r.figure("f") == pytest.approx(1.1, rel=0.01)
    params = {c.parameter for c in r.changes}
    assert params == {"getriebe[0].multi_gain_z", "getriebe[0].multi_gain_n", "getriebe[0].kv"}


def test_a_refused_experiment_says_why() -> None:
    with pytest.raises(ExperimentError, match="feed"):
        multi_gain_experiment(lathe(), "X")
    with pytest.raises(ExperimentError, match="Q"):
        multi_gain_experiment(lathe(), "Q", feed_mm_min=100)
    # the NC's own words, as the HMI shows them: the job error's text, not a repr of it
    with pytest.raises(ExperimentError) as refused:
        multi_gain_experiment(lathe(), "S1", speed_rpm=50000)
    assert str(refused.value) == (
        "the motion was refused: spindle speed out of reach: S50000 rpm is above the highest "
        "gear stage, M45 up to 7000 rpm (range_table[5].max_speed, P-CHAN-00055)"
    )


@pytest.mark.parametrize(
    ("plant", "flips"),
    [
        ({}, set()),
        ({"sim.encoder_inverted": 1}, {"lr_hw[0].vz_istw"}),
        ({"sim.motor_inverted": 1}, {"lr_hw[0].vz_stellgr"}),
        (
            {"sim.encoder_inverted": 1, "sim.motor_inverted": 1},
            {"lr_hw[0].vz_istw", "lr_hw[0].vz_stellgr"},
        ),
    ],
    ids=["right", "encoder", "motor", "mirrored"],
)
def test_the_sign_check_finds_each_wrong_sign_before_lag_monitoring(
    plant: dict[str, Any], flips: set[str]
) -> None:
    """004 §3.5: one wrong sign makes the loop run away; it is found within a few increments
    of the actual going the wrong way, far below lag_max (5 mm), and the servo goes off. Both
    wrong leave the loop stable but mirrored: only the way the machine moved shows it. After
    the proposed flips the check is clean."""
    r = sign_check_experiment(lathe(X=plant), "X")
    assert r.ok
    assert {c.parameter for c in r.changes} == flips
    assert r.figure("max_lag") < 0.1 * r.figure("lag_max")
    assert r.figure("runaway") == float(len(flips) == 1)
    fixed = sign_check_experiment(applied(lathe(X=plant), r), "X")
    assert fixed.changes == () and fixed.figure("runaway") == 0.0
