"""Before the real-time loop starts: load every compiled kernel function and calm the GC.

A compiled function is loaded from numba's cache on its first call, which holds the GIL for
milliseconds; if that first call came from a request handler, the loop thread would miss its
deadline. Short scripted sessions on scratch demo machines call them all (the path
planner's with a program). Freezing the
objects alive after start-up keeps later full garbage collections short for the same reason.
"""

from __future__ import annotations

import gc

from nc_sim.config import demo_machine
from nc_sim.scenario import run_scenario

_SESSION = {
    "duration_s": 3.0,
    "actions": [
        {"t_s": 0.01, "mdi": "M3 S1000"},
        {"t_s": 0.02, "move": {"axis": "X", "target": 60.0, "rapid": False, "feed_mm_min": 600}},
        {"t_s": 0.03, "jog": {"axis": "Z", "step": 1.0}},
        {"t_s": 0.5, "spindle": {"name": "S", "gear": 44}},
        {"t_s": 1.0, "spindle": {"name": "S", "pos_deg": 90.0}},
        {"t_s": 1.5, "home": "X"},
        {"t_s": 2.0, "emergency_stop": True},
        {"t_s": 2.5, "reset": True},
    ],
}
# a short contour (a corner, an arc) held on its way: the path planner's compiled functions
_PROGRAM_SESSION = {
    "duration_s": 1.0,
    "actions": [
        {"t_s": 0.01, "program": "G18 G01 X52 Z-99 F3000\nG03 X54 Z-98 R2\nG01 X56\nM30\n"},
        {"t_s": 0.05, "feedhold": True},
        {"t_s": 0.15, "feedhold": False},
        {"t_s": 0.2, "cycle_start": True},
    ],
}


_warm = False


def warm_up() -> None:
    """Run the scratch sessions, then move every live object out of the GC's way (once in a
    process, and not again in a process forked from one that did)."""
    global _warm
    if _warm:
        return
    run_scenario(demo_machine(), _SESSION)
    run_scenario(demo_machine(), _PROGRAM_SESSION)
    gc.collect()
    gc.freeze()
    _warm = True
