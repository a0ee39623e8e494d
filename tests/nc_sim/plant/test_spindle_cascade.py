"""The spindle on the drive cascade: it ramps up within its dynamic lag monitoring, the
NC's worked check holds (lag = v/kv at constant speed, kv 10/s: 1000 rpm -> 600°), the
motor turns at the spindle speed times the gear ratio, and each gear stage sets the inertia
the motor drives (the mechanics measured as an integrator of J_M · p0342 of that stage):
INB-SIM-0031 and INB-SIM-0032 per stage."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from nc_sim.commands import SpindleRun
from nc_sim.kernel import layout as L
from nc_sim.plant import frf
from nc_sim.plant import layout as PL
from nc_sim.units import RPM_TO_RAD_S
from tests.nc_sim.sim_helpers import make

TS = 125e-6
FS = 1.0 / TS
J_M = 0.01  # p0341 (kg·m²)
# the demo spindle's stages 1 (M40) and 3 (M42): motor revolutions per spindle revolution,
# and p0342 of each: the load weighs more on the motor through the lower ratio
RATIO = {1: 16.0, 3: 2.5}
INERTIA_RATIO = {1: 1.1, 3: 6.0}


def _spindle() -> dict[str, dict[str, Any]]:
    values: dict[str, Any] = {
        "sim.plant": "DRIVE_CASCADE",
        "drive.speed_kp": 3.0,
        "drive.speed_tn": 20000,
        "drive.current_loop_t": 250,
        "drive.current_filter_active": 0,
        "drive.torque_limit": 200.0,
        "drive.motor_inertia": J_M,
        "drive.inertia_ratio": 2.0,  # what the stages below do not give
        "sim.mech.anti_resonance": 0.0,
        "sim.mech.coulomb_friction": 0.0,
        "sim.mech.breakaway_torque": 0.0,
        "sim.mech.viscous_friction": 0.0,
        "sim.mech.backlash": 0,
        "sim.measuring_system": "DIRECT",
    }
    for stage, ratio in RATIO.items():
        # spindle travel per motor revolution in 0.0001°
        values[f"sim.getriebe[{stage - 1}].travel_per_rev"] = round(3_600_000 / ratio)
        values[f"sim.getriebe[{stage - 1}].inertia_ratio"] = INERTIA_RATIO[stage]
    return {"S1": values}


def _trace(sim: Any, slot: int, excitation: np.ndarray, point: int) -> np.ndarray:
    sim.kernel.start_probe(slot, excitation, point)
    sim.run(len(excitation) // round(sim.kernel.cycle_s / TS))
    return np.asarray(sim.kernel.probe_trace())


def test_a_spindle_on_the_cascade_keeps_the_manuals_lag_and_turns_its_motor_by_the_ratio() -> None:
    sim, m, _ = make(_spindle())
    s1 = m.axis("S1")
    m.submit(SpindleRun("S1", 3, 1000.0))  # M42 (stage 3) from start-up covers 1000 rpm
    sim.run(6000)
    assert s1.gear == 3
    assert s1.job_error == 0  # the ramp stayed within the lag model's tolerance (5°)
    st = sim.kernel.st[s1.slot]
    assert float(st[L.S_V_ACT]) == pytest.approx(6000.0, rel=1e-3)  # °/s
    assert float(st[L.S_LAG]) == pytest.approx(600.0, rel=0.01)  # [DOMAIN §2]
    tr = _trace(sim, s1.slot, np.zeros(4000), PL.INJECT_TORQUE)
    motor = float(np.mean(tr[:, PL.D_W_MOTOR]))
    assert motor == pytest.approx(1000.0 * RATIO[3] * RPM_TO_RAD_S, rel=0.005)


@pytest.mark.parametrize("stage", [1, 3])
def test_each_gear_stage_sets_the_inertia_the_motor_drives(stage: int) -> None:
    sim, m, _ = make(_spindle())
    s1 = m.axis("S1")
    m.submit(SpindleRun("S1", 3, 300.0 if stage == 1 else 1000.0))  # 300 rpm: M40
    sim.run(9000)
    assert s1.gear == stage
    tr = _trace(sim, s1.slot, frf.prbs(12, 1.0, periods=10), PL.INJECT_TORQUE)
    h = frf.h1(tr[:, PL.D_TORQUE], tr[:, PL.D_W_MOTOR], FS, nperseg=4096).band(10.0, 300.0)
    j_total = J_M * INERTIA_RATIO[stage]
    expected_db = -20 * np.log10(j_total * 2 * np.pi * h.f_hz)
    np.testing.assert_allclose(h.magnitude_db, expected_db, atol=1.0)
