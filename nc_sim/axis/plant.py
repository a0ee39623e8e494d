"""The simulated plant behind an axis: motor, drive, mechanics and encoder as its `sim.*`
and `drive.*` parameters describe them, changed by the training faults injected into it
(nc_sim/faults.py, nc_sim/machine/fault_injection.py). `sim.plant` chooses the ideal
first-order drive (`sim.drive_t`) or the drive cascade and mechanics of nc_sim/plant.

A fault changes the plant's kernel columns, never a parameter: `push_plant` writes them from
the lists and then the faults, so every parameter refresh (`push_params`: gear change, list
change, changeover) keeps the faults in force, and removing them gives back what the lists say.
"""

from __future__ import annotations

import math

from nc_sim.axis.faults import PlantFaults
from nc_sim.axis.state import Axis
from nc_sim.config import AxisConfig
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.params.definitions import OPMODE_SYMBOLS
from nc_sim.params.plant import (
    CURRENT_FILTERS,
    FILTER_TYPES,
    MEASURING_SYMBOLS,
    PLANT_SYMBOLS,
)
from nc_sim.plant import layout as PL
from nc_sim.plant.model import DriveModel, SecondOrderFilter
from nc_sim.units import RAD_PER_REV, RPM_TO_RAD_S


def _symbol(c: AxisConfig, name: str, symbols: dict[str, int]) -> int:
    value = c.raw(name)
    return symbols[value] if isinstance(value, str) else int(value)


# drive types whose position loop can close in the drive, and does by default (DRIVE_DEFAULT):
# SERCOS, ProfiDrive MC and CANopen; every other type's closes in the CNC [004 §2.1]
POSITION_CONTROL_DRIVES = (2, 3, 8)


def operation_mode(c: AxisConfig) -> int:
    """P-AXIS-00320 as its code (OPMODE_SYMBOLS)."""
    return _symbol(c, "antr.operation_mode", OPMODE_SYMBOLS)


def position_control_in_drive(c: AxisConfig) -> bool:
    """The position loop closes in the drive: DRIVE_POSITION_CONTROL, or DRIVE_DEFAULT on a
    drive type whose default it is, for a type that can [004 §2.1]. Only the drive cascade
    makes a difference: the ideal drive has no steps of its own (DOMAIN §2: one loop)."""
    if int(c.raw("kenngr.antr_typ")) not in POSITION_CONTROL_DRIVES:
        return False
    return operation_mode(c) in (
        OPMODE_SYMBOLS["DRIVE_POSITION_CONTROL"],
        OPMODE_SYMBOLS["DRIVE_DEFAULT"],
    )


def cascade(c: AxisConfig) -> bool:
    """The axis runs the drive cascade and mechanics (`sim.plant` DRIVE_CASCADE)."""
    return _symbol(c, "sim.plant", PLANT_SYMBOLS) == PLANT_SYMBOLS["DRIVE_CASCADE"]


