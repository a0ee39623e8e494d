"""The simulated plant behind an axis: motor, drive, mechanics and encoder as its `sim.*`
parameters describe them, changed by the training faults injected into it (nc_sim/faults.py,
nc_sim/machine/fault_injection.py).

A fault changes the plant's kernel columns, never a parameter: `push_plant` writes them from
the lists and then the faults, so every parameter refresh (`push_params`: gear change, list
change, changeover) keeps the faults in force, and removing them gives back what the lists say.
"""

from __future__ import annotations

import math

from nc_sim.axis.faults import PlantFaults
from nc_sim.axis.state import Axis
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel


def push_plant(k: Kernel, ax: Axis) -> None:
    """Write the axis' plant (its `sim.*` parameters, its gear stage) with its faults into
    its kernel row."""
    c, g, s, f = ax.cfg, ax.gear, ax.slot, ax.plant
    pr = k.pr
    # the plant's true gain follows the mechanical gear stage; a ratio factor times the
    # gear's scales it, a drive that runs factor times faster per digit divides it
    gain = c.eng("sim.getriebe[i].drive_gain", g) or c.eng("sim.drive_gain")
    pr[s, L.P_DRV_GAIN] = gain * f.gear_factors.get(g, 1.0) / f.speed_factor
    pr[s, L.P_MOTOR_SIGN] = -1.0 if c.flag("sim.motor_inverted") != f.motor_inverted else 1.0
    pr[s, L.P_ENC_SIGN] = -1.0 if c.flag("sim.encoder_inverted") != f.encoder_inverted else 1.0
    t_drive = c.eng("sim.drive_t")
    pr[s, L.P_DRV_ALPHA] = 1.0 - math.exp(-k.cycle_s / t_drive) if t_drive > 0 else 1.0
    a_max = c.eng("sim.drive_a_max")  # 0: no limit of its own
    if f.a_max > 0.0:
        a_max = min(a_max, f.a_max) if a_max > 0.0 else f.a_max
    pr[s, L.P_DRV_A_MAX] = a_max
    pr[s, L.P_CAM_POS] = c.eng("sim.ref_cam_pos")
    pr[s, L.P_ENC_FACTOR] = f.encoder_factor
    pr[s, L.P_ENC_NOISE] = f.noise_rms
    pr[s, L.P_FRICTION] = f.friction
    pr[s, L.P_BACKLASH] = f.backlash


def change_plant(k: Kernel, ax: Axis, faults: PlantFaults) -> None:
    """The axis' plant gets these faults now. The NC's actual position does not jump when
    the encoder's sign or factor changes (the encoder is re-based onto it, as if it had been
    so since the last homing), and the load couples to the motor when the play goes."""
    s = ax.slot
    pr, st = k.pr, k.st
    before = pr[s, L.P_ENC_SIGN] * pr[s, L.P_ENC_FACTOR]
    ax.plant = faults
    push_plant(k, ax)
    after = pr[s, L.P_ENC_SIGN] * pr[s, L.P_ENC_FACTOR]
    pr[s, L.P_ENC_OFFSET] += pr[s, L.P_SIGN_FB] * (before - after) * st[s, L.S_X_MOTOR]
    if faults.backlash <= 0.0:
        st[s, L.S_PLAY] = 0.0


def encoder_reading(k: Kernel, slot: int, x: float) -> float:
    """The NC position the encoder gives for the load at `x` (true position), unquantised
    and without noise: sign · factor · x + offset (homing latches it at the reference)."""
    pr = k.pr
    sign = pr[slot, L.P_ENC_SIGN] * pr[slot, L.P_SIGN_FB]
    return float(sign * pr[slot, L.P_ENC_FACTOR] * x + pr[slot, L.P_ENC_OFFSET])
