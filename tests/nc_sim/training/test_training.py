"""Training exercises: the file format, the score, and every check of every shipped
exercise on a seat in simulated time - passed by a scripted student who does the right
thing, failed by one who does not.

The seat is fed as the service's worker feeds it: chunks of 100 recorded cycles (0.1 s)
with the events logged since. The numbers come from the demo lathe's lists: X kv 20 1/s
[004 §3.6], S1 kv 10 1/s, plc.m_ack_timeout 5 s, S1 ramps at 3000 °/s² in gear stage 3.
"""

from __future__ import annotations

import pytest

from nc_sim.commands import (
    GearChange,
    PlcAck,
    PlcSignal,
    Reset,
    SpindlePosition,
)
from nc_sim.params import Scope
from nc_sim.sim import Simulation
from nc_sim.training.checks import ExerciseMonitor
from nc_sim.training.exercise import ExerciseError, parse_exercise
from nc_sim.training.score import score, time_weight
from nc_sim.training.seat import start_seat
from tests.nc_sim.training.seats import Seat, load

NAMES = (
    "sign-error",
    "multi-gain",
    "gear-change-plc",
    "accel-curve",
    "c-axis",
    "circle-ellipse",
    "soft-coupling",
    "find-backlash",
)


# --- the files ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_every_shipped_exercise_parses_and_names_itself_as_its_file(name: str) -> None:
    ex = load(name)
    assert ex.id == name
    assert ex.checks and all(c.points > 0 for c in ex.checks)
    assert ex.par_time_s > 0 and ex.hints


GOOD = """
id = "t"
title = "T"
summary = "S"
task = "Do it."
par_time_s = 600
machine = "demo"

[[faults]]
kind = "drive_gain_wrong"
axis = "X"
factor = 2.0

[[checks]]
id = "a"
text = "A"
points = 40
kind = "gain"
axis = "X"
within_pct = 1.0

[[checks]]
id = "b"
text = "B"
points = 60
kind = "no_event"
codes = ["LAG_MONITORING"]
axis = "X"
window_s = 60
"""


def test_a_good_file_parses_to_its_values() -> None:
    ex = parse_exercise(GOOD, "t.toml")
    assert [c.id for c in ex.checks] == ["a", "b"] and ex.max_points == 100
    assert ex.faults[0].fault.kind == "drive_gain_wrong"


@pytest.mark.parametrize(
    ("old", "new", "key", "value"),
    [
        ('axis = "X"\nwithin_pct', 'axis = "x1"\nwithin_pct', "checks[0].axis", "x1"),
        ('kind = "drive_gain_wrong"', 'kind = "motor_lost"', "faults[0].kind", "motor_lost"),
        ("factor = 2.0", "factor = 2.0\ngain = 3", "faults[0].gain", 3),
        ("factor = 2.0", "factor = -2.0", "faults[0].factor", -2.0),
        ("points = 40", "points = 0", "checks[0].points", 0),
        ('kind = "gain"', 'kind = "telepathy"', "checks[0].kind", "telepathy"),
        ('["LAG_MONITORING"]', '["LAG_MONITORING", "NO_SUCH"]', "checks[1].codes[1]", "NO_SUCH"),
        ("window_s = 60", "window_s = 0", "checks[1].window_s", 0),
        ('machine = "demo"', 'machine = "mill"', "machine", "mill"),
        ("par_time_s = 600", "par_time_s = -1", "par_time_s", -1),
        ('id = "b"', 'id = "a"', "checks[1].id", "a"),
        ("window_s = 60", 'window_s = 60\nrequires = ["c"]', "checks[1].requires", "c"),
        ("window_s = 60", 'window_s = 60\nrequires = ["b"]', "checks[1].requires", "b"),
        ("within_pct = 1.0", "within_pct = 1.0\nkeep_kv = 1", "checks[0].keep_kv", 1),
        ("window_s = 60", "window_s = 60\nbusy_pct = 120", "checks[1].busy_pct", 120),
    ],
)
def test_each_error_names_the_file_the_key_and_the_value(
    old: str, new: str, key: str, value: object
) -> None:
    assert old in GOOD
    with pytest.raises(ExerciseError) as e:
        parse_exercise(GOOD.replace(old, new, 1), "bad.toml")
    assert (e.value.source, e.value.key, e.value.value) == ("bad.toml", key, value)
    assert str(e.value).startswith(f"bad.toml: {key} = {value!r}: ")
    assert isinstance(e.value, ValueError)


