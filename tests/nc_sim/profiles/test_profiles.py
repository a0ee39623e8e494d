"""Setpoint profiles against analytic results and an independent time-optimal generator."""

from __future__ import annotations

import math

import numpy as np
import pytest
from ruckig import InputParameter, Ruckig, Trajectory

from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.profiles.plan import (
    SHAPE_SIN2,
    make_limits,
    new_plan,
    plan_distance,
    plan_duration,
    position_move,
    velocity_change,
)

CYCLE = 0.001


def ideal_slot(k: Kernel) -> int:
    """An enabled slot with a matched loop, for watching the setpoint alone."""
    s = k.claim(1)[0]
    for col, value in (
        (L.P_KV, 10.0),
        (L.P_MG, 1.0),
        (L.P_DRV_GAIN, 1.0),
        (L.P_DA_MAX, 1e300),
        (L.P_SIGN_CMD, 1.0),
        (L.P_SIGN_FB, 1.0),
        (L.P_MOTOR_SIGN, 1.0),
        (L.P_ENC_SIGN, 1.0),
        (L.P_LAG_MAX, 1e300),
        (L.P_SWE_POS, 1e300),
        (L.P_SWE_NEG, -1e300),
        (L.P_CAM_POS, 1e300),
    ):
        k.pr[s, col] = value
    k.ist[s, L.I_ENABLED] = 1
    return s


def ruckig_duration(d: float, v: float, a: float, j: float) -> float:
    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [d], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v], [a], [j]
    traj = Trajectory(1)
    Ruckig(1).calculate(inp, traj)
    return float(traj.duration)


def test_rest_to_rest_moves_are_time_optimal() -> None:
    """Seeded random moves: our plan's duration equals ruckig's, and the kernel ends the move
    in the cycle that contains that instant."""
    rng = np.random.default_rng(20261121)
    k = Kernel(CYCLE)
    slot = ideal_slot(k)
    for _ in range(150):
        d = float(rng.uniform(0.01, 500.0)) * (1 if rng.random() < 0.5 else -1)
        v = float(rng.uniform(5.0, 1000.0))
        a = float(rng.uniform(100.0, 10000.0))
        tr = float(rng.uniform(0.002, 0.2))
        lim = make_limits(a, a, tr, tr, tr, tr)
        seg = new_plan()
        n = position_move(seg, 0.0, 0.0, 0.0, d, v, lim, CYCLE)
        t_ours = plan_duration(seg, n)
        t_ref = ruckig_duration(abs(d), v, a, a / tr)
        assert t_ours == pytest.approx(t_ref, abs=1e-6)
        assert plan_distance(seg, 0, n, 0.0)[0] == pytest.approx(d, abs=1e-9)
        # execute in the kernel: the plan-done event falls in the cycle holding t_ref
        k.st[slot, L.S_P_CMD] = k.st[slot, L.S_V_CMD] = 0.0
        k.load_plan(slot, seg, n, d)
        cycles = 0
        while k.ist[slot, L.I_EVENTS] & L.EV_PLAN_DONE == 0:
            cycles += k.run(100000)
        k.ist[slot, L.I_EVENTS] = 0
        assert abs(cycles * CYCLE - t_ref) <= CYCLE
        assert k.st[slot, L.S_P_CMD] == d


@pytest.mark.parametrize(("v0", "v1", "a"), [(0.0, 100.0, 1000.0), (50.0, -50.0, 500.0)])
def test_step_shaped_ramp_time_is_dv_over_a(v0: float, v1: float, a: float) -> None:
    seg = new_plan()
    n = velocity_change(seg, 0, v0, 0.0, v1, make_limits(a, a), CYCLE)
    assert plan_duration(seg, n) == pytest.approx(abs(v1 - v0) / a)


def test_two_stage_step_profile_uses_each_acceleration_in_its_band() -> None:
    # a_stufe_1 = 1000 below vb_stufe_1_2 = 40, a_stufe_2 = 250 above [002 §2.2.1]
    seg = new_plan()
    n = velocity_change(
        seg, 0, 0.0, 0.0, 100.0, make_limits(1000, 1000, a_acc2=250, a_dec2=250, v12=40), CYCLE
    )
    assert plan_duration(seg, n) == pytest.approx(40 / 1000 + 60 / 250)


@pytest.mark.parametrize("shape", [0.0, SHAPE_SIN2])
def test_jerk_limited_ramp_time_and_peak_jerk(shape: float) -> None:
    # 0 -> 100 at a = 1000 with ramp times 20 ms: t = v/a + tr = 0.12 s for both shapes;
    # sine-square needs pi/2 times the jerk of the trapezoid [002 §2.2.3]
    seg = new_plan()
    n = velocity_change(
        seg, 0, 0.0, 0.0, 100.0, make_limits(1000, 1000, 0.02, 0.02, 0.02, 0.02, shape), CYCLE
    )
    assert plan_duration(seg, n) == pytest.approx(0.12)
    assert plan_distance(seg, 0, n, 0.0)[1] == pytest.approx(100.0)
    k = Kernel(CYCLE)
    s = ideal_slot(k)
    k.load_plan(s, seg, n, math.nan)
    rec = np.zeros((200, 1, L.R_COLS))
    k.run(200, rec)
    acc = rec[:, 0, L.R_A_CMD]
    jerk = np.max(np.abs(np.diff(acc))) / CYCLE
    expected = 1000 / 0.02 * (math.pi / 2 if shape else 1.0)
    assert jerk == pytest.approx(expected, rel=0.01)
    assert np.max(acc) == pytest.approx(1000.0)
