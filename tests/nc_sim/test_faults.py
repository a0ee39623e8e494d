"""Training faults (nc_sim/faults.py) in the simulated plant and PLC: each shows the symptom
physics gives it, none changes a parameter, and removing one gives the sound plant back."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from nc_sim.commands import Mdi, PlcMode, Reset
from nc_sim.errors import Code, NcUsageError
from nc_sim.faults import (
    NOW,
    Backlash,
    DriveAccelLimit,
    DriveGainWrong,
    DriveNotReady,
    EnableDrop,
    EncoderNoise,
    EncoderResolutionWrong,
    Friction,
    GearRatioWrong,
    MotorInverted,
    PlcNoAck,
    PlcSlowAck,
    Trigger,
)
from nc_sim.machine.machine import Machine
from nc_sim.sim import Simulation
from tests.nc_sim.sim_helpers import L, make, mdi, record

KV_X = 20.0  # demo X: getriebe[0].kv 2000 = 20 /s [004 §3.6]
NO_LAG_MONITOR = {"getriebe[0].lag_max": 10_000_000}  # 1000 mm: a wrong plant runs on
# the friction and backlash faults as the ideal drive has them: a speed the drive loses, a
# kinematic gap (the drive cascade's: tests/nc_sim/plant)
IDEAL = {"sim.plant": "IDEAL"}


def _errors(m: Machine) -> list[int]:
    return [e.code for e in m.events if e.error]


def _cruise(sim: Simulation, m: Machine, feed: float, seconds: float) -> tuple[float, float]:
    """Steady lag (mm) and actual speed (mm/s) of X in a long G01 move at `feed` mm/min:
    the means over the last second of `seconds`."""
    x = m.axis("X")
    start = float(m.k.st[x.slot, L.S_P_CMD])
    mdi(m, f"G01 X{start + feed / 60 * (seconds + 2):.3f} F{feed}")  # limits off: unhomed
    rec = record(sim, seconds)[-1000:, x.slot]
    return float(rec[:, L.R_LAG].mean()), float(rec[:, L.R_V_ACT].mean())


def test_motor_inverted_runs_away_into_lag_monitoring_and_changes_no_parameter() -> None:
    """Positive feedback: the lag grows until lag monitoring (getriebe[0].lag_max) trips,
    while the parameter lists and the HLI's signs stay as they were."""
    sim, m, cfg = make()
    lists = pickle.dumps(cfg)
    x = m.axis("X")
    assert m.inject(MotorInverted("X")) == 1
    mdi(m, "G01 X60 F1000")
    rec = record(sim, 2.0)
    assert _errors(m) == [Code.LAG_MONITORING]
    assert np.max(np.abs(rec[:, x.slot, L.R_LAG])) > 5.0  # ran away beyond lag_max 5 mm
    assert pickle.dumps(m.cfg) == lists
    assert not cfg.axis("X").flag("sim.motor_inverted")
    assert [(f.id, f.active_since) for f in m.faults()] == [(1, 20)]


def test_after_a_lag_trip_the_reset_gives_the_servo_back() -> None:
    """The error reaction takes X's TorquePermission; the CNC reset that clears the error
    gives it back (the PLC program's part), and X then reaches its target without a trip."""
    sim, m, _ = make()
    x = m.axis("X")
    fid = m.inject(MotorInverted("X"))
    mdi(m, "G01 X60 F1000")
    record(sim, 2.0)
    assert _errors(m) == [Code.LAG_MONITORING] and x.units["TorquePermission"] == 0
    m.remove_fault(fid)
    m.submit(Reset())
    record(sim, 0.1)
    assert x.units["TorquePermission"] == 1 and x.job_error == 0
    start = float(m.k.st[x.slot, L.S_P_CMD])
    mdi(m, f"G01 X{start + 5:.3f} F600")  # 5 mm at 10 mm/s
    rec = record(sim, 1.5)
    assert _errors(m) == [Code.LAG_MONITORING]  # no second trip
    assert rec[-1, x.slot, L.R_P_ACT] == pytest.approx(start + 5, abs=0.01)


def test_drive_gain_wrong_gives_the_factor_times_kv_as_the_measured_gain() -> None:
    """k = v / lag in steady motion equals factor · kv [004 §3.6.2]."""
    sim, m, _ = make({"X": NO_LAG_MONITOR})
    m.inject(DriveGainWrong("X", 1.6))
    lag, v = _cruise(sim, m, 1200.0, 3.0)
    assert v == pytest.approx(20.0, rel=1e-3)
    assert v / lag == pytest.approx(1.6 * KV_X, rel=0.01)