def test_an_unknown_starting_parameter_is_named_with_its_key() -> None:
    text = GOOD + '\n[[start]]\nscope = "axis"\ntarget = "X"\nname = "getriebe[0].kw"\nvalue = 1\n'
    with pytest.raises(ExerciseError) as e:
        parse_exercise(text, "bad.toml")
    assert e.value.key == "start[0].name" and "getriebe[0].kw" in str(e.value)


def test_sizes_are_limited() -> None:
    check = '\n[[checks]]\nid = "c{i}"\ntext = "C"\npoints = 1\nkind = "event"\ncode = 22\n'
    many = GOOD + "".join(check.format(i=i) for i in range(31))  # 33 checks
    with pytest.raises(ExerciseError) as e:
        parse_exercise(many, "big.toml")
    assert e.value.key == "checks" and "at most 32" in str(e.value)
    with pytest.raises(ExerciseError) as e:
        parse_exercise(GOOD.replace('task = "Do it."', f'task = "{"x" * 20001}"'), "big.toml")
    assert e.value.key == "task"


def test_a_toml_syntax_error_keeps_line_and_column() -> None:
    with pytest.raises(ExerciseError) as e:
        parse_exercise('id = "t"\ntitle = "T"\npoints = = 3\n', "syntax.toml")
    assert str(e.value).startswith("syntax.toml: TOML syntax: ")
    assert "line 3, column" in str(e.value)


# --- the score ---------------------------------------------------------------------------


def test_the_time_weight_falls_from_par_to_three_times_par() -> None:
    assert time_weight(0.0, 600) == 1.0 and time_weight(600, 600) == 1.0
    assert time_weight(1200, 600) == pytest.approx(0.75)  # half-way from par to 3 par
    assert time_weight(1800, 600) == pytest.approx(0.5)
    assert time_weight(6000, 600) == 0.5


def test_the_score_by_hand() -> None:
    """Check a (40 points) passed after 300 s: 40; b (60) after 1200 s with par 600:
    60 × 0.75 = 45; one hint of 10 taken: 40 + 45 - 10 = 75 of 100."""
    ex = parse_exercise(GOOD + '\n[[hints]]\ntext = "h"\ncost = 10\n', "t.toml")
    s = score(ex, {"a": 300.0, "b": 1200.0}, hints_taken=[0])
    assert (s.passed, s.total, s.max_points) == (2, 2, 100)
    assert s.points == pytest.approx(75.0) and s.hint_cost == 10
    half = score(ex, {"a": 300.0})
    assert half.passed == 1 and half.points == pytest.approx(40.0)
    with pytest.raises(ValueError, match="not the exercise's checks"):
        score(ex, {"a": 1.0, "zz": 2.0})


def test_the_score_never_goes_below_zero() -> None:
    ex = parse_exercise(
        GOOD + '\n[[hints]]\ntext = "h"\ncost = 25\n[[hints]]\ntext = "i"\ncost = 30\n', "t.toml"
    )
    assert score(ex, {}, hints_taken=[0, 1]).points == 0.0
    with pytest.raises(ValueError, match="no hint 2"):
        score(ex, {}, hints_taken=[2])


# --- the shipped exercises on a seat -------------------------------------------------------


def test_sign_error_fixed_by_the_command_value_sign() -> None:
    """004 §3.5: the motor is wired inverted; lr_hw[0].vz_stellgr inverts the command value
    and the loop is negative again: k = kv, and a minute of strokes without a trip."""
    seat = Seat("sign-error")
    seat.param(Scope.AXIS, "X", {"lr_hw[0].vz_stellgr": 1})
    seat.x_back_and_forth(68.0)
    assert seat.passed("gain"), seat.result("gain")
    assert "k = 20.00 1/s against kv 20.00 1/s" in seat.result("gain").detail
    assert seat.passed("no-trip"), seat.result("no-trip")
    assert seat.passed("direction"), seat.result("direction")


