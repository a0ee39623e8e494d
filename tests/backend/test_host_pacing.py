"""A machine's real-time factor as its worker reports it: simulated seconds per wall second,
from when the stepping really ended (a clock of the test's own, never the wall)."""

from __future__ import annotations

import time

from backend.workers.host import MachineHost
from backend.workers.protocol import AddMachine
from backend.workers.threaded import QueueChannel
from backend.workers.worker import Worker
from nc_sim.config import demo_machine

PERIOD_S = 0.01


def host_on(clock: list[float]) -> MachineHost:
    host = MachineHost(AddMachine("m", "m", demo_machine(), 1), None)
    host.clock = lambda: clock[0]
    host.pacing.anchor_mono = 0.0  # cycle 0 at t = 0
    return host


def test_a_worker_on_time_steps_in_real_time() -> None:
    clock = [0.0]
    host = host_on(clock)
    for k in range(1, 101):  # 1 s of ticks, each done right at its deadline
        clock[0] = k * PERIOD_S
        host.tick(k * PERIOD_S, 0.0)
    assert host.cycle == 1000
    assert abs(host.rt_factor() - 1.0) < 1e-9


def test_a_starved_worker_shows_below_1() -> None:
    """Every tick steps to its deadline's cycle, but the worker only gets to it 5 ms late
    and later each time (it falls behind): 1 s of simulated time took 1.5 s of wall time.
    Cycles per deadline would still read 1.000."""
    clock = [0.0]
    host = host_on(clock)
    for k in range(1, 101):
        clock[0] = k * PERIOD_S * 1.5
        host.tick(k * PERIOD_S, 0.0)
    assert abs(host.rt_factor() - 1 / 1.5) < 1e-6


def test_a_stalled_worker_shows_the_stall_and_then_the_catch_up() -> None:
    """A worker that stops for half a second, then steps the missed cycles at once: right
    after the stall the last second shows 0.5 s simulated in 0.99 s of wall time; once
    caught up, 0.99 s in 0.991 s."""
    clock = [0.0]
    host = host_on(clock)
    for k in range(1, 51):  # 0.5 s on time
        clock[0] = k * PERIOD_S
        host.tick(k * PERIOD_S, 0.0)
    clock[0] = 1.0  # nothing for 0.5 s: the next tick, late, steps to its own deadline
    host.tick(0.51, 0.0)
    assert abs(host.rt_factor() - 0.5 / 0.99) < 1e-6
    clock[0] = 1.001  # the next deadline is now: 490 cycles in 1 ms of wall time
    host.tick(1.0, 0.0)
    assert host.cycle == 1000
    assert abs(host.rt_factor() - 0.99 / 0.991) < 1e-6


def test_a_worker_sleeps_only_while_nothing_is_due() -> None:
    """A worker whose machines are all paused waits for a request instead of waking every
    period; a running machine, a single step in progress or a request just served keep it
    ticking (the served request's effects go out with the next status)."""
    channel = QueueChannel(lambda push: None)
    worker = Worker(channel, PERIOD_S, None)
    assert worker.idle()  # no machines
    host = host_on([0.0])
    worker.hosts[host.id] = host
    assert not worker.idle()  # a new machine runs in real time
    host.set_mode("pause")
    assert worker.idle()
    host.start_step(10)
    assert not worker.idle()
    host.pacing.step_to = None
    worker.awake_until = time.monotonic() + 60.0  # as after a request served while idle
    assert not worker.idle()
    worker.awake_until = 0.0
    host.set_mode("fast")
    assert not worker.idle()
