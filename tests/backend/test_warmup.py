"""The warm-up loads the compiled functions a session calls from Python before the loop runs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# in a fresh interpreter: nothing else of the test run has loaded them there
_CHECK = """
from backend.workers.warmup import warm_up
from nc_sim.profiles import plan
warm_up()
# the path planner's (nc_sim/channel/planner.py, path.py) are called when a program starts
missing = [f for f in ("speed_within", "move_through", "velocity_change")
           if not getattr(plan, f).overloads]
print(" ".join(missing))
"""


def test_warm_up_loads_the_path_planner() -> None:
    out = subprocess.run(
        [sys.executable, "-c", _CHECK], cwd=ROOT, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "", f"not loaded by the warm-up: {out.stdout.strip()}"