def test_sign_error_fixed_on_the_actual_value_drives_the_slide_backwards() -> None:
    """Inverting the actual value (lr_hw[0].vz_istw) instead of the command value closes the
    loop too: no trip and k = kv in the NC's view. But the slide moves against the command
    (motor inverted, its encoder counting true), which the direction check sees; the gain
    and the quiet minute require it, so the wrong parameter scores nothing."""
    seat = Seat("sign-error")
    seat.param(Scope.AXIS, "X", {"lr_hw[0].vz_istw": 1})
    seat.run(0.1)
    seat.recover("X")  # the actual value jumped to -x: lag monitoring trips at once
    seat.x_back_and_forth(68.0)
    assert not seat.passed("direction")
    assert "the wrong way" in seat.result("direction").detail
    for check in ("gain", "no-trip"):  # as the NC sees it they hold, but not counted
        assert not seat.passed(check)
        assert "not counted while direction fails" in seat.result(check).detail
    assert "k = 20.00 1/s against kv 20.00 1/s" in seat.result("gain").detail
    assert score(seat.exercise, seat.first_passes()).points == 0.0


def test_sign_error_not_fixed_fails_both_checks() -> None:
    """Moving without the fix runs away into lag monitoring each time; a student who then
    only waits has not moved X in the last minute."""
    seat = Seat("sign-error")
    for _ in range(3):
        seat.mdi("G01 X100 F1000")
        seat.run(4.0)
        seat.recover("X")
    seat.run(62.0)
    assert not seat.passed("gain") and not seat.passed("no-trip")
    assert "not moved" in seat.result("no-trip").detail


def test_sign_error_with_kv_halved_instead_fails_both_checks() -> None:
    seat = Seat("sign-error")
    seat.param(Scope.AXIS, "X", {"getriebe[0].kv": 1000})
    for _ in range(16):
        seat.mdi("G01 X100 F1000")
        seat.run(4.0)
        seat.recover("X")
    assert not seat.passed("gain") and not seat.passed("no-trip")


def test_sign_error_fixed_but_x_moved_only_a_moment_ago_is_not_a_minute_of_use() -> None:
    """ "X moves for a minute": a fixed X that stood still for 70 s and then made one 4 s
    stroke has not been in use for a minute; a minute of strokes later it has."""
    seat = Seat("sign-error")
    seat.param(Scope.AXIS, "X", {"lr_hw[0].vz_stellgr": 1})
    seat.run(70.0)
    assert seat.result("no-trip").detail == "X has not moved"
    seat.x_back_and_forth(4.0)
    assert not seat.passed("no-trip")
    assert "X in use without 90002: 4 of 60 s" in seat.result("no-trip").detail
    seat.x_back_and_forth(60.0)
    assert seat.passed("no-trip"), seat.result("no-trip")


def test_sign_error_a_short_move_then_a_wait_is_not_a_minute_of_use() -> None:
    """One 3 s stroke, then a minute of waiting and a nudge: its first motion lies a minute
    back and it moved within that minute, but in 3 of its 60 seconds, not in the 30 that
    "in use" asks (busy_pct 50)."""
    seat = Seat("sign-error")
    seat.param(Scope.AXIS, "X", {"lr_hw[0].vz_stellgr": 1})
    seat.mdi("G01 X100 F1000")  # 50 mm at 16.7 mm/s: 3 s and the ramps
    seat.run(58.0)
    seat.mdi("G01 X99 F1000")  # a nudge just inside the window's last seconds
    seat.run(4.0)
    assert not seat.passed("no-trip")
    # the stroke took seconds 0..3, of which 2 and 3 lie in the last 60 s; the nudge one more
    assert "moved in 3 of the last 60 s" in seat.result("no-trip").detail
    seat.x_back_and_forth(60.0)  # strokes of 3 s every 4 s: 45 of 60 s
    assert seat.passed("no-trip"), seat.result("no-trip")


def test_sign_error_doing_nothing_fails_both_checks() -> None:
    seat = Seat("sign-error")
    seat.run(70.0)
    assert not seat.passed("gain") and not seat.passed("no-trip")


def test_multi_gain_by_experiment() -> None:
    """DOMAIN §7: the drive gives 1/2.2857 of the speed per digit, so k = 20 · 0.4375 =
    8.75 1/s; f = (kv/100)/k = 2.2857 and multi_gain 10000 · f = 22857 brings k back to kv."""
    seat = Seat("multi-gain")
    seat.x_back_and_forth(8.0)
    measured = seat.result("gain")
    assert not measured.passed and "k = 8.75 1/s" in measured.detail
    seat.param(Scope.AXIS, "X", {"getriebe[0].multi_gain_z": 22857})
    seat.x_back_and_forth(8.0)
    assert seat.passed("gain"), seat.result("gain")