def test_removing_a_fault_restores_the_plant() -> None:
    sim, m, _ = make({"X": NO_LAG_MONITOR})
    fid = m.inject(DriveGainWrong("X", 0.5))
    slot = m.axis("X").slot
    assert m.k.pr[slot, L.P_DRV_GAIN] == pytest.approx(20000.0)
    m.remove_fault(fid)
    assert m.k.pr[slot, L.P_DRV_GAIN] == 10000.0  # sim.drive_gain again
    assert m.faults() == []
    lag, v = _cruise(sim, m, 1200.0, 3.0)
    assert v / lag == pytest.approx(KV_X, rel=0.01)


def test_plc_no_ack_times_out_with_90004_although_the_plc_mode_is_auto() -> None:
    """plc.m_ack_timeout 0.3 s: the NC gives up with 90004 exactly then."""
    sim, m, _ = make(channel={"plc.m_ack_timeout": 300000})
    m.inject(PlcNoAck())
    m.submit(Mdi("M8"))
    out = m.cycle
    record(sim, 0.5)
    assert m.snapshot().plc.mode == "auto"
    timeouts = [e for e in m.events if e.code == Code.PLC_ACK_TIMEOUT]
    assert [e.cycle - out for e in timeouts] == [300]
    assert not [e for e in m.events if e.code == Code.EV_M_ACK]


def test_plc_slow_ack_acknowledges_after_its_delay_not_the_plcs() -> None:
    sim, m, _ = make(channel={"plc.m_ack_timeout": 2000000})  # 2 s
    m.inject(PlcSlowAck(0.75))
    m.submit(Mdi("M8"))
    out = m.cycle
    record(sim, 1.0)
    acks = [e for e in m.events if e.code == Code.EV_M_ACK]
    assert [e.cycle - out for e in acks] == [750]  # not plc.m_ack_delay's 20 ms
    assert not _errors(m)


def test_plc_slow_ack_in_the_middle_of_a_handshake_counts_from_the_output() -> None:
    sim, m, _ = make(channel={"plc.m_ack_timeout": 2000000})
    m.submit(PlcMode("manual"))
    m.submit(Mdi("M8"))
    out = m.cycle
    record(sim, 0.1)
    m.submit(PlcMode("auto", 1.0))  # auto again, the PLC's delay 1 s ...
    m.inject(PlcSlowAck(0.25))  # ... but the faulty program answers 0.25 s after the output
    record(sim, 0.5)
    acks = [e for e in m.events if e.code == Code.EV_M_ACK]
    assert [e.cycle - out for e in acks] == [250]


@pytest.mark.parametrize(
    ("fault", "message"),
    [
        (MotorInverted("Q"), "no axis or spindle 'Q'"),
        (DriveGainWrong("X", 0.0), "factor = 0.0"),
        (DriveGainWrong("X", -2.0), "factor = -2.0"),
        (EncoderNoise("X", float("nan")), "rms = nan"),
        (GearRatioWrong("S1", 7, 1.2), "gear = 7"),
        (GearRatioWrong("S1", 0, 1.2), "gear = 0"),
        (Backlash("X", -0.1), "width = -0.1"),
        (PlcSlowAck(0.0), "delay_s = 0.0"),
        (DriveNotReady("S1"), "reports no ready signals"),
    ],
)
def test_a_fault_with_a_value_it_cannot_have_is_refused_naming_it(
    fault: object, message: str
) -> None:
    _sim, m, _ = make()
    with pytest.raises(NcUsageError, match=message.replace("(", r"\(")):
        m.inject(fault)  # type: ignore[arg-type]
    assert m.faults() == []


def test_unknown_fault_id_and_negative_trigger_are_refused() -> None:
    _sim, m, _ = make()
    with pytest.raises(NcUsageError, match="no injected fault with id 3"):
        m.remove_fault(3)
    with pytest.raises(NcUsageError, match="after_s = -1"):
        m.inject(MotorInverted("X"), Trigger(after_s=-1.0))
    with pytest.raises(ValueError):  # NcUsageError is a ValueError
        m.remove_fault(1)


def test_faults_lists_each_with_its_trigger_and_whether_it_is_in_force() -> None:
    sim, m, _ = make()
    a = m.inject(Friction("X", 1.0))
    b = m.inject(Backlash("Z", 0.1), Trigger(after_s=0.5))
    c = m.inject(EncoderNoise("X", 0.01), Trigger(on_motion=True))
    assert (a, b, c) == (1, 2, 3)
    states = m.faults()
    assert [(s.id, s.injected_cycle, s.active_since) for s in states] == [
        (1, 20, 20),
        (2, 20, None),
        (3, 20, None),
    ]
    assert states[1].trigger == Trigger(after_s=0.5) and states[0].trigger == NOW
    sim.run(500)
    assert m.faults()[1].active_since == 520
    assert m.faults()[2].active_since is None  # X has not moved


