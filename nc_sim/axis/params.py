"""An axis' parameters in its kernel row: the active gear record and loop parameters, the
power-on position, and the spindle's operation mode read from its list."""

from __future__ import annotations

import math

from nc_sim.axis.plant import operation_mode, push_plant
from nc_sim.axis.state import Axis
from nc_sim.config import AxisConfig
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.params.definitions import OPMODE_SYMBOLS
from nc_sim.units import AxisKind, v_reso_digits_per_unit_s

# control units every drive type needs [004 §4.1]; others need only TorquePermission
ENABLES_BY_DRIVE = {
    2: ("DriveOn", "TorquePermission", "ReleaseFeedhold"),  # SERCOS
    3: ("DriveOn", "TorquePermission"),  # PROFIDRIVE
    8: ("DriveOn", "TorquePermission", "ReleaseFeedhold"),  # CANopen
}


def open_position_loop(cfg: AxisConfig) -> bool:
    """A spindle in operation mode OPEN_POSITION_LOOP_MODE (P-AXIS-00320) [000 §2.2.4]."""
    return cfg.is_spindle and operation_mode(cfg) == OPMODE_SYMBOLS["OPEN_POSITION_LOOP_MODE"]


def speed_controlled(cfg: AxisConfig) -> bool:
    """A spindle that is never position-controlled [000 §2.2.4]: OPEN_POSITION_LOOP_MODE, or
    no encoder at all (it cannot be positioned: 70252)."""
    return open_position_loop(cfg) or (cfg.is_spindle and cfg.flag("sim.sensorless"))


def changeover_speeds(cfg: AxisConfig) -> tuple[float, float]:
    """(to speed control, back to position control) in °/s [001 §2.3]: P-AXIS-00767/00768,
    or their old names P-AXIS-00265/00266, which keep working; each default means "never",
    so whichever of a pair is set is in force (the lower / the higher speed if both are)."""
    on = min(
        cfg.eng("antr.sai_op_mode_change.v_velocity_control_on"),
        cfg.eng("antr.velocity_position_control_on"),
    )
    back = max(
        cfg.eng("antr.sai_op_mode_change.v_position_control_on"),
        cfg.eng("antr.velocity_position_control_off"),
    )
    return on, back


