"""G63 tapping and G33 thread cutting on the demo lathe, in simulated time [000 §2.8.6-2.8.7].

The numbers are the manual's: F = S × pitch (200 rpm × 1.25 mm = 250 mm/min), the M70×1.5
thread in four passes at X 69.54 / 69.08 / 68.62 / 68.16 (diameters, G51) and its two-start
variant with S.OFFSET=180. Ratios are measured from actual positions (encoder of the spindle,
encoder of Z), never from the coupling's own numbers.
"""

from __future__ import annotations

import numpy as np
import pytest

from nc_sim.commands import Accepted, CycleStart, EmergencyStop, Feedhold, ProgramLoad
from nc_sim.errors import Code
from nc_sim.machine.machine import Machine
from nc_sim.snapshot import ChannelState
from tests.nc_sim.sim_helpers import L, make, record, run_program

RPM = 6.0  # °/s per rpm


run = run_program


def actual(m: Machine, rec: np.ndarray, name: str) -> np.ndarray:
    return rec[:, m.axis(name).slot, L.R_P_ACT]


def lines(m: Machine, rec: np.ndarray) -> np.ndarray:
    return rec[:, m.channel_slot, L.R_LINE]


def angle_at(z: np.ndarray, theta: np.ndarray, z_mark: float, rows: np.ndarray) -> float:
    """Spindle angle (mod 360) when Z passes `z_mark` going down, within `rows`."""
    zs, ths = z[rows], theta[rows]
    j = int(np.argmax(zs <= z_mark))
    assert j > 0 and zs[j] <= z_mark < zs[j - 1]
    f = (zs[j - 1] - z_mark) / (zs[j - 1] - zs[j])
    return float((ths[j - 1] + f * (ths[j] - ths[j - 1])) % 360.0)


def ratio(z: np.ndarray, theta: np.ndarray, rows: np.ndarray) -> float:
    """dZ/dθ over `rows`, mm per revolution."""
    return float((z[rows[-1]] - z[rows[0]]) / (theta[rows[-1]] - theta[rows[0]]) * 360.0)


# --- G63 -----------------------------------------------------------------------------------

TAP = """G01 F2000 G90 X10 Z0
M19 S.POS=0
G63 Z-50 F250 S200
Z0 S-200
G01 F1000 X100
M30
"""


def test_the_manuals_tap_runs_at_f_equal_s_times_pitch_and_retracts_in_the_same_thread() -> None:
    _sim, m, rec = run(TAP, 40.0)
    z, th = actual(m, rec, "Z"), actual(m, rec, "S1")
    line = lines(m, rec)
    down, up = np.where(line == 3)[0], np.where(line == 4)[0]
    assert len(down) and len(up)
    # 50 mm at 1.25 mm per revolution: 40 revolutions in, 40 out
    assert z[down[-1]] == pytest.approx(-50.0, abs=0.01)
    assert th[down[-1]] - th[down[0]] == pytest.approx(40 * 360.0, abs=1.0)
    assert th[up[-1]] - th[up[0]] == pytest.approx(-40 * 360.0, abs=1.0)
    # at full speed: 200 rpm, 250 mm/min, dZ/dθ = 1.25 mm per revolution within 1 %
    steady = down[(z[down] < -15.0) & (z[down] > -35.0)]
    span_s = (steady[-1] - steady[0]) * m.k.cycle_s  # mean speeds over the window (secants)
    assert (z[steady[0]] - z[steady[-1]]) / span_s * 60.0 == pytest.approx(250.0, rel=0.01)
    assert (th[steady[-1]] - th[steady[0]]) / span_s / RPM == pytest.approx(200.0, rel=0.01)
    assert ratio(z, th, steady) == pytest.approx(-1.25, rel=0.01)
    back = up[(z[up] > -35.0) & (z[up] < -15.0)]
    assert ratio(z, th, back) == pytest.approx(-1.25, rel=0.01)  # S-200: same thread, out
    # through the ramps as well: the tap follows the spindle's actual angle, never a plan
    z_cmd = rec[:, m.axis("Z").slot, L.R_P_CMD]
    follow = z_cmd[down[1:]] - (0.0 - 1.25 / 360.0 * (th[down[:-1]] - th[down[0] - 1]))
    assert np.abs(follow).max() < 0.002
    assert m.channel.state is ChannelState.READY  # M30 reached
    assert not [e for e in m.events if e.error]