def test_a_trigger_after_s_takes_effect_in_its_exact_cycle() -> None:
    """DriveNotReady 0.3 s after its injection: the drive follows (R_READY) up to the cycle
    before and not from that cycle's boundary on; the NC stops the moving axis in error."""
    sim, m, _ = make({"X": NO_LAG_MONITOR})
    x = m.axis("X")
    mdi(m, "G01 X100 F600")
    t0 = m.cycle
    m.inject(DriveNotReady("X"), Trigger(after_s=0.3))
    rec = record(sim, 0.5)[:, x.slot]
    ready = rec[:, L.R_READY]
    assert ready[:300].all() and not ready[300:].any()  # rows are cycles t0+1 ...
    assert m.faults()[0].active_since == t0 + 300
    assert Code.ENABLES_LOST in _errors(m) and x.state.name == "ERROR"


def _move_x(sim: Simulation, m: Machine, target: float, seconds: float = 3.0) -> None:
    mdi(m, f"G01 X{target:.4f} F1200")
    record(sim, seconds)
    assert m.axis("X").state.name == "STANDSTILL", _errors(m)


@pytest.mark.parametrize("factor", [0.5, 1.25, 2.0])
def test_encoder_resolution_wrong_moves_the_load_distance_over_factor(factor: float) -> None:
    """The NC reads factor × the true position: a 10 mm move moves the load 10/factor."""
    sim, m, _ = make({"X": NO_LAG_MONITOR})
    x = m.axis("X")
    m.inject(EncoderResolutionWrong("X", factor))
    p0, x0 = float(m.k.st[x.slot, L.S_P_ACT]), float(m.k.st[x.slot, L.S_X_MOTOR])
    _move_x(sim, m, p0 + 10.0)
    assert float(m.k.st[x.slot, L.S_P_ACT]) - p0 == pytest.approx(10.0, abs=1e-3)
    assert float(m.k.st[x.slot, L.S_X_MOTOR]) - x0 == pytest.approx(10.0 / factor, abs=1e-3)


def _noise_run(seed: int) -> np.ndarray:
    sim, m, _ = make()
    m.inject(EncoderNoise("X", 0.01, seed))
    return record(sim, 4.0)[1000:, m.axis("X").slot, L.R_P_ACT]


def test_encoder_noise_has_its_rms_at_standstill_and_the_same_seed_repeats_it() -> None:
    a = _noise_run(7)
    assert float(np.std(a)) == pytest.approx(0.01, rel=0.1)
    assert np.array_equal(a, _noise_run(7))
    assert not np.array_equal(a, _noise_run(8))


def _steady_lag_deg(sim: Simulation, m: Machine, block: str) -> float:
    mdi(m, block)
    rec = record(sim, 6.0)[-1000:, m.axis("S1").slot]
    assert not _errors(m)
    return float(rec[:, L.R_LAG].mean())


@pytest.mark.parametrize(("limit", "slope"), [(None, 3000.0), (2000.0, 2000.0)])
def test_drive_accel_limit_caps_the_run_up_and_changes_no_parameter(
    limit: float | None, slope: float
) -> None:
    """Demo S1, gear 3: M3 S3500 ramps at getriebe[2].slope_profil.a_beschl 3000 °/s². A
    drive limited to 2000 °/s² falls behind: the actual speed rises at 2000 °/s² (the
    slope over 1..3 s of the run-up), the parameters unchanged."""
    big = {f"getriebe[{i}].lag_max": 100_000_000 for i in range(3)}
    sim, m, cfg = make({"S1": big})
    lists = pickle.dumps(cfg)
    if limit is not None:
        m.inject(DriveAccelLimit("S1", limit))
    s1 = m.axis("S1")
    mdi(m, "M3 S3500")
    v = record(sim, 3.0)[:, s1.slot, L.R_V_ACT]
    assert (v[2999] - v[999]) / 2.0 == pytest.approx(slope, rel=0.01)
    assert pickle.dumps(m.cfg) == lists


def test_gear_ratio_wrong_in_gear_2_scales_the_lag_in_gear_2_only() -> None:
    """Demo S1, kv 10/s in every gear: 600 rpm = 3600 °/s gives a lag of 360°. With the
    mechanics of gear 2 (M41) 1.5 times its record's ratio, the drive turns the spindle
    1.5 times slower per digit there: the lag is 1.5 · v/kv in gear 2, v/kv in gear 3."""
    big = {f"getriebe[{i}].lag_max": 100_000_000 for i in range(3)}
    sim, m, cfg = make({"S1": big})
    lists = pickle.dumps(cfg)
    m.inject(GearRatioWrong("S1", 2, 1.5))
    assert m.axis("S1").gear == 3
    assert _steady_lag_deg(sim, m, "M3 S1000") == pytest.approx(6000.0 / 10.0, rel=0.01)
    assert _steady_lag_deg(sim, m, "M3 S600") == pytest.approx(1.5 * 3600.0 / 10.0, rel=0.01)
    assert m.axis("S1").gear == 2
    assert _steady_lag_deg(sim, m, "M3 S1000") == pytest.approx(6000.0 / 10.0, rel=0.01)
    assert pickle.dumps(m.cfg) == lists


