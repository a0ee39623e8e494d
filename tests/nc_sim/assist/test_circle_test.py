"""The circularity test as an assistant (issue 38): the NC's own G02/G03 circle about where
the axes stand, read with ISO 230-4's geometry, and what it says about the cause.

References are physics and geometry, not our output: a gap b makes the true path step by b
where its axis reverses (the load trails the motor by b/2 against the motion); unequal kv
make an ellipse of F·|1/kv_x − 1/kv_z| that turns over with the direction and kv matching
removes it; an encoder counting (1 + δ) times the true travel shrinks the true path along
that axis by R·δ in both directions; friction makes spikes at the quadrant points that grow
with it."""

from __future__ import annotations

import re
from typing import Any

import pytest

from nc_sim.assist.circle_test import CCW, CW, NC_FEEDBACK, TRUE_PATH, circle_test
from nc_sim.assist.procedure import step_through
from nc_sim.assist.result import ExperimentError, Result
from nc_sim.assist.run import run
from nc_sim.commands import Accepted, ProgramLoad
from nc_sim.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.faults import EncoderResolutionWrong, Fault, FrictionRising
from nc_sim.params import Scope
from nc_sim.scenario import power_on
from nc_sim.sim import Simulation

R, F = 10.0, 1000.0
INCREMENT_UM = 0.1  # the demo's measuring system: wegaufz/wegaufn 1/1 in 0.1 µm
RIGID_NO_FRICTION = {
    "sim.measuring_system": "INDIRECT",  # the NC sees the motor: the gap is outside its loop
    "sim.mech.anti_resonance": 0,
    "sim.mech.coulomb_friction": 0,
    "sim.mech.breakaway_torque": 0,
    "sim.mech.viscous_friction": 0,
    "sim.mech.backlash": 0,
}
IDEAL = {"sim.plant": "IDEAL", "sim.drive_t": 0, "lr_param.ff_weight": 0}


def _cfg(axes: dict[str, dict[str, Any]]) -> MachineConfig:
    cfg = demo_machine()
    for name, values in axes.items():
        apply_overrides(cfg, Scope.AXIS, name, values)
    return cfg


def _circle(
    axes: dict[str, dict[str, Any]], path: int = NC_FEEDBACK, faults: tuple[Fault, ...] = ()
) -> Result:
    sim = Simulation(0.001)
    m = sim.add(_cfg(axes))
    power_on(sim, m)
    for f in faults:
        m.inject(f)
    return step_through(sim, circle_test(m, 18, R, F, 0, 0.0, 90.0, path))


def _figures(r: Result) -> dict[str, float]:
    return {f.name: f.value for f in r.figures}


@pytest.mark.parametrize("gap_um", [3.0, 10.0])
def test_a_gap_steps_the_true_path_by_its_width_where_its_axis_reverses(gap_um: float) -> None:
    axes = {"Z": RIGID_NO_FRICTION | {"sim.mech.backlash": gap_um * 10}, "X": RIGID_NO_FRICTION}
    f = _figures(_circle(axes, TRUE_PATH))
    assert f["lost_motion_Z_um"] == pytest.approx(gap_um, abs=INCREMENT_UM)
    assert f["lost_motion_X_um"] == pytest.approx(0.0, abs=INCREMENT_UM)
    # the NC's feedback on the motor does not see it: the loop keeps the motor on the circle
    on_motor = _figures(_circle(axes, NC_FEEDBACK))
    assert on_motor["lost_motion_Z_um"] == pytest.approx(0.0, abs=INCREMENT_UM)


def test_lost_motion_grows_by_what_the_gap_grows_on_the_demos_mechanics() -> None:
    """The demo's coupling twists under friction too (lost motion beyond the gap), but a
    wider gap adds exactly its widening."""
    steps = []
    for gap in (30, 100):  # 3 and 10 µm
        axes = {"Z": {"sim.measuring_system": "INDIRECT", "sim.mech.backlash": gap}}
        steps.append(_figures(_circle(axes, TRUE_PATH))["lost_motion_Z_um"])
    assert steps[1] - steps[0] == pytest.approx(7.0, abs=INCREMENT_UM)


