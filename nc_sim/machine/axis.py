"""Runtime state of one axis or spindle outside the kernel arrays, and its parameter push."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

from nc_sim.kernel import Kernel
from nc_sim.kernel import layout as L
from nc_sim.machine.config import AxisConfig
from nc_sim.machine.dynamics import Motion
from nc_sim.units import AxisKind

# control units every drive type needs [004 §4.1]; others need only TorquePermission
ENABLES_BY_DRIVE = {
    2: ("DriveOn", "TorquePermission", "ReleaseFeedhold"),  # SERCOS
    3: ("DriveOn", "TorquePermission"),  # PROFIDRIVE
    8: ("DriveOn", "TorquePermission", "ReleaseFeedhold"),  # CANopen
}


class AxisState(IntEnum):
    """Operating state shown in the HLI and traces."""

    STANDSTILL = 0
    MOVING = 1  # positioning (G00/G01, incremental jog, M19 later)
    JOG = 2  # continuous jog
    HOMING = 3
    ENDLESS = 4  # spindle M3/M4
    STOPPING = 5
    ERROR = 9


class HomingPhase(IntEnum):
    NONE = 0
    TO_CAM = 1
    OFF_CAM = 2
    TO_REF = 3


@dataclass
class Axis:
    """One axis or spindle of a machine: config, kernel slot and what it is doing."""

    cfg: AxisConfig
    slot: int
    gear: int = 1
    state: AxisState = AxisState.STANDSTILL
    motion: Motion | None = None
    target: float = math.nan
    feed: float | None = None  # unit/s for G01/jog
    speed_prog: float = 0.0  # spindle: programmed signed speed (°/s) before override
    slope: int = 1
    hold: bool = False  # braked by feedhold, resumes on release
    homing: HomingPhase = HomingPhase.NONE
    homed: bool = False
    job_error: int = 0
    block_id: int | None = None  # MDI block this motion belongs to
    units: dict[str, int] = field(
        default_factory=lambda: {
            "override": 1000,
            "override_valid": 1,
            "DriveOn": 0,
            "TorquePermission": 0,
            "ReleaseFeedhold": 0,
            "reduced_speed": 0,
        }
    )

    @property
    def name(self) -> str:
        return self.cfg.name

    @property
    def kind(self) -> AxisKind:
        return self.cfg.kind

    @property
    def required_enables(self) -> tuple[str, ...]:
        return ENABLES_BY_DRIVE.get(int(self.cfg.raw("kenngr.antr_typ")), ("TorquePermission",))

    def enables_ok(self) -> bool:
        return all(self.units[u] for u in self.required_enables)

    def missing_enables(self) -> list[str]:
        return [u for u in self.required_enables if not self.units[u]]


def push_params(k: Kernel, ax: Axis) -> None:
    """Write the axis' active gear record and loop parameters into the kernel row."""
    c, g, s = ax.cfg, ax.gear, ax.slot
    pr = k.pr
    pr[s, L.P_KV] = c.eng("getriebe.kv", g)
    pr[s, L.P_FF] = c.eng("lr_param.ff_weight")
    pr[s, L.P_MG] = c.eng("getriebe.multi_gain_z", g) / c.eng("getriebe.multi_gain_n", g)
    pr[s, L.P_DRV_GAIN] = c.eng("sim.drive_gain")
    pr[s, L.P_DA_MAX] = c.eng("lr_hw.da_max")
    pr[s, L.P_SIGN_CMD] = -1.0 if c.flag("lr_hw.vz_stellgr") else 1.0
    pr[s, L.P_SIGN_FB] = -1.0 if c.flag("lr_hw.vz_istw") else 1.0
    pr[s, L.P_MOTOR_SIGN] = -1.0 if c.flag("sim.motor_inverted") else 1.0
    pr[s, L.P_ENC_SIGN] = -1.0 if c.flag("sim.encoder_inverted") else 1.0
    pr[s, L.P_DRV_T] = c.eng("sim.drive_t")
    pr[s, L.P_DRV_A_MAX] = c.eng("sim.drive_a_max")
    # one increment = wegaufn/wegaufz in 0.1 µm or 0.0001°
    pr[s, L.P_ENC_INC] = c.eng("getriebe.wegaufn", g) / c.eng("getriebe.wegaufz", g)
    pr[s, L.P_LAG_MAX] = c.eng("getriebe.lag_max", g)
    if ax.kind is AxisKind.SPINDLE:
        pr[s, L.P_SWE_NEG], pr[s, L.P_SWE_POS] = -math.inf, math.inf
    else:
        pr[s, L.P_SWE_NEG] = c.eng("kenngr.swe_neg")
        pr[s, L.P_SWE_POS] = c.eng("kenngr.swe_pos")
    pr[s, L.P_CAM_POS] = c.eng("sim.ref_cam_pos")
    pr[s, L.P_SPEED_BAND] = c.eng("kenngr.vb_prozent") if ax.kind is AxisKind.SPINDLE else 0.1
    pr[s, L.P_V_ZERO] = c.eng("getriebe.vb_min_null", g)
    k.ist[s, L.I_GEAR] = g


def power_on(k: Kernel, ax: Axis) -> None:
    """Place the load at its power-on position with the NC position following it."""
    s = ax.slot
    x = ax.cfg.eng("sim.start_pos")
    k.st[s, L.S_X_MOTOR] = x  # the encoder sits on the load: physical = measured
    inc = k.pr[s, L.P_ENC_INC]
    counts = round(k.st[s, L.S_X_MOTOR] / inc) * inc if inc > 0 else k.st[s, L.S_X_MOTOR]
    p = k.pr[s, L.P_ENC_SIGN] * k.pr[s, L.P_SIGN_FB] * counts
    k.st[s, L.S_P_ACT] = k.st[s, L.S_P_CMD] = p
    k.ist[s, L.I_CAM] = int(k.st[s, L.S_X_MOTOR] >= k.pr[s, L.P_CAM_POS])
