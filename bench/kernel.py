"""Kernel throughput: simulated cycles per second for one demo machine, and how many demo
machines one core steps at a 1 ms cycle in real time (one shared vectorised kernel); with a
program running on the X/Z path: cycles per second, the interpreter's cost per block, and the
time to load and start a 10 000-block program."""

from __future__ import annotations

import time

from nc_sim.assist.autotune import autotune_experiment
from nc_sim.assist.circle_test import circle_test_experiment
from nc_sim.assist.experiments import multi_gain, sign_check
from nc_sim.assist.frequency_response import frequency_response_experiment
from nc_sim.assist.procedure import LiveRun
from nc_sim.channel.canon import ListSink
from nc_sim.channel.interpreter import interpret
from nc_sim.commands import CycleStart, Mdi, ProgramLoad
from nc_sim.config import MachineConfig, apply_overrides, demo_machine
from nc_sim.params import Scope
from nc_sim.scenario import power_on
from nc_sim.sim import Simulation

CYCLE_S = 0.001


def ideal_machine() -> MachineConfig:
    """The demo lathe with X and Z on the ideal first-order drive (`sim.plant` IDEAL)."""
    cfg = demo_machine()
    for axis in ("X", "Z"):
        apply_overrides(cfg, Scope.AXIS, axis, {"sim.plant": "IDEAL"})
    return cfg


def busy_sim(machines: int, ideal: bool = False) -> Simulation:
    sim = Simulation(CYCLE_S)
    for _ in range(machines):
        m = sim.add(ideal_machine() if ideal else demo_machine())
        power_on(sim, m)  # the drives are ready: the blocks below are accepted and move
        m.submit(Mdi("G01 X250 F3000"))
        m.submit(Mdi("M3 S1500"))
    sim.run(100)  # compile and settle
    return sim


def cycles_per_second(
    machines: int, seconds: float = 2.0, recording: bool = False, ideal: bool = False
) -> float:
    """With `recording`, every cycle's samples go to a record (as a server's sample ring);
    with `ideal`, X and Z run the ideal drive instead of the demo's drive cascade."""
    sim = busy_sim(machines, ideal)
    rec = sim.new_record(1000) if recording else None
    n = 0
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        sim.run(1000, rec)
        n += 1000
    return n / (time.perf_counter() - t0)