def test_friction_adds_v_loss_over_kv_to_the_steady_lag() -> None:
    """The drive loses v_loss against the motion: the loop needs kv·lag = v + v_loss."""
    sound_lag, _ = _cruise(*make({"X": NO_LAG_MONITOR | IDEAL})[:2], 1200.0, 3.0)
    sim, m, _ = make({"X": NO_LAG_MONITOR | IDEAL})
    m.inject(Friction("X", 4.0))
    lag, v = _cruise(sim, m, 1200.0, 3.0)
    assert v == pytest.approx(20.0, rel=1e-3)
    assert lag - sound_lag == pytest.approx(4.0 / KV_X, rel=0.01)


def test_friction_sticks_a_command_below_it() -> None:
    sim, m, _ = make({"X": IDEAL})
    x = m.axis("X")
    m.inject(Friction("X", 2.0))
    x0 = float(m.k.st[x.slot, L.S_X_MOTOR])
    mdi(m, f"G01 X{float(m.k.st[x.slot, L.S_P_CMD]) + 0.01:.4f} F6")  # 0.1 mm/s, lag 5 µm
    record(sim, 0.5)
    assert float(m.k.st[x.slot, L.S_X_MOTOR]) == x0  # kv·lag never beats 2 mm/s


def test_backlash_leaves_the_motor_its_width_apart_after_a_reversal() -> None:
    """The encoder reads the load: reaching one NC position from below and from above, the
    load stands at the same place and the motor is the play's width apart."""
    b = 0.2
    sim, m, _ = make({"X": IDEAL})
    x = m.axis("X")
    m.inject(Backlash("X", b))
    p0 = float(m.k.st[x.slot, L.S_P_ACT])
    motor: list[float] = []
    load: list[float] = []
    for approach in (-5.0, +5.0):
        _move_x(sim, m, p0 + approach)
        _move_x(sim, m, p0)
        motor.append(float(m.k.st[x.slot, L.S_X_MOTOR] + m.k.st[x.slot, L.S_PLAY]))
        load.append(float(m.k.st[x.slot, L.S_X_MOTOR]))
    assert load[0] == pytest.approx(load[1], abs=2e-3)
    assert motor[0] - motor[1] == pytest.approx(b, abs=2e-3)


def test_enable_drop_stops_the_moving_axis_after_s_into_its_motion() -> None:
    sim, m, _ = make({"X": NO_LAG_MONITOR})
    x = m.axis("X")
    m.inject(EnableDrop("X"), Trigger(after_s=0.2, on_motion=True))
    sim.run(100)
    assert x.units["TorquePermission"] == 1 and m.faults()[0].active_since is None
    mdi(m, "G01 X100 F600")
    start = m.cycle
    rec = record(sim, 0.5)[:, x.slot]
    assert not rec[200:, L.R_READY].any() and rec[:200, L.R_READY].all()
    assert m.faults()[0].active_since == start + 200
    assert _errors(m) == [Code.ENABLES_LOST] and x.state.name == "ERROR"
    assert x.units["TorquePermission"] == 0
    m.remove_fault(1)  # the PLC program gives the enable back
    assert x.units["TorquePermission"] == 1


def test_enable_drop_now_drops_at_the_next_motion() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    m.inject(EnableDrop("X"))
    sim.run(300)
    assert x.units["TorquePermission"] == 1
    mdi(m, "G01 X100 F600")
    assert x.units["TorquePermission"] == 0 and _errors(m) == [Code.ENABLES_LOST]


def test_drive_not_ready_stops_the_moving_axis_and_refuses_motion_with_90007() -> None:
    sim, m, _ = make({"X": NO_LAG_MONITOR})
    x = m.axis("X")
    mdi(m, "G01 X100 F600")
    record(sim, 0.2)
    fid = m.inject(DriveNotReady("X"))
    record(sim, 0.2)
    assert _errors(m) == [Code.ENABLES_LOST] and x.state.name == "ERROR"
    assert "X: ready_for_power_on, ready_for_control_loop_on off" in m.events[-1].message
    assert x.drive.missing() == ["ready_for_power_on", "ready_for_control_loop_on"]
    m.remove_fault(fid)
    assert x.drive.missing() == []
