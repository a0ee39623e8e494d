"""The scope in simulated time: exact pre-trigger, trigger cycles, modes, long blocks."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from nc_sim.commands import Accepted, HliWrite, JogStep, Move, SpindlePosition, SpindleRun
from nc_sim.errors import Code
from nc_sim.events import EventLog
from nc_sim.scope import (
    EventKind,
    EventTrigger,
    LevelTrigger,
    Scope,
    ScopeMode,
    ScopeSetup,
    ScopeState,
)
from nc_sim.signals import Signal, machine_signals, signal_columns
from nc_sim.snapshot import AxisState
from tests.nc_sim.sim_helpers import make


class Rig:
    """A demo machine whose every cycle is kept (for comparison) and fed to a scope."""

    def __init__(self, block: int = 7) -> None:
        self.sim, self.m, _ = make()
        self.block = block
        self.scope = Scope(self.sim.kernel.cycle_s)
        self.base = self.sim.cycle  # cycles before the rig recorded (the drives switching on)
        self.full = [self.sim.new_record(0)]
        self.sig = {s.name: s for s in machine_signals(self.m.axes)}

    def signals(self, *names: str) -> list[Signal]:
        return [self.sig[n] for n in names]

    def arm(self, setup: ScopeSetup) -> None:
        hist = np.concatenate(self.full)
        self.scope.arm(setup, self.sim.cycle, hist, self.m.events)

    def run(self, cycles: int) -> None:
        while cycles > 0:
            n = min(self.block, cycles)
            rec = self.sim.new_record(n)
            first = self.sim.cycle + 1
            self.sim.run(n, rec)
            self.full.append(rec)
            self.scope.feed(rec, first, self.m.events)
            cycles -= n

    def column(self, name: str) -> np.ndarray:
        """The signal over every recorded cycle (index 0 is cycle base + 1)."""
        rec = np.concatenate(self.full)
        out: np.ndarray = signal_columns([self.sig[name]], rec)[0]
        return out

    def span(self, name: str, first: int, count: int) -> np.ndarray:
        """The signal of cycles first … first + count - 1."""
        i = first - self.base - 1
        return self.column(name)[i : i + count]

    def cycles_where(self, mask: np.ndarray) -> list[int]:
        return [int(i) + self.base + 1 for i in np.flatnonzero(mask)]


CH = ("S1.speed_cmd_rpm", "S1.pos_act_deg", "S1.lag_deg", "S1.state")


@pytest.mark.parametrize("block", [1, 7, 1000, 5000])
def test_m19_capture_has_the_asked_pretrigger_and_the_trigger_at_the_first_m19_cycle(
    block: int,
) -> None:
    rig = Rig(block)
    rig.run(300)
    setup = ScopeSetup(
        rig.signals(*CH),
        length_cycles=1000,
        pretrigger_pct=25.0,
        trigger=EventTrigger(EventKind.M_START, "S1", 19),
    )
    rig.arm(setup)
    rig.run(123)
    issued_after = rig.sim.cycle
    assert isinstance(rig.m.submit(SpindlePosition("S1", 90.0)), Accepted)
    rig.run(4000)

    assert len(rig.scope.completed) == 1
    rec = rig.scope.completed[0]
    assert rec.trigger_cycle == issued_after + 1  # the first cycle under M19
    assert rec.pre_cycles == 250 and rec.count == 1000
    assert rec.first_cycle == rec.trigger_cycle - 250
    state = rec.data[3]
    assert state[250] == AxisState.POSITIONING and state[249] != AxisState.POSITIONING
    # the record is exactly what the kernel produced in those cycles
    for k, name in enumerate(CH):
        np.testing.assert_array_equal(rec.data[k], rig.span(name, rec.first_cycle, 1000))
    assert rig.scope.state is ScopeState.DONE
    assert any(e.code == Code.EV_M_START and e.m == 19 for e in rec.events)


def test_pretrigger_comes_from_history_when_the_trigger_follows_arming_at_once() -> None:
    rig = Rig()
    rig.run(800)
    rig.arm(
        ScopeSetup(
            rig.signals("S1.speed_cmd_rpm"),
            length_cycles=1000,
            pretrigger_pct=50.0,
            trigger=EventTrigger(EventKind.M_START, "S1"),
        )
    )
    at = rig.sim.cycle
    rig.m.submit(SpindleRun("S1", 3, 500.0))
    rig.run(600)
    (rec,) = rig.scope.completed
    assert rec.trigger_cycle == at + 1 and rec.pre_cycles == 500
    np.testing.assert_array_equal(rec.data[0], rig.span("S1.speed_cmd_rpm", at - 499, 1000))


def _two_speed_ramps(rig: Rig) -> None:
    rig.m.submit(SpindleRun("S1", 3, 1000.0))
    rig.run(1500)
    rig.m.submit(SpindleRun("S1", 5))
    rig.run(1500)
    rig.m.submit(SpindleRun("S1", 3, 1000.0))
    rig.run(1500)


def _crossings(rig: Rig, level: float) -> list[int]:
    """Cycles where the speed command goes from below to at-or-above level."""
    x = rig.column("S1.speed_cmd_rpm")
    return rig.cycles_where(np.r_[False, (x[1:] >= level) & (x[:-1] < level)])


@pytest.mark.parametrize("mode", [ScopeMode.SINGLE, ScopeMode.NORMAL])
def test_level_trigger_fires_on_the_first_crossing_and_single_mode_only_once(
    mode: ScopeMode,
) -> None:
    rig = Rig(block=64)
    rig.run(100)
    sig = rig.sig["S1.speed_cmd_rpm"]
    rig.arm(ScopeSetup([sig], 500, 10.0, mode, LevelTrigger(sig, 500.0, True, 5.0)))
    _two_speed_ramps(rig)
    crossings = _crossings(rig, 500.0)
    assert len(crossings) == 2  # M3 twice; M5 crossed downwards
    got = [r.trigger_cycle for r in rig.scope.completed]
    assert got == (crossings[:1] if mode is ScopeMode.SINGLE else crossings)
    for r in rig.scope.completed:
        assert r.data[0][50] >= 500.0 > r.data[0][49]


def test_falling_edge_and_hysteresis_ignore_ripple_around_the_level() -> None:
    rig = Rig(block=10)
    rig.run(50)
    sig = rig.sig["S1.speed_cmd_rpm"]
    rig.arm(ScopeSetup([sig], 200, 0.0, ScopeMode.NORMAL, LevelTrigger(sig, 500.0, False, 50.0)))
    _two_speed_ramps(rig)
    x = rig.column("S1.speed_cmd_rpm")
    falls = rig.cycles_where(np.r_[False, (x[1:] <= 500.0) & (x[:-1] > 500.0)])
    assert len(falls) == 1
    assert [r.trigger_cycle for r in rig.scope.completed] == falls


def test_a_level_already_beyond_the_edge_at_arming_waits_for_a_real_crossing() -> None:
    rig = Rig()
    rig.m.submit(SpindleRun("S1", 3, 1000.0))
    rig.run(1500)  # above 500 rpm when armed
    sig = rig.sig["S1.speed_cmd_rpm"]
    rig.arm(ScopeSetup([sig], 100, 0.0, ScopeMode.SINGLE, LevelTrigger(sig, 500.0)))
    rig.run(500)
    assert rig.scope.completed == [] and rig.scope.state is ScopeState.ARMED


def test_a_crossing_in_the_first_cycle_after_arming_counts() -> None:
    rig = Rig()
    rig.run(500)
    sig = rig.sig["X.vel_cmd_mm_min"]
    rig.arm(ScopeSetup([sig], 300, 10.0, ScopeMode.SINGLE, LevelTrigger(sig, 1.0)))
    at = rig.sim.cycle
    assert isinstance(rig.m.submit(Move("X", 75.0, rapid=False, feed_mm_min=600)), Accepted)
    rig.run(400)
    (rec,) = rig.scope.completed
    assert rec.trigger_cycle == at + 1 and rec.data[0][30] > 1.0 and rec.data[0][29] == 0.0


def test_a_trigger_soon_after_power_on_keeps_the_history_back_to_cycle_1() -> None:
    sim, m, _ = make(settle=0)
    scope = Scope(sim.kernel.cycle_s)
    sig = machine_signals(m.axes)
    trig = EventTrigger(EventKind.M_START, "S1", 3)
    scope.arm(
        ScopeSetup(sig[:2], 1000, 50.0, ScopeMode.SINGLE, trig), 0, sim.new_record(0), EventLog()
    )
    rec = sim.new_record(100)
    sim.run(100, rec)
    scope.feed(rec, 1, m.events)
    m.submit(SpindleRun("S1", 3, 100.0))
    rec = sim.new_record(1000)
    sim.run(1000, rec)
    scope.feed(rec, 101, m.events)
    (r,) = scope.completed
    assert r.trigger_cycle == 101 and r.first_cycle == 1 and r.pre_cycles == 100
    assert r.count == 1000


def test_a_trigger_before_the_pretrigger_is_filled_is_ignored() -> None:
    rig = Rig()  # its history starts after power-on (the settle cycles are not kept)
    rig.run(100)
    sig = rig.sig["S1.speed_cmd_rpm"]
    trig = EventTrigger(EventKind.M_START, "S1")
    rig.arm(ScopeSetup([sig], 1000, 50.0, ScopeMode.SINGLE, trig))
    rig.m.submit(SpindleRun("S1", 3, 100.0))  # 100 cycles of history, 500 asked: ignored
    rig.run(600)
    assert rig.scope.completed == [] and rig.scope.state is ScopeState.ARMED
    at = rig.sim.cycle
    rig.m.submit(SpindleRun("S1", 3, 200.0))  # now the history is there
    rig.run(600)
    (r,) = rig.scope.completed
    assert r.trigger_cycle == at + 1 and r.pre_cycles == 500


def test_force_takes_the_newest_cycle_and_roll_keeps_the_newest_window() -> None:
    rig = Rig()
    rig.run(400)
    sig = rig.sig["X.pos_act_mm"]
    rig.arm(ScopeSetup([sig], 100, 50.0, ScopeMode.SINGLE, EventTrigger(EventKind.JOB_ERROR)))
    rig.run(10)
    rig.scope.force()
    rig.run(60)
    (rec,) = rig.scope.completed
    t = rig.base + 410
    assert rec.forced and rec.trigger_cycle == t and rec.first_cycle == t - 50

    rig.arm(ScopeSetup([sig], 300, 0.0, ScopeMode.ROLL))
    rig.run(1000)
    snap = rig.scope.snapshot()
    assert snap is not None and snap.first_cycle == rig.sim.cycle - 299 and snap.count == 300
    np.testing.assert_array_equal(snap.data[0], rig.column("X.pos_act_mm")[-300:])
    assert snap.first_cycle == rig.sim.cycle - 299


def test_setup_limits_name_what_is_wrong() -> None:
    s = machine_signals(make()[1].axes)
    with pytest.raises(ValueError, match="channels: 1 … 16"):
        ScopeSetup(s[:17], 100, trigger=EventTrigger(EventKind.JOB_ERROR)).check()
    with pytest.raises(ValueError, match="60000 cycles"):
        ScopeSetup(s[:1], 60_001, trigger=EventTrigger(EventKind.JOB_ERROR)).check()
    with pytest.raises(ValueError, match="needs a trigger"):
        ScopeSetup(s[:1], 100).check()


@pytest.mark.parametrize(
    ("hysteresis", "rising", "expected"),
    [
        (0.5, True, [3, 15]),
        (0.0, True, [3, 7, 11, 15]),
        (0.5, False, [19]),
        (0.0, False, [5, 9, 13, 19]),
    ],
)
def test_hysteresis_ignores_ripple_around_the_level(
    hysteresis: float, rising: bool, expected: list[int]
) -> None:
    # each value held two cycles, so a 2-cycle capture ends before the next one starts
    x = np.repeat([0.0, 10.2, 9.9, 10.1, 9.95, 10.3, 0.0, 12.0, 12.0, 0.0], 2)
    rec = np.zeros((x.size, 1, 18))
    rec[:, 0, 0] = x
    sig = Signal("T.x", "T", 0, 0, 1.0, "", "float")
    scope = Scope(0.001)
    scope.arm(
        ScopeSetup([sig], 2, 0.0, ScopeMode.NORMAL, LevelTrigger(sig, 10.0, rising, hysteresis)),
        0,
        rec[:0],
        EventLog(),
    )
    scope.feed(rec, 1, EventLog())
    assert [r.trigger_cycle for r in scope.completed] == expected


def _first_rise(rig: Rig, name: str, after: int) -> int:
    """First cycle after `after` where the signal changes from the cycle before."""
    x = rig.column(name)
    i = after - rig.base  # index of cycle after + 1
    return next(rig.base + 1 + k for k in range(i, x.size) if x[k] != x[k - 1])


def test_event_triggers_fire_in_the_cycle_the_record_shows_the_event() -> None:
    def capture(kind: EventKind, act: Callable[[Rig], object], run: int = 6000) -> tuple[Rig, int]:
        rig = Rig(block=50)
        rig.run(2000)
        sig = rig.signals("S1.speed_reached", "S1.gear", "S1.in_position", "X.job_error")
        rig.arm(ScopeSetup(sig, 200, 50.0, ScopeMode.SINGLE, EventTrigger(kind)))
        at = rig.sim.cycle
        act(rig)
        rig.run(run)
        (r,) = rig.scope.completed
        assert r.trigger_cycle is not None
        return rig, at

    # speed reached: the first cycle the speed_reached bit is set
    rig, at = capture(EventKind.SPEED_REACHED, lambda r: r.m.submit(SpindleRun("S1", 3, 1000.0)))
    t = rig.scope.completed[0].trigger_cycle
    assert t == _first_rise(rig, "S1.speed_reached", at)
    # gear change: the first cycle in the new gear stage (S300 needs M40 from M42)
    rig, at = capture(EventKind.GEAR_CHANGE, lambda r: r.m.submit(SpindleRun("S1", 3, 300.0)), 9000)
    assert rig.scope.completed[0].trigger_cycle == _first_rise(rig, "S1.gear", at)
    # M19 done: the cycle the spindle comes into its exact-stop window for good
    rig, at = capture(EventKind.M19_DONE, lambda r: r.m.submit(SpindlePosition("S1", 90.0)), 9000)
    t = rig.scope.completed[0].trigger_cycle or 0
    pos = rig.column("S1.in_position")
    assert pos[t - rig.base - 1] == 1 and pos[t - rig.base - 2] == 0

    # job error (a step without enables): the first cycle with X's job error set
    def refused(r: Rig) -> None:
        r.m.submit(HliWrite("DriveOn", 0, "X"))
        r.m.submit(JogStep("X", 1.0))

    rig, at = capture(EventKind.JOB_ERROR, refused, 300)
    assert rig.scope.completed[0].trigger_cycle == _first_rise(rig, "X.job_error", at) == at + 1