def test_program(blocks: int) -> str:
    """Back and forth on X/Z with half circles between: short blocks, look-ahead busy."""
    lines = ["G18 G01 F3000"]
    for i in range(blocks // 2):
        z = -100.0 + (i % 50) * 0.5
        lines.append(f"X{60 + (i % 2) * 2} Z{z:.3f}")
        lines.append(
            f"G03 X{60 + (i % 2) * 2} Z{z + 0.5:.3f} R0.25" if i % 2 else f"G01 Z{z + 0.5:.3f}"
        )
        lines.append("G01")
    return "\n".join(lines[:blocks]) + "\nM30\n"


def path_figures() -> None:
    text = test_program(10_000)
    t0 = time.perf_counter()
    sink = ListSink()
    interpret(text, sink, ("X", "Z"), ("S1",), {"X": 50.0, "Z": -100.0})
    t_interp = time.perf_counter() - t0
    blocks = text.count("\n")
    print(f"interpreter: {t_interp / blocks * 1e6:.1f} µs per block ({blocks} blocks)")
    sim = Simulation(CYCLE_S)
    m = sim.add(demo_machine())
    power_on(sim, m)
    # as the server's warm-up (backend/workers/warmup.py): a short contour loads the path
    # planner's compiled functions before anything is timed
    m.submit(ProgramLoad("warm", "G18 G01 X52 Z-99 F3000\nG03 X54 Z-98 R2\nG01 X56\nM30\n"))
    m.submit(CycleStart())
    sim.run(1000)
    t0 = time.perf_counter()
    m.submit(ProgramLoad("bench", text))
    m.submit(CycleStart())
    sim.run(1)
    t_start = time.perf_counter() - t0
    print(f"10 000-block program: load and start {t_start * 1e3:.0f} ms (bar: < 1000 ms)")
    sim.run(2000)  # compile and get going
    n = 0
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < 2.0:
        sim.run(1000)
        n += 1000
    rate = n / (time.perf_counter() - t0)
    line = m.channel.progress.block_line
    print(
        f"path running on X/Z: {rate:,.0f} cycles/s = {rate * CYCLE_S:,.0f}x real time "
        f"(at line {line}, {m.channel.progress.blocks_done} blocks done)"
    )


def live_assistant_figures() -> None:
    """A live run as a worker steps it: the sign check wants every cycle before the next
    (cycle-by-cycle kernel calls), multi_gain long stretches; simulated cycles per second."""
    for name, start in (
        ("sign check (cycle by cycle)", lambda m: sign_check(m, "X", 50.0, 1000.0)),
        ("multi_gain (in stretches)", lambda m: multi_gain(m, "X", feed_mm_min=200.0)),
    ):
        sim = Simulation(CYCLE_S)
        m = sim.add(demo_machine())
        power_on(sim, m)
        run = LiveRun(m, start, CYCLE_S)
        t0 = time.perf_counter()
        while not run.done:
            n = min(run.want(), 1000)
            rec = sim.new_record(n)
            sim.run(n, rec)
            run.feed(rec)
        rate = run.fed_cycles / (time.perf_counter() - t0)
        print(f"live assistant run, {name}: {rate:,.0f} cycles/s = {rate * CYCLE_S:,.0f}x")


def frf_on_a_copy() -> None:
    """X's mechanics measured by the frequency-response assistant on a copy of the demo
    lathe: PRBS at the torque, 10 averages, 1 Hz to half the drive rate, 30 rpm offset;
    wall time, and what it found against f_ar·√p0342."""
    t0 = time.perf_counter()
    r = frequency_response_experiment(demo_machine(), "X", f_min_hz=1.0, window_mm=150.0)
    wall = time.perf_counter() - t0
    f_r = 65.0 * 2.5**0.5  # the demo X: anti-resonance 65 Hz, p0342 = 2.5
    print(
        f"FRF on a copy (10 averages, 1 Hz to 4 kHz, {r.figure('measured_s'):.1f} s of machine "
        f"time): {wall:.2f} s wall (bar: <= 2 s); resonance {r.figure('resonance_1_hz'):.1f} Hz "
        f"(physics {f_r:.1f}), anti-resonance {r.figure('anti_resonance_1_hz'):.1f} Hz (65.0)"
    )


def circle_on_a_copy() -> None:
    """The circularity test on a copy of the demo lathe: R10 at F1000 in G18, CCW and CW
    with 90° of overrun; simulated seconds per wall second, and the radius change against
    the P loop's R(1 − 1/√(1 + (ω/kv)²)) at kv 20/s. (Once before, so the compiled kernel
    is loaded, as in a running service.)"""
    circle_test_experiment(demo_machine(), direction=3, radius_mm=1.0)
    t0 = time.perf_counter()
    r = circle_test_experiment(demo_machine())
    wall = time.perf_counter() - t0
    radius, feed, kv = 10.0, 1000.0, 20.0
    machine_s = 2 * (2 * 3.14159265 * radius / (feed / 60.0) * 1.5 + 2 * radius / (feed / 60.0))
    shrink = radius * (1 - 1 / (1 + (feed / 60 / radius / kv) ** 2) ** 0.5) * 1000
    print(
        f"circle on a copy (R10 F1000, CCW and CW, about {machine_s:.1f} s of machine time): "
        f"{wall:.2f} s wall = {machine_s / wall:,.0f}x real time (bar: >= 50x); radius change "
        f"{r.figure('radius_change_ccw_um'):.1f} µm (continuous P loop: -{shrink:.1f} µm)"
    )


def autotune_on_a_copy() -> None:
    """The speed-loop autotune on a copy of the demo lathe with X's speed gain at a quarter
    (stiff template): measure the mechanics and the open loop, tune, measure again; wall
    time, and what the measured-again loop keeps against the template."""
    cfg = demo_machine()
    apply_overrides(cfg, Scope.AXIS, "X", {"drive.speed_kp": 0.125})
    t0 = time.perf_counter()
    r = autotune_experiment(cfg, "X", 1)
    wall = time.perf_counter() - t0
    print(
        f"autotune on a copy (measure twice, tune, validate): {wall:.2f} s wall (bar: <= 10 s); "
        f"bandwidth {r.figure('bandwidth_now_hz'):.1f} -> {r.figure('bandwidth_achieved_hz'):.1f} "
        f"Hz, measured again {r.figure('pm_achieved_deg'):.1f}° / {r.figure('gm_achieved_db'):.1f} "
        "dB (template 45° / 8 dB)"
    )


def main() -> None:
    path_figures()
    live_assistant_figures()
    one = cycles_per_second(1)
    print(
        f"one demo machine (X and Z on the drive cascade, 8 drive steps per cycle): "
        f"{one:,.0f} cycles/s = {one * CYCLE_S:,.0f}x real time (bar: >= 300x)"
    )
    ideal = cycles_per_second(1, ideal=True)
    print(
        f"one demo machine, X and Z on the ideal drive: {ideal:,.0f} cycles/s = "
        f"{ideal * CYCLE_S:,.0f}x real time"
    )
    frf_on_a_copy()
    circle_on_a_copy()
    autotune_on_a_copy()
    rec = cycles_per_second(1, recording=True)
    print(f"one demo machine recording every cycle: {rec:,.0f} cycles/s")
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
