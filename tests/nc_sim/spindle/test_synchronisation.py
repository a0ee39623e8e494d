"""How a block waits for its spindle, as the spindle manual [000 §2.5, §2.7, §2.8.2] gives it:
speed reached before the path (MVS_SVS) also when a turning spindle gets a new speed, G74
homing beside the path, the automatic gear change's synchronisation (m_synch[40..45]).
Numbers from the manual's examples on the demo lathe, in simulated time."""

from __future__ import annotations

import numpy as np
import pytest

from tests.nc_sim.sim_helpers import L, run_program

RPM = 6.0  # °/s per rpm
MVS_SVS, MOS = 0x2, 0x1


def _first(mask: np.ndarray) -> int:
    idx = np.flatnonzero(mask)
    assert idx.size, "condition never met"
    return int(idx[0])


@pytest.mark.parametrize("plc_info", [0, 0x20000], ids=["internal", "plc_info"])
def test_the_path_waits_for_each_new_speed_of_a_turning_spindle(plc_info: int) -> None:
    # 000 §2.5.2, example 2: s_synch MVS_SVS, m3_synch MOS. "N20 ... S500: path motion only
    # starts when spindle speed is reached; N30 S100 X0 Y0: path waits before executing
    # motion until spindle speed is reached" (here on the lathe's X and Z)
    program = "N10 M3 G0 X50 Z-100\nN20 G1 X60 Z-90 F1500 S500\nN30 S100 X50 Z-100\nM30\n"
    channel = {"spindel[0].s_synch": MVS_SVS | plc_info, "spindel[0].m3_synch": MOS}
    _sim, m, rec = run_program(program, 6.0, channel=channel)
    x, s = m.axis("X").slot, m.axis("S1").slot
    vx, rpm = rec[:, x, L.R_V_CMD], rec[:, s, L.R_V_ACT] / RPM
    band = 0.10  # "speed reached": within kenngr.vb_prozent = 100 (0.1 %) of the demo spindle
    # the path starts in the cycle after the one that found the speed reached
    n20 = _first(vx > 1e-9) - 1  # X leaves 50 for 60
    assert rec[n20, s, L.R_SPEED_REACHED] == 1
    assert rpm[n20] == pytest.approx(500.0, rel=band)
    n30 = n20 + _first(vx[n20:] < -1e-9) - 1  # and comes back
    assert rec[n30, s, L.R_SPEED_REACHED] == 1
    assert rpm[n30] == pytest.approx(100.0, rel=band)  # not still about 500


# a slow homing speed for the spindle in every gear stage (1 rpm, in 0.001°/s): its homing
# takes seconds
SLOW_SPINDLE_HOMING = {
    "S1": {f"getriebe[{g}].vb_{v}": 6000 for g in range(6) for v in ("reflow", "refmax")}
}


def _done(rec: np.ndarray, slot: int) -> int:
    """The cycle after the last one in which the axis was commanded to move."""
    return int(np.flatnonzero(np.abs(rec[:, slot, L.R_V_CMD]) > 1e-9)[-1]) + 1


def test_g74_s1_homes_the_spindle_while_the_program_goes_on() -> None:
    # 000 §2.7, example 2: "N10 G74 S1 / N15 G74 X1 Y2: the system continues to the next NC
    # block without waiting until the spindle is referenced so that the X axis is referenced
    # quasi simultaneously" (Z for Y on the lathe)
    _sim, m, rec = run_program("N10 G74 S1\nN15 G74 X1 Z2\nM30\n", 8.0, SLOW_SPINDLE_HOMING)
    x, s = m.axis("X").slot, m.axis("S1").slot
    x_starts = _first(np.abs(rec[:, x, L.R_V_CMD]) > 1e-9)
    assert x_starts < 10  # at once, not after the spindle's seconds
    assert _done(rec, s) > 1000


