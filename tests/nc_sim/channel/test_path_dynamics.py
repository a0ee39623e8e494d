"""The path's dynamics as the dynamics manual [002] gives them: the step-shaped profile's two
acceleration stages [002 §2.2.2] and the PLC's reduced speed [002 §2.8] on program and MDI
path motion, the slope type at program start [002 §3.2.1] and the safety zones. Expected
numbers are the parameters the tests write (or the demo lathe's lists), not our output."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc_sim.commands import Accepted, CycleStart, HliWrite, Move, ProgramLoad, Reset
from nc_sim.machine.machine import Machine
from nc_sim.sim import Simulation
from tests.nc_sim.sim_helpers import L, make, mdi, record, run_program

STEP_SHAPED = {"prog_start.slope.profile": 0}  # P-CHAN-00071: step-shaped at program start
# lslope_profil of X and Z, written by the tests (in the list's units: mm/s², µm/s):
# G00 4000 mm/s² below 120 mm/s, 1500 above; G01 2500 and 800 changing at the same speed
V12 = 120.0
RAPID = (4000.0, 1500.0)
FEED = (2500.0, 800.0)
STAGES = {
    "getriebe[0].lslope_profil.a_grenz_stufe_1": 4000,
    "getriebe[0].lslope_profil.a_grenz_stufe_2": 1500,
    "getriebe[0].lslope_profil.vb_grenz_stufe_1_2": 120000,
    "getriebe[0].lslope_profil.a_stufe_1": 2500,
    "getriebe[0].lslope_profil.a_stufe_2": 800,
    "getriebe[0].lslope_profil.vb_stufe_1_2": 120000,
}
V_RAPID = 333.333  # the demo's vb_eilgang, mm/s


def _stages(v: np.ndarray, a: np.ndarray, v12: float, dv: float) -> tuple[set[float], set[float]]:
    """The accelerations (rounded to 1 mm/s²) commanded below and above the changeover speed,
    leaving out the cycles next to it and at the ends of the ramps."""
    moving = np.abs(a) > 1.0
    low = moving & (np.abs(v) > dv) & (np.abs(v) < v12 - dv)
    high = moving & (np.abs(v) > v12 + dv) & (np.abs(v) < np.abs(v).max() - dv)
    return set(np.round(np.abs(a[low]))), set(np.round(np.abs(a[high])))


def test_a_rapid_path_block_accelerates_in_each_stage_of_the_step_shaped_profile() -> None:
    # 002 §2.2.2: below vb_grenz_stufe_1_2 the first G00 stage, above it the second
    _sim, m, rec = run_program("G00 Z100\nM30\n", 1.5, {"Z": STAGES}, STEP_SHAPED)
    z = m.axis("Z").slot
    v, a = rec[:, z, L.R_V_CMD], rec[:, z, L.R_A_CMD]
    assert np.abs(v).max() == pytest.approx(V_RAPID, rel=1e-6)
    low, high = _stages(v, a, V12, dv=RAPID[0] * 0.001)
    assert low == {RAPID[0]} and high == {RAPID[1]}


def _first_ramp(m: Machine, rec: np.ndarray) -> list[float]:
    """Z's commanded acceleration over the first 5 cycles of its motion."""
    a = np.abs(rec[:, m.axis("Z").slot, L.R_A_CMD])
    start = int(np.flatnonzero(a > 1e-9)[0])
    return [float(v) for v in a[start : start + 5]]


# trapezoidal G00: a_grenz 3000 mm/s² built up over tr_grenz 20 ms, 150 mm/s² per cycle
TRAPEZ_RAMP = [3000.0 * k / 20 for k in range(1, 6)]


