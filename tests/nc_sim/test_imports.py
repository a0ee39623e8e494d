"""The gateway imports nc_sim's typed surface without the kernel: no numba, no compiled step,
no machine, no simulation in a process that only describes, validates and relays."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

GATEWAY_IMPORTS = (
    "backend.main",  # the whole gateway: app, routes, services, worker clients
    "nc_sim.params",
    "nc_sim.config",
    "nc_sim.commands",
    "nc_sim.events",
    "nc_sim.errors",
    "nc_sim.snapshot",
    "nc_sim.units",
    "nc_sim.signals",
)
KERNEL_SIDE = ("numba", "nc_sim.kernel.step", "nc_sim.machine.machine", "nc_sim.sim")


def test_the_gateways_modules_import_without_the_kernel() -> None:
    code = (
        "import importlib, json, sys\n"
        f"for name in {GATEWAY_IMPORTS!r}:\n"
        "    importlib.import_module(name)\n"
        "from nc_sim.signals import Signal, machine_signals, signal_columns\n"
        "from nc_sim.config import demo_machine\n"
        "from nc_sim.params import registry\n"
        "demo_machine()  # reading and validating lists checks the acceleration curves too\n"
        f"print(json.dumps([m for m in {KERNEL_SIDE!r} if m in sys.modules]))\n"
    )
    # a fresh interpreter: this test process has long imported the kernel
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []
