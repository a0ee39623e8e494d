"""The channel runs programs: path interpolation, look-ahead, modal words, synchronisation,
feedhold and single block, on the demo lathe in simulated time. Expected numbers come from
geometry (lines, circles) and the axis parameters, never from our own output."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc_sim.commands import (
    Accepted,
    CycleStart,
    Feedhold,
    Invalid,
    JogStep,
    ProgramLoad,
    ProgramStop,
    Refused,
    SingleBlock,
)
from nc_sim.errors import Code
from nc_sim.machine.machine import Machine
from nc_sim.snapshot import ChannelState
from tests.nc_sim.sim_helpers import L, make, record, run_program

# the demo lathe starts at X50 Z-100 (both unhomed: no software limits yet)
X0, Z0 = 50.0, -100.0


run = run_program


def cols(m: Machine, rec: np.ndarray, col: int) -> tuple[np.ndarray, np.ndarray]:
    x, z = m.axis("X"), m.axis("Z")
    return rec[:, x.slot, col], rec[:, z.slot, col]


def test_a_straight_line_moves_both_axes_at_path_feed_and_they_arrive_together() -> None:
    _sim, m, rec = run("G01 X90 Z-80 F600\nM30\n", 8.0)
    px, pz = cols(m, rec, L.R_P_CMD)
    vx, vz = cols(m, rec, L.R_V_CMD)
    speed = np.hypot(vx, vz) * 60.0
    assert speed.max() == pytest.approx(600.0, rel=1e-9)  # the path feed, not 600 per axis
    # every commanded point on the line from (50, -100) to (90, -80): 20·(x-50) = 40·(z+100)
    assert np.abs(20.0 * (px - X0) - 40.0 * (pz - Z0)).max() < 1e-9
    arrive_x = int(np.argmax(np.abs(px - 90.0) < 1e-9))
    arrive_z = int(np.argmax(np.abs(pz + 80.0) < 1e-9))
    assert arrive_x == arrive_z > 0
    # 44.72 mm at 10 mm/s plus the ramps: not the X-alone time of 40 mm at 10 mm/s
    assert arrive_x * 0.001 > math.hypot(40, 20) / 10.0


def test_every_commanded_point_of_an_arc_lies_on_its_circle() -> None:
    # G18 (lathe): Z horizontal, X vertical; from X50 Z-100 a half circle about Z-90 X50
    _sim, m, rec = run("G18 G03 X50 Z-80 K10 F1200\nM30\n", 6.0)
    px, pz = cols(m, rec, L.R_P_CMD)
    radius = np.hypot(pz + 90.0, px - 50.0)
    assert np.abs(radius - 10.0).max() < 1e-6  # within 1 µm
    # G03 seen from +Y: from Z-100 counter-clockwise through X40 (sampled every cycle)
    assert px.min() == pytest.approx(40.0, abs=1e-4)
    assert px.max() == pytest.approx(50.0, abs=1e-9)
    assert pz[-1] == pytest.approx(-80.0, abs=1e-9)


def test_the_weakest_axis_limits_path_velocity_and_acceleration() -> None:
    # Z: 12 m/min (vb_max 200000 µm/s) and 500 mm/s²; X: 30 m/min and 2000 mm/s². A 45° line
    # at F30000 runs with Z at its limits and X just as fast (the path stays straight)
    weak_z = {
        "getriebe[0].dynamik.vb_max": 200000,
        "getriebe[0].vb_eilgang": 200000,
        "getriebe[0].slope_profil.a_beschl": 500,
        "getriebe[0].slope_profil.a_brems": 500,
    }
    _sim, m, rec = run("G01 X150 Z0 F30000\nM30\n", 6.0, axes={"Z": weak_z})
    vx, vz = cols(m, rec, L.R_V_CMD)
    ax, az = cols(m, rec, L.R_A_CMD)
    assert np.abs(vz).max() * 60 == pytest.approx(12000.0, rel=1e-9)
    assert np.abs(vx).max() == pytest.approx(np.abs(vz).max(), rel=1e-9)
    assert max(np.abs(ax).max(), np.abs(az).max()) <= 500 * (1 + 1e-9)
    assert np.abs(az).max() == pytest.approx(500.0, rel=1e-6)


def test_modal_words_carry_over_from_block_to_block() -> None:
    # G01 and F stay in force: the bare X70 runs at 500 mm/min, not at rapid
    _sim, m, rec = run("G01 X60 F500\nX70\nM30\n", 5.0)
    vx, _vz = cols(m, rec, L.R_V_CMD)
    lines = rec[:, m.channel_slot, L.R_LINE]
    assert np.abs(vx[lines == 2]).max() * 60 == pytest.approx(500.0, rel=1e-9)


def test_lookahead_does_not_stop_between_collinear_blocks() -> None:
    _sim, m, rec = run("G01 X60 F600\nX70\nX80\nM30\n", 5.0)
    vx, _vz = cols(m, rec, L.R_V_CMD)
    v = vx * 60.0
    at_feed = np.flatnonzero(np.abs(v - 600.0) < 1e-6)
    cruise = v[at_feed[0] : at_feed[-1] + 1]
    assert cruise.min() == pytest.approx(600.0, rel=1e-9)  # through both block ends
    lines = rec[:, m.channel_slot, L.R_LINE]
    assert {1, 2, 3} <= set(lines[at_feed[0] : at_feed[-1] + 1].astype(int))


def test_a_right_angle_corner_slows_to_the_transition_speed() -> None:
    # X then Z: each axis' velocity jumps by the whole path speed at the corner; with
    # a_trans_weight 0 the allowed jump per cycle is a · cycle / ramp time [002 §2.3.1]
    _sim, m, rec = run("G01 X60 F3000\nZ-90\nM30\n", 5.0)
    vx, vz = cols(m, rec, L.R_V_CMD)
    speed = np.hypot(vx, vz)
    lines = rec[:, m.channel_slot, L.R_LINE]
    corner = int(np.argmax(lines == 2))
    a, tr, cycle = 2000.0, 0.020, 0.001
    v_corner = a * cycle / tr * cycle  # mm/s: (a · cycle/tr) · cycle
    assert speed[corner - 1 : corner + 1].min() <= v_corner + a * cycle
    assert speed.max() * 60 == pytest.approx(3000.0, rel=1e-9)


def test_m3_holds_the_path_until_speed_reached() -> None:
    # NO_SYNCH on M3 still synchronises internally on speed reached [000 §2.5.1]
    _sim, m, rec = run("M3 S1000 G01 X60 F1000\nM30\n", 6.0)
    s1 = m.axis("S1")
    vx, _vz = cols(m, rec, L.R_V_CMD)
    first_move = int(np.argmax(np.abs(vx) > 0))
    reached = int(np.argmax(rec[:, s1.slot, L.R_SPEED_REACHED] > 0))
    assert 0 < reached <= first_move


def test_m3_with_mos_does_not_hold_the_path() -> None:
    _sim, m, rec = run("M3 S1000 G01 X60 F1000\nM30\n", 3.0, channel={"spindel[0].m3_synch": 0x1})
    s1 = m.axis("S1")
    vx, _vz = cols(m, rec, L.R_V_CMD)
    first_move = int(np.argmax(np.abs(vx) > 0))
    reached = int(np.argmax(rec[:, s1.slot, L.R_SPEED_REACHED] > 0))
    assert first_move < reached


def test_feedhold_stops_on_the_path_and_release_finishes_it() -> None:
    sim, m, _cfg = make()
    m.submit(ProgramLoad("hold", "G01 X90 Z-80 F1200\nM30\n"))
    m.submit(CycleStart())
    record(sim, 1.0)
    m.submit(Feedhold(True))
    rec = record(sim, 1.0)
    px, pz = cols(m, rec, L.R_P_CMD)
    vx, vz = cols(m, rec, L.R_V_CMD)
    assert m.channel.state is ChannelState.HELD
    assert vx[-1] == vz[-1] == 0.0
    assert px[-1] < 90.0 - 1.0  # stopped short of the end
    assert np.abs(20.0 * (px - X0) - 40.0 * (pz - Z0)).max() < 1e-9  # on the line
    m.submit(Feedhold(False))
    rec = record(sim, 4.0)
    px, pz = cols(m, rec, L.R_P_CMD)
    assert (px[-1], pz[-1]) == (pytest.approx(90.0), pytest.approx(-80.0))
    state: ChannelState = m.channel.state
    assert state is ChannelState.READY  # M30: ready for the next cycle start


def test_single_block_stops_at_each_block_end() -> None:
    sim, m, _cfg = make()
    m.submit(SingleBlock(True))
    m.submit(ProgramLoad("sb", "G01 X60 F1200\nX70\nM30\n"))
    m.submit(CycleStart())
    rec = record(sim, 2.0)
    px, _pz = cols(m, rec, L.R_P_CMD)
    assert m.channel.state is ChannelState.BLOCK_END
    assert px[-1] == pytest.approx(60.0)
    m.submit(CycleStart())
    rec = record(sim, 2.0)
    px, _pz = cols(m, rec, L.R_P_CMD)
    assert px[-1] == pytest.approx(70.0)


def test_a_bad_program_is_refused_with_line_and_column() -> None:
    _sim, m, _cfg = make()
    out = m.submit(ProgramLoad("bad", "G01 X60 F100\nG01 X70 Q5\nM30\n"))
    assert isinstance(out, Invalid)
    assert (out.line, out.column) == (2, 9)
    assert m.channel.state is ChannelState.IDLE


def test_g60_stops_the_path_at_its_block_end_only() -> None:
    _sim, m, rec = run("G01 X60 F600\nG60 X70\nX80\nM30\n", 5.0)
    vx, _vz = cols(m, rec, L.R_V_CMD)
    px, _pz = cols(m, rec, L.R_P_CMD)
    moving = np.abs(vx) > 0
    between_1_2 = (px > 59.0) & (px < 61.0)
    between_2_3 = (px > 69.0) & (px < 71.0)
    assert np.abs(vx[between_1_2]).min() == pytest.approx(10.0)  # X60: carried on at F
    # G60: the speed falls to rest at X70 (sampled once a cycle: within the first cycle of
    # jerk j = a/tr after rest, v ≤ j·cycle²/2 = 0.05 mm/s)
    assert np.abs(vx[between_2_3]).min() < 0.05 + 1e-9
    assert moving.any()
    assert px[-1] == pytest.approx(80.0)


def test_single_block_switched_on_during_a_run_stops_at_the_end_of_that_block() -> None:
    sim, m, _cfg = make()
    m.submit(ProgramLoad("sb", "G01 X60 F600\nX70\nX80\nM30\n"))
    m.submit(CycleStart())
    record(sim, 0.5)  # in the first block (X50 -> X60 at 10 mm/s)
    m.submit(SingleBlock(True))
    rec = record(sim, 3.0)
    px, _pz = cols(m, rec, L.R_P_CMD)
    assert m.channel.state is ChannelState.BLOCK_END
    assert px[-1] == pytest.approx(60.0)  # the end of the block it was in
    m.submit(CycleStart())
    rec = record(sim, 3.0)
    px, _pz = cols(m, rec, L.R_P_CMD)
    assert px[-1] == pytest.approx(70.0)
    m.submit(SingleBlock(False))
    m.submit(CycleStart())
    rec = record(sim, 3.0)
    px, _pz = cols(m, rec, L.R_P_CMD)
    assert px[-1] == pytest.approx(80.0)


def test_stop_brakes_on_the_path_and_gives_the_axes_back() -> None:
    sim, m, _cfg = make()
    m.submit(ProgramLoad("stop", "G01 X90 Z-80 F1200\nM30\n"))
    m.submit(CycleStart())
    record(sim, 1.0)
    m.submit(ProgramStop())
    rec = record(sim, 1.0)
    px, pz = cols(m, rec, L.R_P_CMD)
    assert np.abs(20.0 * (px - X0) - 40.0 * (pz - Z0)).max() < 1e-9  # braked on the line
    assert px[-1] < 90.0 - 1.0
    assert m.channel.state is ChannelState.READY
    x = m.axis("X")
    assert x.state.name == "STANDSTILL"
    assert isinstance(m.submit(JogStep("X", 1.0)), Accepted)  # the axis is free again
    rec = record(sim, 2.0)
    assert rec[-1, x.slot, L.R_P_CMD] == pytest.approx(px[-1] + 1.0)


def test_stop_in_feedhold_ends_the_run_where_it_holds_and_nothing_moves_afterwards() -> None:
    """Stop while held: the path is at rest, so the axes are given back at once; releasing
    feedhold or switching single block must not run the rest of the stopped block."""
    sim, m, _cfg = make()
    m.submit(ProgramLoad("stop", "G01 X90 Z-80 F1200\nM30\n"))
    m.submit(CycleStart())
    record(sim, 1.0)
    m.submit(Feedhold(True))
    record(sim, 1.0)
    m.submit(ProgramStop())
    x, z = m.axis("X"), m.axis("Z")
    held_at = (m.k.st[x.slot, L.S_P_CMD], m.k.st[z.slot, L.S_P_CMD])
    assert x.state.name == z.state.name == "STANDSTILL"
    m.submit(Feedhold(False))
    m.submit(SingleBlock(True))
    rec = record(sim, 2.0)
    assert np.all(rec[:, x.slot, L.R_V_CMD] == 0.0) and np.all(rec[:, z.slot, L.R_V_CMD] == 0.0)
    assert (m.k.st[x.slot, L.S_P_CMD], m.k.st[z.slot, L.S_P_CMD]) == held_at
    assert isinstance(m.submit(CycleStart()), Accepted)  # a new run may start


def test_cycle_start_under_feedhold_waits_held_and_runs_when_it_is_released() -> None:
    sim, m, _cfg = make()
    x = m.axis("X")
    m.submit(Feedhold(True))
    m.submit(ProgramLoad("fh", "G01 X60 F1200\nM30\n"))
    assert isinstance(m.submit(CycleStart()), Accepted)
    rec = record(sim, 1.0)
    assert m.channel.state is ChannelState.HELD and np.all(rec[:, x.slot, L.R_V_CMD] == 0.0)
    refused = m.submit(CycleStart())
    assert isinstance(refused, Refused) and refused.code == Code.FEEDHOLD_ACTIVE
    m.submit(Feedhold(False))
    record(sim, 3.0)
    state: ChannelState = m.channel.state  # (mypy narrowed it to HELD above)
    assert m.k.st[x.slot, L.S_P_CMD] == pytest.approx(60.0) and state is ChannelState.READY


def test_a_job_error_during_a_run_names_the_line_and_mdi_keeps_the_programs_modal_words() -> None:
    """M3 S20000 fits no gear stage (above M45's 7000 rpm): the run stops at line 3 with
    90017, and the G18 G01 F400 of lines 1-2 stay in force for MDI."""
    sim, m, _cfg = make()
    m.submit(ProgramLoad("err", "G18 G01 X55 F400\nZ-95\nM3 S20000\nM30\n"))
    m.submit(CycleStart())
    record(sim, 5.0)
    ch = m.snapshot().channel
    assert ch.state is ChannelState.ERROR and ch.error is not None
    assert (ch.error.code, ch.error.line) == (Code.GEAR_NO_RANGE, 3)
    assert (ch.modal.motion, ch.modal.plane, ch.modal.feed_mm_min) == (1, 18, 400.0)
