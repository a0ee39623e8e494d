"""The training faults of the drive cascade's mechanics, measured as a trainee would find them
(the frequency response, the speed a P loop loses), against physics; removing one gives the
sound plant back."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc_sim.assist.frequency_response import CLOSED_SPEED, MECHANICS, frequency_response
from nc_sim.assist.procedure import step_through
from nc_sim.assist.result import Result
from nc_sim.faults import CouplingSoft, FrictionRising, NotchMistuned
from nc_sim.machine.machine import Machine
from nc_sim.plant import layout as PL
from nc_sim.sim import Simulation
from tests.nc_sim.plant.test_frequency_response import FS, _x_axis
from tests.nc_sim.sim_helpers import make, mdi


def _mechanics(m: Machine, sim: Simulation) -> Result:
    return step_through(sim, frequency_response(m, "X", MECHANICS, offset_rpm=30.0))


def test_a_coupling_gone_soft_brings_both_frequencies_down_by_the_root_of_its_stiffness() -> None:
    f_ar, ratio = 80.0, 3.0
    sim, m, _ = make(_x_axis(**{"drive.inertia_ratio": ratio, "sim.mech.anti_resonance": f_ar}))
    sound = _mechanics(m, sim)
    fid = m.inject(CouplingSoft("X", 0.25))  # a quarter the stiffness: half the frequencies
    soft = _mechanics(m, sim)
    assert soft.figure("anti_resonance_1_hz") == pytest.approx(f_ar / 2, rel=0.02)
    assert soft.figure("resonance_1_hz") == pytest.approx(f_ar * math.sqrt(ratio) / 2, rel=0.02)
    m.remove_fault(fid)
    again = _mechanics(m, sim)
    assert again.figure("resonance_1_hz") == pytest.approx(sound.figure("resonance_1_hz"))


def test_rising_friction_costs_a_p_speed_loop_that_much_more_speed() -> None:
    kp, fc = 0.3, 0.15
    params = _x_axis(**{"drive.speed_kp": kp, "drive.speed_tn": 0, "sim.mech.coulomb_friction": fc})

    def speed_error(factor: float) -> float:
        sim, m, _ = make(params)
        if factor != 1.0:
            m.inject(FrictionRising("X", factor))
        sim.kernel.start_probe(m.axis("X").slot, np.zeros(round(2 * FS)), PL.INJECT_TORQUE)
        mdi(m, "G01 X150 F2000")
        sim.run(2000)
        cruise = sim.kernel.probe_trace()[round(1.5 * FS) :]
        return float((cruise[:, PL.D_W_REF] - cruise[:, PL.D_W_MOTOR]).mean())

    assert speed_error(1.0) == pytest.approx(fc / kp, rel=0.01)
    assert speed_error(3.0) == pytest.approx(3 * fc / kp, rel=0.01)


def test_a_mistuned_notch_lets_the_resonance_back_into_the_speed_loop() -> None:
    f_ar, ratio = 300.0, 3.0
    f_r = f_ar * math.sqrt(ratio)
    params = _x_axis(
        **{
            "drive.speed_kp": 0.8,
            "drive.inertia_ratio": ratio,
            "sim.mech.anti_resonance": f_ar,
            "sim.mech.damping": 0.02,
            "drive.current_filter_active": 2,
            "drive.current_filter_2.type": "GENERAL_2ND_ORDER",
            "drive.current_filter_2.denominator_frequency": f_r,
            "drive.current_filter_2.denominator_damping": 0.3,
            "drive.current_filter_2.numerator_frequency": f_r,
            "drive.current_filter_2.numerator_damping": 0.0,
        }
    )

    def peak_db(factor: float) -> float:
        sim, m, _ = make(params)
        if factor != 1.0:
            m.inject(NotchMistuned("X", factor))
        r = step_through(sim, frequency_response(m, "X", CLOSED_SPEED, offset_rpm=0.0))
        band = [
            y
            for f, y in zip(r.series[0].x, r.series[0].y, strict=True)
            if 0.9 * f_r <= f <= 1.1 * f_r
        ]
        return max(band)

    assert peak_db(0.6) > peak_db(1.0) + 10.0  # the notch sits at 0.6·f_r, the peak returns