def test_a_tap_with_the_spindle_turning_is_refused_with_its_line() -> None:
    _sim, m, _rec = run("M3 S300\nG63 Z-20 F300 S200\nM30\n", 3.0)
    assert m.channel.state is ChannelState.ERROR
    err = m.channel.progress.error
    assert err is not None and err.code == Code.TAPPING_NOT_POSSIBLE and err.line == 2
    assert "M5 or M19" in err.message


def test_an_emergency_stop_during_a_tap_brakes_the_spindle_and_the_axis() -> None:
    sim, m, _cfg = make()
    assert isinstance(
        m.submit(ProgramLoad("t", "M19 S.POS=0\nG63 Z-150 F300 S200\nM30\n")), Accepted
    )
    m.submit(CycleStart())
    sim.run(4000)
    assert m.axis("S1").state.name == "MOVING"
    m.submit(EmergencyStop())
    rec = record(sim, 2.0)
    assert abs(rec[-1, m.axis("S1").slot, L.R_V_CMD]) < 1e-9
    assert abs(rec[-1, m.axis("Z").slot, L.R_V_CMD]) < 1e-9
    assert m.channel.state is ChannelState.ERROR


# --- G33 -----------------------------------------------------------------------------------

# the manual's program (000 §2.8.7); the manual names its subprogram `longit_thread` but
# calls `longitudinal thread`: one name here
LONGITUDINAL = """%L longitudinal thread
N100 G33 Z48 K1.5 ;Cut thread turn
N110 G00 X72 ;Retract and move
N120 Z105 ;to start position
N130 M29 ;Subroutine end
%G33 (thread depth 0.92 mm)
N10 G51 ;Select diameter programming
N15 T1 D1 M03 S400 ;Select tool, start spindle
N20 G00 X72 Z105 ;Approach
N25 G01 X69.54 F1000 ;Position at 1st cutting depth
N30 LL longitudinal thread ;1st thread cut
N35 G01 X69.08 ;Position at 2nd cutting depth
N30 LL longitudinal thread ;2nd thread cut
N35 G01 X68.62 ;Position at 3rd cutting depth
N30 LL longitudinal thread ;3rd thread cut
N35 G01 X68.16 ;Position at final depth
N30 LL longitudinal thread ;4th thread cut
N35 G01 X68.16 ;Reposition at final depth
N30 LL longitudinal thread ;Empty cut
N60 M05 X150 Z200 ;Moving to end position
N65 M30 ;Program end
"""


def passes(m: Machine, rec: np.ndarray, program: str) -> list[np.ndarray]:
    """Rows of each G33 pass, in order (the G33 block's line)."""
    g33 = [
        i + 1
        for i, text in enumerate(program.splitlines())
        if text.startswith("N") and "G33" in text
    ]
    line = lines(m, rec)
    rows = np.where(np.isin(line, g33))[0]
    splits = np.where(np.diff(rows) > 1)[0] + 1
    return [r for r in np.split(rows, splits) if len(r)]


