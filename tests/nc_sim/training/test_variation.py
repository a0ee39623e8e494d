"""Per-seat numbers and locked assistants in an exercise file: what is drawn, that
neighbours differ, that a restart draws the same, and the errors a wrong file gets."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

from nc_sim.faults import DriveGainWrong
from nc_sim.training.exercise import ExerciseError, parse_exercise
from nc_sim.training.template import check_fits
from nc_sim.training.variation import seat_seed

MULTI_GAIN = (Path(__file__).resolve().parents[3] / "exercises" / "multi-gain.toml").read_text()
VARY = {"key": 'key = "faults[0].factor"', "min": "min = 0.35", "max": "max = 0.6"}
VARY["step"] = "step = 0.005"  # the lines of multi-gain.toml's [[vary]]


def test_every_seat_of_a_class_gets_its_own_factor_on_the_grid() -> None:
    ex = parse_exercise(MULTI_GAIN, "multi-gain.toml")
    assert ex.locked == ("multi-gain", "multi-gain-calc", "loop-gain")
    seed = seat_seed("class-1", ex.id)
    drawn = [ex.for_seat(seed, n)[1]["faults[0].factor"] for n in range(1, 51)]
    grid = {round(0.35 + 0.005 * k, 12) for k in range(51)}
    assert set(drawn) <= grid and len(set(drawn)) == 50  # 51 grid points: no two seats alike
    # neighbours a good part of the range apart: a neighbour's answer does not pass (1 %)
    assert min(abs(a - b) for a, b in itertools.pairwise(drawn)) >= 0.05
    again = [ex.for_seat(seat_seed("class-1", ex.id), n)[1] for n in (1, 2)]
    assert [v["faults[0].factor"] for v in again] == drawn[:2]  # after a restart: the same
    other = [ex.for_seat(seat_seed("class-2", ex.id), n)[1]["faults[0].factor"] for n in (1, 2)]
    assert other != drawn[:2]
    seat_ex, values = ex.for_seat(seed, 7)
    fault = seat_ex.faults[0].fault
    assert isinstance(fault, DriveGainWrong) and fault.factor == values["faults[0].factor"]
    assert ex.faults[0].fault == DriveGainWrong("X", 0.4375)  # the file's stays as it is


@pytest.mark.parametrize(
    ("change", "key", "says"),
    [
        ('key = "faults[0].axis"', "vary[0].key", "a number of drive_gain_wrong: factor"),
        ('key = "faults[2].factor"', "vary[0].key", "an entry of [[faults]] (it has 1)"),
        ('key = "start[0].value"', "vary[0].key", "an entry of [[start]] (it has 0)"),
        ('key = "checks[0].points"', "vary[0].key", "faults[i].<field> or start[i].value"),
        ("min = -0.35", "vary[0].min", "factor: a number > 0"),
        ("max = 0.2", "vary[0].max", "a number > 0.35"),
        ("step = 0.000001", "vary[0].step", "at least (max − min)/100000"),
    ],
)
def test_a_wrong_variation_is_refused_naming_its_key(change: str, key: str, says: str) -> None:
    text = MULTI_GAIN.replace(VARY[change.split(" = ")[0]], change)
    assert text != MULTI_GAIN
    with pytest.raises(ExerciseError) as e:
        parse_exercise(text, "x.toml")
    assert e.value.key == key and says in e.value.allowed, str(e.value)


def test_a_locked_assistant_must_be_one_of_the_service() -> None:
    text = MULTI_GAIN.replace('"multi-gain-calc",', '"multi-gain-calculator",')
    with pytest.raises(ExerciseError) as e:
        parse_exercise(text, "x.toml")
    assert e.value.key == "locked_assistants[1]" and "multi-gain-calc" in e.value.allowed


def test_a_varied_starting_value_is_checked_at_both_ends() -> None:
    """getriebe[0].kv takes 1 and up (P-AXIS-00099, 0.01/s): a range reaching down to −500
    fails at its bottom although the file's own value fits."""
    base = (
        'id = "kv"\ntitle = "T"\nsummary = "S"\ntask = "T"\npar_time_s = 60\nmachine = "demo"\n'
        '[[start]]\nscope = "axis"\ntarget = "X"\nname = "getriebe[0].kv"\nvalue = 2000\n'
        '[[checks]]\nid = "g"\ntext = "G"\npoints = 10\nkind = "gain"\naxis = "X"\n'
        "within_pct = 1.0\n"
        '[[vary]]\nkey = "start[0].value"\nmax = 2500\nstep = 100\n'
    )
    check_fits(parse_exercise(base + "min = 1500\n", "ok.toml"), "ok.toml")
    with pytest.raises(ValueError, match=r"getriebe\[0\]\.kv"):
        check_fits(parse_exercise(base + "min = -500\n", "bad.toml"), "bad.toml")
