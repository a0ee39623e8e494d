"""Dynamics parameters as the dynamics manual [002 §3.2.2] describes them, each shown by the
motion it shapes on the demo lathe in simulated time: the four ramp times of the
trapezoidal profile, the minimum ramp time, homing acceleration and ramp time with the axis'
slope type, reduced jog acceleration, the corner weighting. The expected numbers are the
values the tests write (list units: mm/s², µs, ‰), never our output."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from nc_sim.commands import Accepted, Command, HliWrite, Home, JogStart, Move
from nc_sim.params import ParamListError
from tests.nc_sim.sim_helpers import L, make, record, run_program

A = 2000.0  # the demo Z's a_beschl = a_brems (mm/s²)


def _z(axis_params: dict[str, Any], *cmds: Command, seconds: float = 3.0) -> np.ndarray:
    """Z's commanded acceleration, cycle by cycle, after these commands."""
    sim, m, _cfg = make({"Z": axis_params})
    for c in cmds:
        assert isinstance(m.submit(c), Accepted), c
    rec = record(sim, seconds)
    return np.asarray(rec[:, m.axis("Z").slot, L.R_A_CMD])


def _cycles(a: np.ndarray, frm: float, to: float) -> int:
    """Cycles from the first sample past `frm` to the first at `to` (both in the ramp's
    direction): a ramp's duration in ms."""
    sign = 1.0 if to > frm else -1.0
    start = int(np.flatnonzero(sign * (a - frm) > 1e-6)[0])
    end = start + int(np.flatnonzero(np.abs(a[start:] - to) < 1e-6)[0])
    return end - start + 1


def test_each_of_the_four_ramp_times_shapes_its_part_of_a_feed_move() -> None:
    # P-AXIS-00196/00195/00198/00197: acceleration builds up over tr_beschl_zu, goes over
    # tr_beschl_ab, deceleration builds up over tr_brems_zu and goes over tr_brems_ab
    ramps = {
        "getriebe[0].slope_profil.tr_beschl_zu": 30000,
        "getriebe[0].slope_profil.tr_beschl_ab": 50000,
        "getriebe[0].slope_profil.tr_brems_zu": 70000,
        "getriebe[0].slope_profil.tr_brems_ab": 90000,
    }
    a = _z(ramps, Move("Z", 100.0, False, 12000.0), seconds=2.0)  # 200 mm at 200 mm/s
    # to the cycle: a ramp that starts between two samples spans one sample more
    assert _cycles(a, 0.0, A) == pytest.approx(30, abs=1)
    held = int(np.flatnonzero(np.abs(a - A) < 1e-6)[-1])  # the last cycle at full a
    assert _cycles(a[held:], A, 0.0) == pytest.approx(50, abs=1)
    assert _cycles(a, 0.0, -A) == pytest.approx(70, abs=1)
    braked = int(np.flatnonzero(np.abs(a + A) < 1e-6)[-1])
    assert _cycles(a[braked:], -A, 0.0) == pytest.approx(90, abs=1)


def test_no_ramp_time_may_be_shorter_than_the_minimum_ramp_time() -> None:
    # P-AXIS-00201 tr_min "minimum permissible ramp time": the ramp times' lower bound; the
    # demo's ramps are 20 ms, so 60 ms refuses them, naming it
    with pytest.raises(ParamListError) as err:
        make({"Z": {"getriebe[0].dynamik.tr_min": 60000}})
    assert "tr_grenz = 20000 is out of range 60000" in str(err.value)
    assert "limited by P-AXIS-00201" in str(err.value)
    a = _z({"getriebe[0].dynamik.tr_min": 20000}, Move("Z", 100.0, True))
    assert _cycles(a, 0.0, 3000.0) == 20  # G00: a_grenz 3000 mm/s² over tr_grenz 20 ms


@pytest.mark.parametrize(("slope_type", "ramp_ms"), [(0, 1), (1, 40)])
def test_homing_accelerates_at_a_ref_over_tr_ref_by_the_axis_slope_type(
    slope_type: int, ramp_ms: int
) -> None:
    # P-AXIS-00285 a_ref, P-AXIS-00286 tr_ref; P-AXIS-00270 getriebe[i].slope_type: 0 is
    # step-shaped (a_ref at once), otherwise the acceleration builds up over tr_ref
    params = {
        "getriebe[0].a_ref": 800,
        "getriebe[0].tr_ref": 40000,
        "getriebe[0].slope_type": slope_type,
    }
    a = _z(params, Home("Z"), seconds=2.0)
    assert np.abs(a).max() == pytest.approx(800.0)
    assert _cycles(np.abs(a), 0.0, 800.0) == ramp_ms