def test_multi_gain_with_kv_changed_instead_fails() -> None:
    """Setting kv to the measured k leaves the loop gain at 0.4375 · 8.75 = 3.83 1/s,
    against the kv of 20 1/s the task keeps."""
    seat = Seat("multi-gain")
    seat.param(Scope.AXIS, "X", {"getriebe[0].kv": 875})
    seat.x_back_and_forth(12.0)
    assert not seat.passed("gain")
    detail = seat.result("gain").detail
    assert "k = 3.83 1/s against kv 20.00 1/s" in detail
    assert "getriebe[0].kv changed from 20.00 to 8.75 1/s: the task keeps kv" in detail


def test_multi_gain_with_the_whole_proposal_applied_fails() -> None:
    """multi_gain × 2.2857 and kv lowered to the measured 8.75 1/s: the drive is right
    again, so k = 8.75 1/s, the new kv, but not the 20 1/s the task says to keep."""
    seat = Seat("multi-gain")
    seat.param(Scope.AXIS, "X", {"getriebe[0].multi_gain_z": 22857, "getriebe[0].kv": 875})
    seat.x_back_and_forth(12.0)
    assert not seat.passed("gain")
    assert "k = 8.75 1/s against kv 20.00 1/s (-56." in seat.result("gain").detail  # 8.75/20 - 1


def _z_back_and_forth(seat: Seat, seconds: float) -> None:
    """G01 Z between -100 and -150 mm at 1 m/min (3 s per stroke)."""
    for i in range(round(seconds / 4.0)):
        seat.mdi(f"G01 Z{-150 if i % 2 == 0 else -100} F1000")
        seat.run(4.0)


def test_circle_ellipse_fixed_at_its_cause() -> None:
    """Z's drive gives 0.8 of the speed per digit: k = 16 1/s against kv 20; multi_gain ·
    1.25 (10000 -> 12500) brings Z to its kv, which is X's: round and fixed."""
    seat = Seat("circle-ellipse")
    _z_back_and_forth(seat, 8.0)
    assert not seat.passed("round") and not seat.passed("cause")
    assert "k = 16.00 1/s against kv of X 20.00 1/s" in seat.result("round").detail
    seat.param(Scope.AXIS, "Z", {"getriebe[0].multi_gain_z": 12500})
    _z_back_and_forth(seat, 8.0)
    assert seat.passed("round") and seat.passed("cause"), seat.monitor.results()


def test_circle_ellipse_matched_by_kv_is_round_but_leaves_the_cause() -> None:
    """kv matching instead (X's kv down to Z's 16 1/s): the circle is round (Z follows with
    X's kv), but Z still follows at 0.8 of its own kv: 60 of 100 points."""
    seat = Seat("circle-ellipse")
    seat.param(Scope.AXIS, "X", {"getriebe[0].kv": 1600})
    _z_back_and_forth(seat, 8.0)
    assert seat.passed("round") and not seat.passed("cause")
    assert "k = 16.00 1/s against kv 20.00 1/s" in seat.result("cause").detail


def test_gear_change_completes_once_the_plc_gets_its_time() -> None:
    """The PLC acknowledges after 8 s; plc.m_ack_timeout raised from 5 s to 10 s lets M41
    complete [000 §2.8.2]; then M19 to 90° ends in position in gear stage 2."""
    seat = Seat("gear-change-plc")
    seat.param(Scope.CHANNEL, "", {"plc.m_ack_timeout": 10_000_000})
    seat.do(GearChange("S", 41))
    seat.run(12.0)
    assert seat.passed("gear-2"), seat.result("gear-2")
    seat.do(SpindlePosition("S", 90.0))
    seat.run(12.0)
    assert seat.passed("m19-90"), seat.result("m19-90")


def test_gear_change_acknowledged_by_hand() -> None:
    """The other way: acknowledge the pending M41 by hand before the 5 s run out."""
    seat = Seat("gear-change-plc")
    seat.do(GearChange("S", 41))
    seat.run(2.0)
    seat.do(PlcAck())
    seat.run(4.0)
    assert seat.passed("gear-2"), seat.result("gear-2")
    seat.do(SpindlePosition("S", 90.0))
    seat.run(12.0)
    assert seat.passed("m19-90"), seat.result("m19-90")


