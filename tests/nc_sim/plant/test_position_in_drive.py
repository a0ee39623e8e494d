"""Position control in the drive (P-AXIS-00320 `antr.operation_mode`): the position loop
closes at every drive step, measured against python-control's response of the same loop
built from the textbook blocks at the drive's rate; in the CNC it closes at the NC cycle,
later by a cycle, which the measured phase shows. The NC's worked check (lag = v/kv at
constant speed) holds in both."""

from __future__ import annotations

from typing import Any

import control
import numpy as np
import pytest

from nc_sim.commands import JogStart
from nc_sim.kernel import layout as L
from nc_sim.plant import frf
from nc_sim.plant import layout as PL
from tests.nc_sim.plant.test_frequency_response import FS, J_M, TS, _phase_close, _x_axis
from tests.nc_sim.sim_helpers import make

KP, TN = 1.0, 0.02  # p1460 (Nm·s/rad), p1462 (s): a speed loop of ~80 Hz
T_I = 250e-6  # current loop
F_LP, D_LP = 1500.0, 0.7  # current setpoint filter 1: PT2 low pass
RATIO = 2.0  # rigid: total inertia J_M · 2
KV = 100.0  # 1/s


def _params(drive_type: int, mode: str) -> dict[str, dict[str, Any]]:
    return _x_axis(
        **{
            "kenngr.antr_typ": drive_type,
            "antr.operation_mode": mode,
            "getriebe[0].kv": round(KV * 100),
            "lr_param.ff_weight": 0,
            "drive.speed_kp": KP,
            "drive.speed_tn": round(TN * 1e6),
            "drive.current_loop_t": round(T_I * 1e6),
            "drive.current_filter_active": 1,
            "drive.current_filter_1.denominator_frequency": F_LP,
            "drive.current_filter_1.denominator_damping": D_LP,
            "drive.inertia_ratio": RATIO,
        }
    )


def _measured(drive_type: int, mode: str) -> frf.Frf:
    """The closed position loop, position command -> actual position, excited at the
    position command per drive step (a PRBS of ±20 µm)."""
    sim, m, _ = make(_params(drive_type, mode))
    x = m.axis("X")
    exc = frf.prbs(13, 0.02, periods=8)
    sim.kernel.start_probe(x.slot, exc, PL.INJECT_POSITION)
    sim.run(len(exc) // round(sim.kernel.cycle_s / TS))
    tr = sim.kernel.probe_trace()[round(0.2 * FS) :]
    return frf.h1(tr[:, PL.D_P_REF], tr[:, PL.D_P_ACT], FS, nperseg=8192)


def _reference(f_hz: np.ndarray) -> np.ndarray:
    """The position loop at the drive's rate: w_ref(k) = kv·(r(k) - x(k)) on the PI speed
    loop (z⁻¹ computing time) and ZOH[low pass · current loop · rigid mass], x the
    integral of the speed; each block's response from python-control, combined."""
    s = control.tf("s")
    jt = J_M * RATIO
    wd = 2 * np.pi * F_LP
    drive = wd**2 / (s**2 + 2 * D_LP * wd * s + wd**2) / (T_I * s + 1)
    p_speed = control.c2d(control.ss(drive / (jt * s)), TS, method="zoh")
    p_angle = control.c2d(control.ss(drive / (jt * s**2)), TS, method="zoh")
    z = control.tf([1.0, 0.0], [1.0], TS)
    c = KP * (1 + TS / TN * z / (z - 1)) / z

    def h(sys: Any) -> np.ndarray:
        return np.asarray(control.frequency_response(sys, 2 * np.pi * f_hz).complex).ravel()

    hc = h(c)
    angle_per_ref = hc * h(p_angle) / (1 + hc * h(p_speed))  # w_ref -> load angle
    # r and x in mm: w_ref = kv·(r - x)/mm_per_rad and x = mm_per_rad·angle, so kv acts on
    # the angle alone
    loop = KV * angle_per_ref
    closed: np.ndarray = loop / (1 + loop)
    return closed


def test_position_control_in_the_drive_closes_at_every_drive_step() -> None:
    measured = _measured(2, "DRIVE_POSITION_CONTROL").band(2.0, 150.0)
    ref = _reference(measured.f_hz)
    np.testing.assert_allclose(measured.magnitude_db, 20 * np.log10(np.abs(ref)), atol=1.0)
    _phase_close(np.degrees(np.angle(measured.h)), np.degrees(np.angle(ref)), 3.0)


@pytest.mark.parametrize(
    ("drive_type", "mode", "in_drive"),
    [
        (2, "DRIVE_DEFAULT", True),  # SERCOS: in the drive by default [004 §2.1]
        (2, "CNC_POSITION_CONTROL", False),
        (6, "DRIVE_POSITION_CONTROL", False),  # a terminal (±10 V) drive cannot
    ],
)
def test_where_the_position_loop_closes_follows_the_operation_mode(
    drive_type: int, mode: str, in_drive: bool
) -> None:
    measured = _measured(drive_type, mode).band(80.0, 120.0)
    ref_phase = np.degrees(np.angle(_reference(measured.f_hz)))
    extra_lag = float(np.mean((ref_phase - measured.phase_deg + 180.0) % 360.0 - 180.0))
    if in_drive:
        assert abs(extra_lag) < 3.0
    else:  # the NC reads once per cycle and holds its output over it: at least half a
        # cycle (0.5 ms) more delay than the drive's step, 14.4° at 80 Hz
        assert extra_lag > 14.4


@pytest.mark.parametrize("mode", ["DRIVE_POSITION_CONTROL", "CNC_POSITION_CONTROL"])
def test_lag_is_v_over_kv_at_constant_speed_wherever_the_loop_closes(mode: str) -> None:
    """[DOMAIN §2]: lag = v / kv without feedforward, 1000 mm/min at kv 100/s: 0.1667 mm."""
    sim, m, _ = make(_params(2, mode))
    m.submit(JogStart("X", 1, 1000.0))
    sim.run(1500)
    st = sim.kernel.st[m.axis("X").slot]
    v = 1000.0 / 60.0
    assert float(st[L.S_V_ACT]) == pytest.approx(v, rel=1e-3)
    assert float(st[L.S_LAG]) == pytest.approx(v / KV, abs=2e-4)