def test_jog_under_reduced_acceleration_uses_its_own_acceleration() -> None:
    # P-AXIS-00545 handbetrieb.hb.a_max_red: while the channel's reduced_acceleration is
    # set, G200 jog accelerates at it instead of hb.a_max (the demo's 1000 mm/s²)
    params = {"handbetrieb.hb.a_max_red": 400}
    reduced = _z(params, HliWrite("reduced_acceleration", 1), JogStart("Z", 1), seconds=1.0)
    assert reduced.max() == pytest.approx(400.0)
    plain = _z(params, JogStart("Z", 1), seconds=1.0)
    assert plain.max() == pytest.approx(1000.0)


@pytest.mark.parametrize(("range_way", "gear"), [(0, 1), (1, 2)])
def test_the_gear_search_runs_the_way_range_way_says(range_way: int, gear: int) -> None:
    # P-CHAN-00074 spindel[i].range_way [000 §2.8.2]: S450 lies in M40 (50-560 rpm) and M41
    # (400-800): bottom up (0) takes M40, top down (1) M41
    channel = {"spindel[0].range_way": range_way, "spindel[0].m3_synch": 0}
    _sim, m, rec = run_program("M3 S450\nM30\n", 8.0, channel=channel)
    assert rec[-1, m.axis("S1").slot, L.R_GEAR] == gear


@pytest.mark.parametrize("weight", [1000, 500])
def test_a_right_angle_corner_is_taken_at_the_weighted_transition_acceleration(
    weight: int,
) -> None:
    # P-AXIS-00013 a_trans_weight [002 §2.3.1]: at a corner no axis' velocity may jump by
    # more than a_trans · cycle, a_trans = a · weight / 1000; X then Z at 90°: each axis'
    # velocity jumps by the whole path speed, so the corner speed is a_trans · 1 ms
    params = {"getriebe[0].dynamik.a_trans_weight": weight}
    _sim, m, rec = run_program("G01 X60 F3000\nZ-90\nM30\n", 4.0, {"X": params, "Z": params})
    vx, vz = rec[:, m.axis("X").slot, L.R_V_CMD], rec[:, m.axis("Z").slot, L.R_V_CMD]
    lines = rec[:, m.channel_slot, L.R_LINE]
    corner = int(np.argmax(lines == 2))
    v_corner = A * weight / 1000.0 * 0.001  # mm/s
    speed = np.hypot(vx, vz)[corner - 2 : corner + 2]
    assert speed.min() == pytest.approx(v_corner, abs=A * 0.001)


def _hold(axis_params: dict[str, Any], channel: dict[str, Any], *start: Command) -> np.ndarray:
    """Z's commanded acceleration after `start` ran 1 s and feedhold came (P-CHAN-00097 = 1:
    the feedhold set brakes)."""
    sim, m, _cfg = make({"Z": axis_params}, {"use_drive_curr_limit": 1, **channel})
    for c in start:
        assert isinstance(m.submit(c), Accepted), c
    sim.run(1000)
    assert isinstance(m.submit(HliWrite("feedhold", 1)), Accepted)
    rec = record(sim, 1.0)
    return np.asarray(rec[:, m.axis("Z").slot, L.R_A_CMD])


def test_feedhold_brakes_a_step_shaped_move_at_its_own_deceleration() -> None:
    # P-AXIS-00024 lslope_profil.a_feedh (step-shaped profile, P-CHAN-00097 = 1)
    a = _hold(
        {"getriebe[0].lslope_profil.a_feedh": 700},
        {"prog_start.slope.profile": 0},
        HliWrite("reduced_acceleration", 0),
        Move("Z", 200.0, False, 6000.0),
    )
    assert -a.min() == pytest.approx(700.0)


def test_feedhold_brakes_a_jog_at_the_manual_mode_feedhold_set() -> None:
    # P-AXIS-00259 hb.a_feedh over the ramp time P-AXIS-00360 hb.tr_feedh
    params = {"handbetrieb.hb.a_feedh": 600, "handbetrieb.hb.tr_feedh": 30000}
    a = _hold(params, {}, JogStart("Z", 1))
    assert -a.min() == pytest.approx(600.0)
    assert _cycles(-a, 0.0, 600.0) == pytest.approx(30, abs=1)


