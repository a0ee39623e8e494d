"""One procedure, two drivers: on a copy in simulated time, and live, on a machine stepped
by someone else in chunks of its own (as a worker's real-time loop does). The cycles are the
same, so the answers are identical; a cancel stops the motion the run started."""

from __future__ import annotations

import random

from nc_sim.assist.experiments import multi_gain, multi_gain_experiment, sign_check
from nc_sim.assist.procedure import LiveRun, Start
from nc_sim.config import MachineConfig
from nc_sim.machine.machine import Machine
from nc_sim.scenario import power_on
from nc_sim.sim import Simulation
from nc_sim.snapshot import AxisState
from tests.nc_sim.assist.test_assist_experiments import lathe


def _powered(cfg: MachineConfig) -> tuple[Simulation, Machine]:
    sim = Simulation(cfg.cycle_s)
    m = sim.add(cfg)
    power_on(sim, m)
    return sim, m


def _drive(sim: Simulation, run: LiveRun, seed: int, until_s: float = 60.0) -> None:
    """Step as a worker does: chunks of any size up to what the run wants."""
    rnd = random.Random(seed)
    while not run.done and sim.cycle * sim.kernel.cycle_s < until_s:
        n = min(run.want(), rnd.randint(1, 40))
        rec = sim.new_record(n)
        sim.run(n, rec)
        run.feed(rec)


def test_live_in_chunks_answers_as_the_copy_does() -> None:
    """The issue's wrong drive gain (22857 digits per 1 m/min against 10000): f = 2.2857 both
    ways, and the figures equal to the last bit (same cycles, same records)."""
    cfg = lathe(X={"sim.drive_gain": 22857})
    preview = multi_gain_experiment(cfg, "X", feed_mm_min=200)
    sim, m = _powered(lathe(X={"sim.drive_gain": 22857}))
    run = LiveRun(m, lambda m: multi_gain(m, "X", feed_mm_min=200), sim.kernel.cycle_s)
    _drive(sim, run, seed=1)
    assert run.error is None and run.result is not None
    assert run.result.figure("f") == preview.figure("f")
    assert abs(run.result.figure("f") - 2.2857) < 0.01 * 2.2857
    assert run.result.changes == preview.changes
    assert m.axis("X").state is AxisState.STANDSTILL  # a live run ends at rest


def test_progress_names_the_phase_and_the_planned_time() -> None:
    sim, m = _powered(lathe())
    run = LiveRun(m, lambda m: multi_gain(m, "X", feed_mm_min=200), sim.kernel.cycle_s)
    phase, elapsed_s, planned_s = run.progress()
    assert "200" in phase and elapsed_s == 0.0
    # 2 s ramp allowance + 5 · 3 / kv(20/s) settling + 1 s window, recorded 1 s more, and
    # the move's target a further second away: 5.75 s
    assert abs(planned_s - (2.0 + 15.0 / 20.0 + 1.0 + 2.0)) < 1e-9


def test_cancel_brakes_the_axis_the_run_moved() -> None:
    sim, m = _powered(lathe())
    run = LiveRun(m, lambda m: multi_gain(m, "X", feed_mm_min=600), sim.kernel.cycle_s)
    rec = sim.new_record(500)
    sim.run(500, rec)
    run.feed(rec[: run.want()])
    assert m.axis("X").state is AxisState.MOVING
    run.cancel("cancelled by the engineer")
    assert run.done and run.error == "cancelled by the engineer" and run.want() == 0
    sim.run(2000)
    assert m.axis("X").state is AxisState.STANDSTILL
    assert m.axis("X").error_event is None


def test_a_refused_start_is_an_error_not_a_motion() -> None:
    """S1 at 50000 rpm is beyond every gear: the NC refuses, the run ends before a cycle."""
    sim, m = _powered(lathe())
    start: Start = lambda m: multi_gain(m, "S1", speed_rpm=50000)  # noqa: E731
    run = LiveRun(m, start, sim.kernel.cycle_s)
    assert run.done and run.error is not None and "refused" in run.error


def test_live_sign_check_switches_the_servo_off_within_the_cycle_it_runs_away() -> None:
    """004 §3.5 live, stepped in chunks: an inverted encoder is found below 10 % of lag_max."""
    sim, m = _powered(lathe(X={"sim.encoder_inverted": 1}))
    run = LiveRun(m, lambda m: sign_check(m, "X"), sim.kernel.cycle_s)
    _drive(sim, run, seed=2)
    assert run.result is not None
    assert {c.parameter for c in run.result.changes} == {"lr_hw[0].vz_istw"}
    assert run.result.figure("max_lag") < 0.1 * run.result.figure("lag_max")
