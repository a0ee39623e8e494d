"""The browser HMI under load, in headless Debian Chromium against the real service.

1. Live plot: one plot with 8 signals at 1 kHz in a 10 s window (10 000 points per trace),
   spindle turning and X jogging, 10 s: redraws per second (uPlot `setData` calls, at most
   50 a second and only when new samples came) and animation frames per second (the plot
   asks for one only to draw). Bar: >= 50 redraws/s.
2. Click-to-motion: a real mouse click on M3 to the arrival of the first telemetry sample in
   which S1.speed_cmd_rpm rises, both timed in the page (performance.now). Bar: p99 <= 100 ms.

Also prints, for each part, the overruns summed over every worker (and one line per worker)
and the CPU of the gateway and of the workers.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from playwright.sync_api import Page, expect

from bench.service import Meter, Run
from tests.backend.server import Server
from tests.e2e.browser import chromium, open_hmi

SIGNALS = [
    "S1.speed_cmd_rpm",
    "S1.speed_act_rpm",
    "S1.lag_deg",
    "S1.accel_cmd_deg_s2",
    "X.pos_cmd_mm",
    "X.pos_act_mm",
    "X.lag_mm",
    "X.vel_act_mm_min",
]

ARM_JS = """() => { window.__motion = new Promise((resolve) => {
  const ib = window.inbetrieb;
  const button = document.querySelector('[data-testid="m3"]');
  let pressed = null;
  button.addEventListener('pointerdown', () => { pressed = performance.now(); }, { once: true });
  const listener = (r) => {
    if (pressed !== null && r.latest('S1.speed_cmd_rpm') > 0) {
      ib.frameListeners.delete(listener);
      resolve(performance.now() - pressed);
    }
  };
  ib.frameListeners.add(listener);
}); }"""


def meter(srv: Server) -> Meter:
    """Started measurement of the service (workers' overruns, CPU)."""
    assert srv.proc is not None
    m = Meter(srv.http, srv.proc.pid)
    m.start()
    return m


def print_service(run: Run) -> None:
    print(
        f"  overruns of every worker {run.overruns}   CPU gateway "
        f"{100 * run.gateway_cpu_s / run.wall_s:.0f} % workers "
        f"{100 * run.worker_cpu_s / run.wall_s:.0f} %"
    )
    run.print_workers("    ")


def plot_fps(page: Page, srv: Server, seconds: float) -> None:
    page.get_by_test_id("s-input").fill("1000")
    page.get_by_test_id("m3").click()  # the page now holds control: its commands go from it
    page.get_by_test_id("mdi-input").fill("G01 X250 F600")
    page.get_by_test_id("mdi-send").click()
    page.get_by_test_id("tab-Plots").click()
    plot = page.locator(".liveplot").first
    expect(plot).to_be_visible()
    time.sleep(10.5)  # fill the 10 s window first
    points = page.evaluate(f"window.inbetrieb.rings().window(10, {json.dumps(SIGNALS)})[0].length")
    m = meter(srv)
    c0 = page.evaluate(
        "({...window.inbetrieb.fps, ...window.inbetrieb.frames, t: performance.now()})"
    )
    time.sleep(seconds)
    c1 = page.evaluate(
        "({...window.inbetrieb.fps, ...window.inbetrieb.frames, t: performance.now()})"
    )
    service = m.stop()
    dt = (c1["t"] - c0["t"]) / 1000
    print(
        f"live plot: {len(SIGNALS)} signals at 1 kHz, 10 s window "
        f"({points} points per trace), {dt:.1f} s"
    )
    print(
        f"  redraws {(c1['draws'] - c0['draws']) / dt:6.1f} /s   animation frames "
        f"{(c1['frames'] - c0['frames']) / dt:6.1f} /s   telemetry frames "
        f"{(c1['received'] - c0['received']) / dt:5.1f} /s   decimated "
        f"{c1['decimated'] - c0['decimated']}   skipped cycles "
        f"{c1['skippedCycles'] - c0['skippedCycles']}"
    )
    print_service(service)
    page.get_by_test_id("reset").click()


def click_to_motion(page: Page, srv: Server, n: int) -> None:
    page.get_by_test_id("tab-Operate").click()
    page.get_by_test_id("s-input").fill("1000")
    # the reset after the plot part brakes the spindle from 1000 rpm: seconds to standstill
    expect(page.get_by_test_id("lamp-stopped-S1")).to_have_attribute("data-on", "1", timeout=15_000)
    m = meter(srv)
    lat = []
    for _ in range(n):
        page.evaluate(ARM_JS)
        page.get_by_test_id("m3").click()
        lat.append(float(page.evaluate("() => window.__motion")))
        page.get_by_test_id("m5").click()
        expect(page.get_by_test_id("lamp-stopped-S1")).to_have_attribute(
            "data-on", "1", timeout=15_000
        )
    service = m.stop()
    a = np.array(lat)
    print(
        f"click-to-motion, {n} M3 clicks "
        "(press -> first rising S1.speed_cmd_rpm sample in the page)"
    )
    print(
        f"  p50 {np.percentile(a, 50):6.1f} ms   p99 {np.percentile(a, 99):6.1f} ms   "
        f"max {a.max():6.1f} ms"
    )
    print_service(service)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--clicks", type=int, default=100)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        srv = Server(Path(tmp) / "bench.sqlite").start()
        try:
            with chromium() as browser:
                page = open_hmi(browser, srv.base, "demo", plot_rate=50)  # the HMI's default
                page.evaluate(
                    "(s) => localStorage.setItem('inbetrieb.plots.demo', s)",
                    json.dumps([{"id": "bench", "signals": SIGNALS, "windowS": 10}]),
                )
                page.reload()
                expect(page.get_by_test_id("lamp-connection")).to_have_attribute("data-on", "1")
                plot_fps(page, srv, args.seconds)
                click_to_motion(page, srv, args.clicks)
        finally:
            srv.close()


if __name__ == "__main__":
    main()