def test_gear_change_without_the_fix_fails_both_checks() -> None:
    """M41 times out after 5 s (90004): the spindle stays in gear stage 3, where M19 to 90°
    does not count."""
    seat = Seat("gear-change-plc")
    seat.do(GearChange("S", 41))
    seat.run(7.0)
    seat.do(Reset())
    seat.run(1.0)
    seat.do(SpindlePosition("S", 90.0))
    seat.run(12.0)
    assert not seat.passed("gear-2") and not seat.passed("m19-90")
    assert "gear stage 3" in seat.result("m19-90").detail


def test_accel_curve_with_a_ramp_the_drive_can_follow() -> None:
    """The drive manages 2000 °/s²; a_beschl 1800 °/s² of gear record 2 lets it follow:
    M3 S3500 reaches speed after 21000/1800 = 11.7 s and runs on without a trip."""
    seat = Seat("accel-curve")
    seat.param(Scope.AXIS, "S1", {"getriebe[2].slope_profil.a_beschl": 1800})
    seat.mdi("M3 S3500")
    seat.run(13.0)
    assert seat.passed("run-up"), seat.result("run-up")
    seat.run(30.0)
    assert seat.passed("no-trip"), seat.result("no-trip")


def test_accel_curve_with_the_curve_controlled_acceleration() -> None:
    """000 §2.8.4: a hyperbola (typ 1) whose constant part a_konst 1800 °/s² reaches past
    the top speed (n_grenz 3500 rpm) does the same."""
    seat = Seat("accel-curve")
    curve = "getriebe[2].beschl_kennlinie"
    seat.param(
        Scope.AXIS,
        "S1",
        {f"{curve}.typ": 1, f"{curve}.a_konst": 1800, f"{curve}.n_grenz": 21_000_000},
    )
    seat.mdi("M3 S3500")
    seat.run(43.0)
    assert seat.passed("run-up") and seat.passed("no-trip")


def test_accel_curve_not_fixed_fails_both_checks() -> None:
    """At 3000 °/s² the drive falls behind, lag monitoring trips; a_beschl 2500 is still
    too steep."""
    seat = Seat("accel-curve")
    seat.mdi("M3 S3500")
    seat.run(5.0)
    seat.recover("S1")
    seat.param(Scope.AXIS, "S1", {"getriebe[2].slope_profil.a_beschl": 2500})
    seat.mdi("M3 S3500")
    seat.run(30.0)
    assert not seat.passed("run-up") and not seat.passed("no-trip")


def test_c_axis_with_the_handshake_completed_by_hand() -> None:
    """003 §4.1: the NC sets ROTMOD and waits for ROTMOD_Q, which this PLC never gives;
    set by hand within the 5 s, the changeover ends and C positions to 90°."""
    seat = Seat("c-axis")
    seat.mdi("G00 C90")
    seat.run(1.0)
    seat.do(PlcSignal("ROTMOD_Q", True))
    seat.run(4.0)
    assert seat.passed("rotary-mode"), seat.result("rotary-mode")
    assert seat.passed("c-90"), seat.result("c-90")


def test_c_axis_without_the_handshake_fails_both_checks() -> None:
    """Without ROTMOD_Q the changeover times out (90004); orienting the spindle to 90°
    with M19 instead is not C in position."""
    seat = Seat("c-axis")
    seat.mdi("G00 C90")
    seat.run(7.0)
    seat.do(Reset())
    seat.do(SpindlePosition("S", 90.0))
    seat.run(8.0)
    assert not seat.passed("rotary-mode") and not seat.passed("c-90")


def test_a_check_naming_an_axis_the_machine_lacks_is_refused_at_the_start() -> None:
    """Axis names are checked for their form at parse time, against the machine when the
    seat's monitor starts."""
    ex = parse_exercise(GOOD.replace('axis = "X"\nwithin_pct', 'axis = "Y"\nwithin_pct'), "t")
    sim = Simulation()
    m = start_seat(sim, ex)
    with pytest.raises(ValueError, match=r"checks\[0\] \(a\): .*'Y'"):
        ExerciseMonitor(ex.checks, m)