def drive_model(
    c: AxisConfig, cycle_s: float, faults: PlantFaults | None = None, gear: int = 1
) -> DriveModel:
    """The axis' drive and mechanics from its list in gear stage `gear` (a spindle's stage
    sets the travel per motor revolution and the inertia ratio where its list gives them),
    with the training faults in force: a friction fault (a speed the ideal drive loses)
    becomes the Coulomb torque that costs a P speed loop that speed, a backlash fault adds
    to the gap, a torque-limited acceleration caps the torque; the mechanical faults soften
    the coupling, raise the friction and shift the filters. The drive's step is the NC
    cycle over the nearest whole number."""
    f = faults or PlantFaults()
    substeps = max(1, round(cycle_s / c.eng("drive.sampling_time")))
    active = int(c.raw("drive.current_filter_active"))
    filters = []
    for i in range(CURRENT_FILTERS):
        if not active >> i & 1:
            continue
        base = f"drive.current_filter_{i + 1}."
        general = _symbol(c, base + "type", FILTER_TYPES) == FILTER_TYPES["GENERAL_2ND_ORDER"]
        filters.append(
            SecondOrderFilter(
                c.eng(base + "denominator_frequency") * f.filter_factor,
                c.eng(base + "denominator_damping"),
                c.eng(base + "numerator_frequency") * f.filter_factor if general else 0.0,
                c.eng(base + "numerator_damping") if general else 0.0,
            )
        )
    per_rev = c.eng("sim.getriebe[i].travel_per_rev", gear) or c.eng("sim.mech.travel_per_rev")
    unit_per_rad = per_rev / RAD_PER_REV
    ratio = c.eng("sim.getriebe[i].inertia_ratio", gear) or c.eng("drive.inertia_ratio")
    kp = c.eng("drive.speed_kp")
    j_total = c.eng("drive.motor_inertia") * ratio
    torque_limit = c.eng("drive.torque_limit")
    if f.a_max > 0.0:
        torque_limit = min(torque_limit, j_total * f.a_max / unit_per_rad)
    return DriveModel(
        sampling_s=cycle_s / substeps,
        substeps=substeps,
        kp=kp,
        tn_s=c.eng("drive.speed_tn"),
        torque_limit=torque_limit,
        speed_filter_s=c.eng("drive.speed_setpoint_filter_t"),
        current_t_s=c.eng("drive.current_loop_t"),
        filters=tuple(filters),
        motor_inertia=c.eng("drive.motor_inertia"),
        inertia_ratio=ratio,
        # k ∝ f_ar²: a coupling `stiffness_factor` as stiff has its anti-resonance at √factor
        anti_resonance_hz=c.eng("sim.mech.anti_resonance") * math.sqrt(f.stiffness_factor),
        damping=c.eng("sim.mech.damping"),
        unit_per_rad=unit_per_rad,
        coulomb=c.eng("sim.mech.coulomb_friction") * f.friction_factor
        + kp * f.friction / unit_per_rad,
        breakaway=c.eng("sim.mech.breakaway_torque") * f.friction_factor,
        stribeck_rad_s=c.eng("sim.mech.stribeck_speed") * RPM_TO_RAD_S,
        viscous=c.eng("sim.mech.viscous_friction"),
        backlash=c.eng("sim.mech.backlash") + f.backlash,
        direct=_symbol(c, "sim.measuring_system", MEASURING_SYMBOLS) == MEASURING_SYMBOLS["DIRECT"],
    )


def _push_cascade(k: Kernel, ax: Axis) -> None:
    """Write the drive cascade into the slot's plant row. Coming from the ideal drive, the
    cascade starts turning as the load does; a changed set of filters starts them at rest."""
    s = ax.slot
    model = drive_model(ax.cfg, k.cycle_s, ax.plant, ax.gear)
    row = model.kernel_row()
    row[PL.PL_POS_IN_DRIVE] = 1.0 if position_control_in_drive(ax.cfg) else 0.0
    was = k.pl[s].copy()
    k.pl[s] = row
    ps = k.ps[s]
    if was[PL.PL_MODEL] != PL.MODEL_CASCADE:
        ps[:] = 0.0
        w = k.st[s, L.S_V_MOTOR] / model.unit_per_rad
        ps[PL.X_WM] = ps[PL.X_WL] = ps[PL.PS_W_REF] = w
    elif was[PL.PL_NX] != row[PL.PL_NX]:
        ps[PL.X_FILTERS : PL.NX_MAX] = 0.0
    if not model.two_mass:
        ps[PL.X_DEF] = ps[PL.X_WL] = 0.0
    # the NC's lag model takes the closed speed loop as a first-order lag
    t = model.speed_loop_time_constant_s()
    k.pr[s, L.P_DRV_ALPHA] = 1.0 - math.exp(-k.cycle_s / t)


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
    if cascade(c):
        _push_cascade(k, ax)
    else:
        k.pl[s, PL.PL_MODEL] = PL.MODEL_IDEAL
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