def push_params(k: Kernel, ax: Axis) -> None:
    """Write the axis' active gear record and loop parameters into the kernel row, then its
    plant (nc_sim/axis/plant.py: the `sim.*` parameters and the faults in force)."""
    c, g, s = ax.cfg, ax.gear, ax.slot
    pr = k.pr
    ax.required_enables = ENABLES_BY_DRIVE.get(int(c.raw("kenngr.antr_typ")), ("TorquePermission",))
    spindle = ax.kind is AxisKind.SPINDLE
    pr[s, L.P_KV] = c.eng("getriebe.kv", g)
    pr[s, L.P_FF] = ax.ff_weight if spindle else c.eng("lr_param.ff_weight")
    pr[s, L.P_MG] = c.eng("getriebe.multi_gain_z", g) / c.eng("getriebe.multi_gain_n", g)
    pr[s, L.P_DA_MAX] = c.eng("lr_hw.da_max")
    # P-AXIS-00159: a gear stage of a spindle may reverse both the output and the actual
    # value: the spindle turns the other way, the NC sees the same [000]
    reverse = spindle and bool(c.raw("getriebe.reverse", g))
    rev = -1.0 if reverse else 1.0
    pr[s, L.P_SIGN_CMD] = rev * (-1.0 if c.flag("lr_hw.vz_stellgr") else 1.0)
    sign_fb, pr[s, L.P_SIGN_FB] = (
        pr[s, L.P_SIGN_FB],
        rev * (-1.0 if c.flag("lr_hw.vz_istw") else 1.0),
    )
    if reverse != ax.reversed:  # a gear change: the NC's actual position must not jump
        if sign_fb != 0.0:  # (0: the row is new)
            x_enc = pr[s, L.P_ENC_SIGN] * pr[s, L.P_ENC_FACTOR] * k.st[s, L.S_X_MOTOR]
            pr[s, L.P_ENC_OFFSET] += (sign_fb - pr[s, L.P_SIGN_FB]) * x_enc
        ax.reversed = reverse
    # one increment = wegaufn/wegaufz in 0.1 µm or 0.0001°
    pr[s, L.P_ENC_INC] = c.eng("getriebe.wegaufn", g) / c.eng("getriebe.wegaufz", g)
    pr[s, L.P_LAG_MAX] = c.eng("getriebe.lag_max", g)
    if spindle:
        pr[s, L.P_SWE_NEG], pr[s, L.P_SWE_POS] = -math.inf, math.inf
    else:
        pr[s, L.P_SWE_NEG] = c.eng("kenngr.swe_neg")
        pr[s, L.P_SWE_POS] = c.eng("kenngr.swe_pos")
    pr[s, L.P_SPEED_BAND] = c.eng("kenngr.vb_prozent") if spindle else 0.1
    pr[s, L.P_V_ZERO] = c.eng("getriebe.vb_min_null", g)
    pr[s, L.P_INPOS_WIN] = c.eng("kenngr.exact_stop_window")
    pr[s, L.P_MODULO] = 360.0 if spindle else 0.0
    pr[s, L.P_V_CTRL_LIMIT] = (
        (c.eng("getriebe.vb_regelgrenze", g) or math.inf) if spindle else math.inf
    )
    pr[s, L.P_V_SPEED_CTRL] = changeover_speeds(c)[0] if spindle else math.inf
    pr[s, L.P_SENSORLESS] = float(spindle and c.flag("sim.sensorless"))
    # a speed-controlled spindle outputs its command speed with the v_reso scaling
    pr[s, L.P_V_RESO] = (
        v_reso_digits_per_unit_s(
            c.eng("antr.v_reso_num"),
            c.eng("antr.v_reso_denom"),
            int(c.raw("antr.v_time_base")),
            k.cycle_s,
        )
        if open_position_loop(c)
        else 0.0
    )
    curve = "getriebe.beschl_kennlinie."
    pr[s, L.P_CURVE_TYPE] = c.raw(curve + "typ", g) if spindle else 0
    for col, name in (
        (L.P_N_LIMIT, "n_grenz"),
        (L.P_A_KONST, "a_konst"),
        (L.P_B1, "b1"),
        (L.P_B2, "b2"),
        (L.P_B3, "b3"),
        (L.P_A_MIN, "a_min"),
        (L.P_CURVE_A_MAX, "a_max"),
        (L.P_N1, "n1"),
        (L.P_N2, "n2"),
    ):
        pr[s, col] = c.eng(curve + name, g)
    a_cap = c.eng("getriebe.dynamik.a_max", g)
    if ax.tool.a_max is not None:
        a_cap = min(a_cap, ax.tool.a_max)
    pr[s, L.P_A_CAP] = a_cap
    k.ist[s, L.I_GEAR] = g
    push_plant(k, ax)  # the plant of this gear stage, with the faults in force


def power_on(k: Kernel, ax: Axis) -> None:
    """Place the load at its power-on position with the NC position following it."""
    s = ax.slot
    x = ax.cfg.eng("sim.start_pos")
    k.st[s, L.S_X_MOTOR] = x  # the encoder sits on the load: physical = measured
    inc = k.pr[s, L.P_ENC_INC]
    x_enc = k.pr[s, L.P_ENC_FACTOR] * x
    counts = round(x_enc / inc) * inc if inc > 0 else x_enc
    p = k.pr[s, L.P_ENC_SIGN] * k.pr[s, L.P_SIGN_FB] * counts
    k.st[s, L.S_P_ACT] = k.st[s, L.S_P_CMD] = p
    x, cam, mod = k.st[s, L.S_X_MOTOR], k.pr[s, L.P_CAM_POS], k.pr[s, L.P_MODULO]
    k.ist[s, L.I_CAM] = math.floor((x - cam) / mod) if mod > 0 else int(x >= cam)
    k.st[s, L.S_OVERRIDE] = 1.0


def modulo_range(c: AxisConfig, gear: int) -> tuple[float, float]:
    """Where a rotary axis' or spindle's position is shown and programmed, in °: modulou
    (P-AXIS-00127) up to, not including, moduloo (P-AXIS-00126) of the gear in force."""
    return c.eng("getriebe.modulou", gear), c.eng("getriebe.moduloo", gear)


def in_modulo(p: float, lo: float, hi: float) -> float:
    """`p` (°) as the angle within lo ≤ angle < hi."""
    return lo + (p - lo) % (hi - lo)