def test_unequal_kv_make_a_servo_mismatch_that_kv_matching_removes() -> None:
    axes = {"X": IDEAL | {"getriebe[0].kv": 2000}, "Z": IDEAL | {"getriebe[0].kv": 2500}}
    before = _circle(axes)
    f = _figures(before)
    p2v = F / 60.0 * abs(1 / 20.0 - 1 / 25.0) * 1000.0  # 166.7 µm
    for d in ("ccw", "cw"):
        assert f[f"ellipse_{d}_um"] == pytest.approx(p2v, rel=0.05)
    diagonals = sorted(
        45.0 if abs(f[f"ellipse_{d}_deg"] - 45) < 20 else 135.0 for d in ("ccw", "cw")
    )
    assert diagonals == [45.0, 135.0]
    assert f["kv_X"] == pytest.approx(20.0, rel=0.01) and f["kv_Z"] == pytest.approx(25.0, rel=0.01)
    assert any(n.startswith("servo mismatch") for n in before.notes)
    (change,) = before.changes
    assert (change.target, change.parameter, change.after) == ("Z", "getriebe[0].kv", 2000)
    axes["Z"] = axes["Z"] | {change.parameter: change.after}
    after = _figures(_circle(axes))
    for d in ("ccw", "cw"):
        assert after[f"ellipse_{d}_um"] < 0.1 * f[f"ellipse_{d}_um"]


def test_kv_matching_on_the_drive_cascade() -> None:
    axes: dict[str, dict[str, Any]] = {"Z": {"getriebe[0].kv": 3000}}
    before = _circle(axes)
    (change,) = before.changes
    assert change.target == "Z" and change.after == pytest.approx(2000, abs=20)
    axes["Z"] = {change.parameter: change.after}
    after = _figures(_circle(axes))
    assert after["ellipse_ccw_um"] < 0.1 * _figures(before)["ellipse_ccw_um"]
    assert not _circle(axes).changes


def test_a_scale_error_shrinks_the_true_path_along_its_axis_in_both_directions() -> None:
    delta = 0.001  # X's encoder counts 1.001 × the true travel
    axes = {"X": IDEAL, "Z": IDEAL}
    r = _circle(axes, TRUE_PATH, (EncoderResolutionWrong("X", 1.0 + delta),))
    f = _figures(r)
    for d in ("ccw", "cw"):
        assert f[f"ellipse_{d}_um"] == pytest.approx(R * delta / (1 + delta) * 1000, rel=0.05)
        assert min(f[f"ellipse_{d}_deg"], 180 - f[f"ellipse_{d}_deg"]) < 5.0  # along Z: X short
    (note,) = [n for n in r.notes if n.startswith("scale mismatch: an ellipse")]
    per_m = re.search(r"Z travels about (\d+) µm/m further", note)
    assert "along Z" in note and per_m is not None
    assert float(per_m.group(1)) == pytest.approx(delta / (1 + delta) * 1e6, rel=0.05)


def test_reversal_spikes_sit_at_the_quadrant_points_and_grow_with_friction() -> None:
    spikes = []
    for factor in (1.0, 4.0):
        faults = tuple(FrictionRising(a, factor) for a in ("X", "Z")) if factor != 1.0 else ()
        f = _figures(_circle({}, NC_FEEDBACK, faults))
        for d in ("ccw", "cw"):
            off = min(abs((f[f"spike_{d}_deg"] - q + 180) % 360 - 180) for q in (0, 90, 180, 270))
            assert off < 10.0
        spikes.append(f["spike_ccw_um"])
    assert spikes[0] > 1.0  # outward: the axis sticks at its reversal
    assert spikes[1] > 2.0 * spikes[0]


def test_the_assistant_runs_by_its_descriptor_and_names_what_it_cannot() -> None:
    r = run("circle", demo_machine(), {"direction": CW, "radius_mm": 5.0})
    assert [s.name for s in r.series] == ["CW"]
    assert r.inputs["axis"] == "ZX"
    with pytest.raises(ExperimentError, match="G17 needs the path axes X and Y: Y"):
        run("circle", demo_machine(), {"plane": 17})
    with pytest.raises(ExperimentError, match="radius_mm"):
        run("circle", demo_machine(), {"radius_mm": 0})
    with pytest.raises(ExperimentError, match="higher feed or a smaller radius"):
        run("circle", demo_machine(), {"radius_mm": 400, "feed_mm_min": 10})


def test_a_program_the_channel_had_loaded_is_loaded_again() -> None:
    sim = Simulation(0.001)
    m = sim.add(demo_machine())
    power_on(sim, m)
    assert isinstance(m.submit(ProgramLoad("part", "G01 X51 F100\nM30\n")), Accepted)
    step_through(sim, circle_test(m, 18, 2.0, 2000.0, CCW, 0.0, 30.0))
    program = m.channel.progress.program
    assert program is not None and program.name == "part"
