"""The resolution check (004 §3.4) by its descriptor: an encoder delivering k times the
increments per unit that wegaufz/wegaufn assume makes the NC count k times the true travel;
the check finds k from the travels and proposes wegaufz/wegaufn · k (geometry: the NC's
position is increments / (wegaufz/wegaufn), so with k times the increments the right value is
k times the set one)."""

from __future__ import annotations

from fractions import Fraction

import pytest

from nc_sim.assist.procedure import LiveRun
from nc_sim.assist.result import ExperimentError, Result
from nc_sim.assist.run import live, run
from nc_sim.faults import EncoderResolutionWrong
from tests.nc_sim.assist.test_assist_experiments import lathe
from tests.nc_sim.assist.test_assist_procedure import _drive, _powered


def _pair(r: Result) -> Fraction:
    after = {c.parameter: c.after for c in r.changes}
    return Fraction(int(after["getriebe[0].wegaufz"]), int(after["getriebe[0].wegaufn"]))


def test_a_wrong_encoder_resolution_is_found_live_and_corrected_by_k() -> None:
    """The fault's factor 1.02 on X: k = 1.02 from a 40 mm move, the proposal 1 · 1.02
    (the demo's wegaufz/wegaufn is 1/1)."""
    sim, m = _powered(lathe())
    m.inject(EncoderResolutionWrong("X", 1.02))
    job = LiveRun(m, live("resolution-check", {"axis": "X", "distance": 40.0}), sim.kernel.cycle_s)
    _drive(sim, job, seed=3)
    assert job.error is None and job.result is not None
    r = job.result
    assert r.figure("k") == pytest.approx(1.02, abs=20e-6)
    assert r.figure("deviation_ppm") == pytest.approx(20000, abs=20)
    assert float(_pair(r)) == pytest.approx(1.02, abs=20e-6)
    assert {c.before for c in r.changes} == {1}


def test_a_measured_travel_given_by_the_engineer_decides() -> None:
    """On a copy, the NC moves Z by -50 mm; the dial gauge says 49.9 mm: k = 50/49.9."""
    r = run("resolution-check", lathe(), {"axis": "Z", "distance": -50.0, "measured": -49.9})
    assert r.figure("nc_travel") == pytest.approx(-50.0, abs=2e-4)  # two increments of 0.1 µm
    assert r.figure("k") == pytest.approx(50 / 49.9, rel=5e-6)
    assert _pair(r) == Fraction(500, 499)  # the simplest fraction within what was measured


def test_travels_that_agree_propose_nothing() -> None:
    """The copy's plant is right: the travels agree within what the measurement resolves."""
    r = run("resolution-check", lathe(), {"axis": "X", "distance": 10.0})
    assert abs(r.figure("deviation_ppm")) <= r.figure("tolerance_ppm")
    assert r.changes == () and r.ok


@pytest.mark.parametrize(
    ("inputs", "why"),
    [
        (
            {"axis": "X", "distance": 2000.0},
            "distance: 2000 is out of range (≥ -1000 and ≤ 1000 mm)",
        ),
        (
            {"axis": "X", "feed_mm_min": 0.0},
            "feed_mm_min: 0 is out of range (> 0 and ≤ 100000 mm/min)",
        ),
        ({"distance": 1.0}, "axis: a value is needed"),
        ({"axis": "X", "speed": 1.0}, "speed: not an input of resolution-check"),
        ({"axis": "Q"}, "no axis Q"),
        ({"axis": "X", "measured": -10.0}, "not the move's way"),
    ],
)
def test_inputs_are_checked_against_the_descriptor(inputs: dict[str, object], why: str) -> None:
    with pytest.raises(ExperimentError, match=why.replace("(", r"\(").replace(")", r"\)")):
        run("resolution-check", lathe(), inputs)