def test_every_program_starts_with_the_profile_of_p_chan_00071() -> None:
    # 002 §3.2.1 P-CHAN-00071 prog_start.slope.profile: "default acceleration profile at
    # program start"; the demo's is 1 (trapezoidal: the acceleration builds up over
    # tr_grenz = 20 ms). An MDI #SLOPE[TYPE=STEP] before does not carry into the program.
    sim, m, _cfg = make()
    mdi(m, "#SLOPE[TYPE=STEP]")
    mdi(m, "G00 Z-90")
    step = _first_ramp(m, record(sim, 1.0))
    assert step == pytest.approx([3000.0] * 5)  # a step to the demo's a_grenz_stufe_1
    assert isinstance(m.submit(ProgramLoad("p", "G00 Z-50\nM30\n")), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    ramp = _first_ramp(m, record(sim, 1.0))
    assert ramp == pytest.approx(TRAPEZ_RAMP)


def test_a_reset_brings_back_the_profile_of_p_chan_00071() -> None:
    sim, m, _cfg = make()
    mdi(m, "#SLOPE[TYPE=STEP]")
    assert isinstance(m.submit(Reset()), Accepted)
    mdi(m, "G00 Z-90")
    ramp = _first_ramp(m, record(sim, 1.0))
    assert ramp == pytest.approx(TRAPEZ_RAMP)


def test_a_feed_path_block_on_two_axes_keeps_each_axis_in_its_stage() -> None:
    # a 45° line at F18000 (300 mm/s on the path, 212 mm/s per axis): each axis changes stage
    # at its own 120 mm/s, that is at 169.7 mm/s on the path
    axes = {"X": STAGES, "Z": STAGES}
    _sim, m, rec = run_program("G01 X200 Z50 F18000\nM30\n", 2.0, axes, STEP_SHAPED)
    for name in ("X", "Z"):
        slot = m.axis(name).slot
        v, a = rec[:, slot, L.R_V_CMD], rec[:, slot, L.R_A_CMD]
        assert np.abs(v).max() == pytest.approx(300.0 / math.sqrt(2.0), rel=1e-6)
        low, high = _stages(v, a, V12, dv=FEED[0] * 0.001)
        assert low == {FEED[0]} and high == {FEED[1]}, name


# 002 §2.8, the manual's axis list excerpt: vb_max_red 25000, rapid_speed_red 50000 µm/s
REDUCED = {"getriebe[0].vb_max_red": 25000, "getriebe[0].rapid_speed_red": 50000}


def _door_open(names: tuple[str, ...]) -> tuple[Simulation, Machine]:
    sim, m, _cfg = make({n: REDUCED for n in names})
    for n in names:
        assert isinstance(m.submit(HliWrite("reduced_speed", 1, n)), Accepted)
    return sim, m


def test_reduced_speed_caps_each_axis_of_a_rapid_and_a_feed_program_block() -> None:
    sim, m = _door_open(("X", "Z"))
    program = "G00 Z-50\nG01 X90 Z-10 F6000\nM30\n"  # G01: 45°, 100 mm/s on the path
    assert isinstance(m.submit(ProgramLoad("door", program)), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    rec = record(sim, 4.0)
    x, z = m.axis("X").slot, m.axis("Z").slot
    vx, vz = rec[:, x, L.R_V_CMD], rec[:, z, L.R_V_CMD]
    rapid = np.abs(vx) < 1e-9  # the G00 block moves Z alone
    assert np.abs(vz[rapid]).max() == pytest.approx(50.0, rel=1e-9)  # rapid_speed_red
    # the feed block: each axis at its 25 mm/s, not the path (35.4 mm/s, not 100)
    assert np.abs(vx).max() == pytest.approx(25.0, rel=1e-9)
    assert np.abs(vz[~rapid]).max() == pytest.approx(25.0, rel=1e-9)
    # and the program ran to its end
    assert (rec[-1, x, L.R_P_CMD], rec[-1, z, L.R_P_CMD]) == pytest.approx((90.0, -10.0))


def test_reduced_speed_caps_mdi_path_motion_and_slows_a_block_already_running() -> None:
    sim, m, _cfg = make({"Z": REDUCED})
    mdi(m, "G01 Z100 F6000")  # 100 mm/s
    sim.run(1000)
    z = m.axis("Z")
    assert abs(m.k.st[z.slot, L.S_V_CMD]) == pytest.approx(100.0, rel=1e-9)
    assert isinstance(m.submit(HliWrite("reduced_speed", 1, "Z")), Accepted)  # door opens
    rec = record(sim, 0.5)
    assert np.abs(rec[-100:, z.slot, L.R_V_CMD]).max() == pytest.approx(25.0, rel=1e-9)
    assert isinstance(m.submit(HliWrite("reduced_speed", 0, "Z")), Accepted)  # closed again
    rec = record(sim, 0.5)
    assert np.abs(rec[-100:, z.slot, L.R_V_CMD]).max() == pytest.approx(100.0, rel=1e-9)


# 002 §2.8: safety zone 1 of Z from -60 to -40 mm (P-AXIS-00093/00085, 0.1 µm), zone 2 from
# 0 to 20 mm (P-AXIS-00105/00097); the manual's excerpt: vb_max_red_zone 50000 µm/s
ZONES = {
    "kenngr.red_speed_zone_neg": -600000,
    "kenngr.red_speed_zone_pos": -400000,
    "kenngr.red_speed_zone_2_neg": 0,
    "kenngr.red_speed_zone_2_pos": 200000,
    "getriebe[0].vb_max_red_zone": 50000,
}


def _top_speed(
    zone_units: dict[str, int], block: str | Move, params: dict[str, int] | None = None
) -> float:
    sim, m, _cfg = make({"Z": {**ZONES, **(params or {})}})
    for unit, value in zone_units.items():
        assert isinstance(m.submit(HliWrite(unit, value, "Z")), Accepted)
    if isinstance(block, Move):  # a single-axis move, not the path
        assert isinstance(m.submit(block), Accepted)
    else:
        mdi(m, block)
    rec = record(sim, 6.0)
    return float(np.abs(rec[:, m.axis("Z").slot, L.R_V_CMD]).max())


def test_the_zone_signal_slows_an_axis_whose_motion_reaches_into_its_zone() -> None:
    zone1 = {"reduced_speed_zone": 1}
    assert _top_speed(zone1, "G01 Z-80 F6000") == pytest.approx(100.0)  # stays outside
    assert _top_speed(zone1, "G01 Z-50 F6000") == pytest.approx(50.0)  # into zone 1
    assert _top_speed(zone1, "G01 Z10 F6000") == pytest.approx(50.0)  # through it
    assert _top_speed({}, "G01 Z-50 F6000") == pytest.approx(100.0)  # no signal, no limit
    assert _top_speed(zone1, Move("Z", -50.0, False, 6000.0)) == pytest.approx(50.0)


def test_zone_2_has_its_own_speed_or_that_of_zone_1() -> None:
    zone2 = {"reduced_speed_2_zone": 1}
    # P-AXIS-00503 unset (0): "the identical value of P-AXIS-00030"
    assert _top_speed(zone2, "G00 Z10") == pytest.approx(50.0)
    assert _top_speed(zone2, "G00 Z10", {"getriebe[0].vb_max_red_zone_2": 20000}) == (
        pytest.approx(20.0)
    )
    assert _top_speed(zone2, "G01 Z-50 F6000") == pytest.approx(100.0)  # zone 1 not signalled


@pytest.mark.parametrize("lookahead", [1, 60])
def test_the_look_ahead_reaches_as_far_as_lookahead_blocks(lookahead: int) -> None:
    # INB-CHAN-0006 lookahead_blocks: 30 collinear blocks of 1 mm at F6000 (100 mm/s). The
    # path must be able to stop at the end of what it sees: seeing one block (1 mm) it cannot
    # get near 100 mm/s (from rest to rest over 1 mm with the 2000 mm/s² and 20 ms ramps of
    # Z it peaks below 40 mm/s); seeing 60 (all 30) it runs at F
    blocks = "".join(f"G01 Z{-100 + i} F6000\n" for i in range(1, 31))
    channel = {"lookahead_blocks": lookahead}
    _sim, m, rec = run_program(blocks + "M30\n", 4.0, channel=channel)
    top = float(np.abs(rec[:, m.axis("Z").slot, L.R_V_CMD]).max())
    if lookahead == 1:
        assert top < 40.0
    else:
        assert top == pytest.approx(100.0)


@pytest.mark.parametrize(("corr", "v_transition"), [(0, 100.0), (1, 31.62)])
def test_a_tangent_line_to_arc_transition_is_slowed_by_corr_v_trans_jerk(
    corr: int, v_transition: float
) -> None:
    # P-CHAN-00009 corr_v_trans_jerk [002 §2.3.2]: a tangent transition from a line into an arc
    # of r = 10 mm jumps the normal axis' acceleration by v²/r. Switched on, no axis' jerk at
    # the transition exceeds j_trans = a/tr · r_trans_weight/1000 = 2000/0.02 · 1, so
    # v = sqrt(j_trans · cycle · r) = sqrt(100000 · 0.001 · 10) = 31.62 mm/s; off, the path
    # keeps F6000 = 100 mm/s (within what the arc allows: sqrt(0.5 · 2000 · 10) = 100 mm/s)
    channel = {"corr_v_trans_jerk": corr}
    _sim, m, rec = run_program("G18 G01 Z-90 F6000\nG03 X60 Z-80 R10\nM30\n", 3.0, channel=channel)
    speed = np.hypot(rec[:, m.axis("X").slot, L.R_V_CMD], rec[:, m.axis("Z").slot, L.R_V_CMD])
    at = int(np.argmax(rec[:, m.channel_slot, L.R_LINE] == 2))
    assert speed[at - 3 : at + 3].min() == pytest.approx(v_transition, rel=1e-3)