def test_a_g74_block_with_the_spindle_ends_when_its_axes_are_homed() -> None:
    # 000 §2.7, example 1: "N10 G74 X2 Y1 S1: homing the spindle starts simultaneously with Y
    # axis homing", and is otherwise not synchronised: X follows Z (its order 2 after 1)
    # and N20 follows X without waiting for the spindle
    program = "N10 G74 X2 Z1 S1\nN20 G01 Z-50 F3000\nM30\n"
    _sim, m, rec = run_program(program, 12.0, SLOW_SPINDLE_HOMING)
    x, z, s = m.axis("X").slot, m.axis("Z").slot, m.axis("S1").slot
    s_starts = _first(np.abs(rec[:, s, L.R_V_CMD]) > 1e-9)
    z_starts = _first(np.abs(rec[:, z, L.R_V_CMD]) > 1e-9)
    assert s_starts == z_starts  # together
    x_homed = _first(rec[:, x, L.R_HOMED] == 1)
    n20 = x_homed + _first(rec[x_homed:, z, L.R_P_CMD] < rec[x_homed, z, L.R_P_CMD] - 1e-6)
    assert rec[-1, z, L.R_P_CMD] == pytest.approx(-50.0)  # N20 ran
    assert n20 < _done(rec, s)  # while the spindle still homed


# 000 §2.8.2, configuration example: "m_synch[40] 0x00000002 MVS_SVS … m_synch[45] MVS_SVS"
GEAR_CHANGES_SYNCHRONISED = {f"m_synch[{m}]": MVS_SVS for m in range(40, 46)}


@pytest.mark.parametrize("synchronised", [False, True])
def test_the_gear_change_of_a_lone_s_waits_as_its_m_synch_says(synchronised: bool) -> None:
    # S950 leaves M41 (400-800 rpm) for M42 (700-3500 rpm); the demo's s_synch is MOS
    program = "M3 S650\nS950 G01 X60 F1000\nM30\n"
    channel = GEAR_CHANGES_SYNCHRONISED if synchronised else {}
    _sim, m, rec = run_program(program, 8.0, channel=channel)
    x, s = m.axis("X").slot, m.axis("S1").slot
    assert rec[-1, s, L.R_GEAR] == 3 and rec[-1, x, L.R_P_CMD] == pytest.approx(60.0)
    in_m41 = _first(rec[:, s, L.R_GEAR] == 2)  # M3 S650 first (the demo powers on in M42)
    gear_changed = in_m41 + _first(rec[in_m41:, s, L.R_GEAR] == 3)
    x_starts = _first(np.abs(rec[:, x, L.R_V_CMD]) > 1e-9)
    if synchronised:  # MVS_SVS: before the motion of its block
        assert x_starts > gear_changed
    else:  # in the background: the path does not wait for it
        assert x_starts < gear_changed


@pytest.mark.parametrize(("m19_synch", "spindle_first"), [(MVS_SVS, True), (0x8, False)])
def test_m19_in_a_motion_block_goes_before_or_after_it_as_m19_synch_says(
    m19_synch: int, spindle_first: bool
) -> None:
    # P-CHAN-00043 spindel[i].m19_synch [000 §2.5]: MVS_SVS orients before the block's
    # motion and the path waits for it in position; MNS_SNS (the demo's) after the motion
    channel = {"spindel[0].m19_synch": m19_synch}
    _sim, m, rec = run_program("M19 S.POS=90 G01 X60 F1000\nM30\n", 8.0, channel=channel)
    x, s = m.axis("X").slot, m.axis("S1").slot
    x_moves = np.flatnonzero(np.abs(rec[:, x, L.R_V_CMD]) > 1e-9)
    s_moves = np.flatnonzero(np.abs(rec[:, s, L.R_V_CMD]) > 1e-9)
    assert rec[-1, s, L.R_P_CMD] % 360.0 == pytest.approx(90.0)
    if spindle_first:
        assert s_moves[-1] < x_moves[0]
    else:
        assert x_moves[-1] < s_moves[0]