@pytest.mark.parametrize(("ref_richt", "sign"), [(0, -1.0), (1, 1.0)])
def test_homing_comes_onto_its_reference_in_the_direction_ref_richt_gives(
    ref_richt: int, sign: float
) -> None:
    # INB-AXIS-0007 kenngr.ref_richt: 1 homes towards +, 0 towards -; whichever side of the
    # cam Z starts, its last move (onto the zero mark) runs that way, and it ends homed
    sim, m, _cfg = make({"Z": {"kenngr.ref_richt": ref_richt}})
    assert isinstance(m.submit(Home("Z")), Accepted)
    rec = record(sim, 12.0)
    z = m.axis("Z").slot
    v = rec[:, z, L.R_V_CMD]
    assert rec[-1, z, L.R_HOMED] == 1
    assert np.sign(v[np.flatnonzero(v != 0)[-1]]) == sign


@pytest.mark.parametrize(("tr_geom_us", "v_arc"), [(0, 70.71), (500000, 46.42)])
def test_an_arc_is_slowed_by_the_geometric_ramp_time(tr_geom_us: int, v_arc: float) -> None:
    # P-AXIS-00199 tr_geom [002 §2.3.3]: on an arc of radius r the geometric jerk v³/r² stays
    # under a/tr_geom; without it (0: the demo's tr_min of 1 ms) the centripetal acceleration
    # limits: half of a = 2000 mm/s², v = sqrt(0.5 a r). r = 5 mm: 70.71 mm/s; with
    # tr_geom 0.5 s: (2000 / 0.5 · 25)^(1/3) = 46.42 mm/s
    params = {"getriebe[0].dynamik.tr_geom": tr_geom_us}
    program = "G18 G01 X50 Z-100 F9000\nG02 X50 Z-90 K5\nM30\n"  # a half circle, r = 5
    _sim, m, rec = run_program(program, 3.0, {"X": params, "Z": params})
    lines = rec[:, m.channel_slot, L.R_LINE]
    vx, vz = rec[:, m.axis("X").slot, L.R_V_CMD], rec[:, m.axis("Z").slot, L.R_V_CMD]
    on_arc = np.hypot(vx, vz)[lines == 2]
    assert on_arc.max() == pytest.approx(v_arc, rel=1e-3)


REFMAX, REFLOW = 83.333, 16.666  # the demo Z's vb_refmax, vb_reflow (mm/s)


def _homing(params: dict[str, Any]) -> tuple[np.ndarray, float, bool]:
    """Z's commanded velocity while it homes towards + from -100 mm, its final position and
    whether it ended homed."""
    sim, m, _cfg = make({"Z": {"kenngr.ref_richt": 1, **params}})
    assert isinstance(m.submit(Home("Z")), Accepted)
    rec = record(sim, 12.0)
    z = m.axis("Z").slot
    return rec[:, z, L.R_V_CMD], float(rec[-1, z, L.R_P_CMD]), bool(rec[-1, z, L.R_HOMED])


def _turns(v: np.ndarray) -> int:
    """How often the motion changes direction."""
    signs = np.sign(v[np.abs(v) > 1e-9])
    return int(np.count_nonzero(np.diff(signs)))


def test_homing_without_reversal_takes_the_zero_pulse_on_the_way_onto_the_cam() -> None:
    # P-AXIS-00157 ref_ohne_rev: onto the cam at vb_refmax, the zero pulse latched there, back
    # to ref_pos (the pulse's position, passed meanwhile): one turn. With reversal the axis
    # first backs off the cam at vb_reflow and turns once more onto the zero pulse.
    v, end, homed = _homing({"kenngr.ref_ohne_rev": 1})
    assert homed and end == pytest.approx(0.0) and _turns(v) == 1
    v, end, homed = _homing({})
    assert homed and end == pytest.approx(0.0) and _turns(v) == 2


def test_homing_without_a_cam_searches_the_zero_pulse_at_the_low_speed() -> None:
    # P-AXIS-00156 ref_ohne_nocken: no cam search at vb_refmax, the zero pulse at vb_reflow
    v, end, homed = _homing({"kenngr.ref_ohne_nocken": 1})
    assert homed and end == pytest.approx(0.0)
    assert np.abs(v).max() == pytest.approx(REFLOW)
    v, _end, _homed = _homing({})
    assert np.abs(v).max() == pytest.approx(REFMAX)