def test_the_manuals_m70x1_5_thread_cuts_every_pass_in_the_same_groove() -> None:
    _sim, m, rec = run(LONGITUDINAL, 60.0)
    assert not [e for e in m.events if e.error]
    z, th, x = actual(m, rec, "Z"), actual(m, rec, "S1"), actual(m, rec, "X")
    cuts = passes(m, rec, LONGITUDINAL)
    assert len(cuts) == 5  # four cuts and the empty cut
    # G51: the diameters 69.54 ... 68.16 are radii 34.77 ... 34.08 on the machine's X
    # each cut starts after the exact stop: X stands within its window (kenngr.exact_stop_window)
    window = m.axis("X").cfg.eng("kenngr.exact_stop_window")
    for rows, radius in zip(cuts, (34.77, 34.54, 34.31, 34.08, 34.08), strict=True):
        assert np.abs(x[rows] - radius).max() <= window
    # each pass meets the groove: Z passes 90, 70 and 55 at the same spindle angle
    for z_mark in (90.0, 70.0, 55.0):
        angles = [angle_at(z, th, z_mark, rows) for rows in cuts]
        spread = max(abs((a - angles[0] + 180.0) % 360.0 - 180.0) for a in angles)
        assert spread < 0.5, (z_mark, angles)  # 0.5° of 1.5 mm: 2 µm
    # synchronised part: 1.5 mm per revolution within 1 %, from actual positions
    for rows in cuts:
        sync = rows[(z[rows] < 95.0) & (z[rows] > 55.0)]
        assert ratio(z, th, sync) == pytest.approx(-1.5, rel=0.01)


TWO_START = """N10 G51
N15 M03 S40
N20 G00 X72 Z105
N25 G01 X68.16 F1000
N30 G33 Z48 K1.5
N35 G00 X72
N40 Z105
N45 G01 X68.16
N50 G33 Z48 K1.5 S.OFFSET=180
N55 G00 X72
N60 M05 X150 Z200
N65 M30
"""


def test_the_second_start_of_a_two_start_thread_is_half_a_turn_later() -> None:
    # the manual's S40 lies below the demo's lowest gear range (50-560 rpm): open it to 40
    _sim, m, rec = run(TWO_START, 130.0, channel={"spindel[0].range_table[0].min_speed": 40})
    assert not [e for e in m.events if e.error]
    z, th = actual(m, rec, "Z"), actual(m, rec, "S1")
    first, second = passes(m, rec, TWO_START)
    for z_mark in (95.0, 75.0, 55.0):
        a, b = angle_at(z, th, z_mark, first), angle_at(z, th, z_mark, second)
        assert (b - a) % 360.0 == pytest.approx(180.0, abs=0.5)
    for rows in (first, second):
        sync = rows[(z[rows] < 95.0) & (z[rows] > 55.0)]
        assert ratio(z, th, sync) == pytest.approx(-1.5, rel=0.01)


def test_a_thread_without_a_rotating_spindle_is_refused() -> None:
    _sim, m, _rec = run("G00 X40 Z5\nG33 Z-20 K2\nM30\n", 3.0)
    err = m.channel.progress.error
    assert err is not None and err.code == Code.THREAD_NOT_POSSIBLE and err.line == 2
    assert "M3/M4 first" in err.message


def test_a_thread_faster_than_the_axis_is_refused_naming_both_feeds() -> None:
    # 3000 rpm × 15 mm = 45 m/min, Z allows 30 m/min (vb_max)
    _sim, m, _rec = run("M3 S3000\nG33 Z-200 K15\nM30\n", 12.0)
    err = m.channel.progress.error
    assert err is not None and err.code == Code.THREAD_NOT_POSSIBLE
    assert "45000.0 mm/min" in err.message and "30000.0 mm/min" in err.message


def test_feedhold_during_a_thread_holds_after_it() -> None:
    sim, m, _cfg = make()
    program = "M3 S400\nG00 X40 Z5\nG33 Z-40 K1.5\nG00 X60\nM30\n"
    assert isinstance(m.submit(ProgramLoad("t", program)), Accepted)
    m.submit(CycleStart())
    rec = record(sim, 30.0)
    started = int(np.argmax(lines(m, rec) == 3))
    assert started > 0
    sim2, m2, _ = make()
    assert isinstance(m2.submit(ProgramLoad("t", program)), Accepted)
    m2.submit(CycleStart())
    sim2.run(started + 1500)  # into the thread
    m2.submit(Feedhold(True))
    sim2.run(20000)
    z = m2.k.st[m2.axis("Z").slot, L.S_P_ACT]
    assert z == pytest.approx(-40.0, abs=0.01)  # the thread ran to its end
    assert m2.channel.state is ChannelState.HELD
    assert m2.k.st[m2.axis("X").slot, L.S_P_CMD] == pytest.approx(40.0)  # X60 waits
