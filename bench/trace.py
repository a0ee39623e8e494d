"""Continuous recording to Rerun: extra CPU of 16 channels at 1 kHz over 60 s simulated, and
.rrd bytes per million samples. Also the cost of a 60 s, 16-channel capture's .rrd and CSV.

The demo lathe runs a spindle and axis programme in simulated time. Each run advances the
machine in 250-cycle blocks, as the real-time loop does, and the recorder writes every block
as the service's recorder thread does every 0.25 s. The extra CPU is the process CPU time
(every thread: Rerun encodes and writes on its own threads) with recording minus without, per
simulated second. Bar: <= 5 % of one core.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from api.scope import LevelTriggerModel, ScopeSetupModel
from backend.services import rrd, scope
from backend.services.machines import MachineProxy
from backend.services.recorder import Recorders
from backend.services.store import StoredMachine
from backend.workers.host import MachineHost
from backend.workers.protocol import AddMachine
from nc_sim.commands import Move, SpindleRun
from nc_sim.config import demo_machine

BLOCK = 250  # cycles per loop tick and per recorder pump (0.25 s at 1 kHz)


def programme(host: MachineHost, cycle: int) -> None:
    """Something moving on every axis: spindle speed steps, X and Z back and forth."""
    m = host.machine
    t = cycle // 1000
    if cycle % 5000 == 0:
        m.submit(SpindleRun("S1", 3, 400.0 + 600.0 * ((t // 5) % 3)))
    if cycle % 4000 == 0:
        x = 60.0 if (t // 4) % 2 == 0 else 40.0
        m.submit(Move("X", x, rapid=False, feed_mm_min=1200.0))
        m.submit(Move("Z", -100.0 + x / 2, rapid=False, feed_mm_min=900.0))


def demo(out: Path) -> tuple[MachineHost, MachineProxy]:
    """The demo lathe as a worker holds it, and the gateway's proxy reading its ring."""
    host = MachineHost(AddMachine("demo", "Demo lathe", demo_machine(), 1), out / "demo.ring")
    proxy = MachineProxy(StoredMachine("demo", "Demo lathe", "demo"), demo_machine())
    proxy.link.attach(None, host.info())
    host.advance(20)  # the PLC switches the drives on
    return host, proxy


def run(seconds: float, signals: list[str] | None, out: Path) -> tuple[float, int, int]:
    """CPU s of a run; with signals, also the .rrd bytes and samples written."""
    host, proxy = demo(out)
    recs = Recorders(out)
    rec = recs.begin(proxy, signals) if signals else None
    n = round(seconds / host.cycle_s)
    cpu0 = time.process_time()
    done = 0
    while done < n:
        programme(host, host.cycle)
        host.advance(BLOCK)
        done += BLOCK
        recs.pump()
    if rec is not None:
        info = recs.end(host.id)
        cpu = time.process_time() - cpu0
        return cpu, info.bytes, info.cycles * len(signals or [])
    return time.process_time() - cpu0, 0, 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=60.0, help="simulated seconds per run")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each kind (best is used)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        host, _ = demo(Path(tmp))
        signals = [s.name for s in host.signals if s.kind == "float"][:16]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        run(2.0, signals, out)  # warm up numba, numpy and the Rerun SDK
        base = min(run(args.seconds, None, out)[0] for _ in range(args.repeat))
        runs = [run(args.seconds, signals, out) for _ in range(args.repeat)]
        cpu, size, samples = min(runs)
        extra = cpu - base
        n = len(signals)
        print(f"continuous recording: {n} channels at 1 kHz, {args.seconds:g} s simulated")
        print(f"  simulation alone   {base:6.2f} s CPU")
        print(f"  with recording     {cpu:6.2f} s CPU")
        print(
            f"  extra CPU          {extra:6.2f} s = {100 * extra / args.seconds:5.2f} % of one core"
            "   (bar <= 5 %)"
        )
        print(
            f"  .rrd               {size / 1e6:6.2f} MB for {samples / 1e6:.2f} M samples"
            f" = {size / samples:5.2f} MB per million samples"
            f" ({size / samples:.1f} bytes per sample)"
        )

        # the scope in the real-time loop: 10 cycles per 10 ms tick, 16 channels, armed
        ticks = round(args.seconds / 0.01)
        cost = []
        for armed in (False, True):
            host, proxy = demo(out)
            if armed:
                setup = ScopeSetupModel(
                    channels=signals,
                    length_s=60,
                    pretrigger_pct=50,
                    mode="normal",
                    trigger=LevelTriggerModel(signal="S1.speed_cmd_rpm", level=900),
                )
                engine, drive = scope.engine_setup(proxy, setup)
                host.arm_scope(engine, drive)
            t0 = time.perf_counter()
            for _ in range(ticks):
                programme(host, host.cycle)
                host.advance(10)
            cost.append((time.perf_counter() - t0) / ticks * 1e6)
        print(
            f"scope armed (16 channels, 60 s record, level trigger): {cost[1] - cost[0]:.1f} µs"
            f" extra per 10 ms loop tick ({cost[0]:.1f} µs without)"
        )

        # one full-length capture: 16 channels x 60 000 cycles
        data = np.random.default_rng(1).standard_normal((16, 60_000)).cumsum(axis=1)
        t0 = time.process_time()
        path = out / "capture.rrd"
        rrd.write_capture(path, "bench", "demo", "bench", signals, 1, 0.001, data, [])
        t_rrd = time.process_time() - t0
        print(
            f"60 s capture, 16 channels: .rrd written in {t_rrd:.2f} s CPU,"
            f" {path.stat().st_size / 1e6:.1f} MB"
        )


if __name__ == "__main__":
    main()
