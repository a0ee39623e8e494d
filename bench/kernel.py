"""Kernel throughput: simulated cycles per second for one demo machine, and how many demo
machines one core steps at a 1 ms cycle in real time (one shared vectorised kernel)."""

from __future__ import annotations

import time

from nc_sim.commands import Mdi
from nc_sim.machine.config import demo_machine
from nc_sim.scenario import power_on
from nc_sim.sim import Simulation

CYCLE_S = 0.001


def busy_sim(machines: int) -> Simulation:
    sim = Simulation(CYCLE_S)
    for _ in range(machines):
        m = sim.add(demo_machine())
        power_on(sim, m)  # the drives are ready: the blocks below are accepted and move
        m.submit(Mdi("G01 X250 F3000"))
        m.submit(Mdi("M3 S1500"))
    sim.run(100)  # compile and settle
    return sim


def cycles_per_second(machines: int, seconds: float = 2.0) -> float:
    sim = busy_sim(machines)
    n = 0
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        sim.run(1000)
        n += 1000
    return n / (time.perf_counter() - t0)


def main() -> None:
    one = cycles_per_second(1)
    print(f"one demo machine: {one:,.0f} cycles/s = {one * CYCLE_S:,.0f}x real time (bar: >= 200x)")
    lo, hi = 1, 2
    while cycles_per_second(hi, 1.0) * CYCLE_S >= 1.0:
        lo, hi = hi, hi * 2
    while hi - lo > max(1, lo // 20):
        mid = (lo + hi) // 2
        if cycles_per_second(mid, 1.0) * CYCLE_S >= 1.0:
            lo = mid
        else:
            hi = mid
    rate = cycles_per_second(lo, 2.0)
    print(
        f"demo machines in real time on one core at 1 ms: {lo} "
        f"({rate * CYCLE_S:.2f}x real time with {lo} machines; bar: >= 100)"
    )


if __name__ == "__main__":
    main()
