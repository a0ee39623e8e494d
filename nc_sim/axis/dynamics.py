"""Which parameter set drives which motion [002 §2.2, §2.4, §2.6, §2.7].

Returns planner limit rows (`nc_sim.profiles.plan.make_limits`) for G01 feed, G00 rapid,
manual mode G200 (jog), homing, feedhold and emergency stop, for the slope type in force
(P-CHAN-00071 or `#SLOPE[TYPE=...]`): 0 step-shaped, 1 trapezoidal, 2 sine-square, 3 HSC.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np

from nc_sim.machine.config import AxisConfig
from nc_sim.profiles.plan import SHAPE_LINEAR, SHAPE_SIN2, make_limits


class Motion(StrEnum):
    FEED = "G01"
    RAPID = "G00"
    MANUAL = "G200"
    HOMING = "G74"


def _cap(a: float, cfg: AxisConfig, gear: int) -> float:
    a_max = cfg.eng("getriebe.dynamik.a_max", gear)
    return min(a, a_max) if a > 0 else a_max


def motion_limits(
    cfg: AxisConfig, gear: int, motion: Motion, slope: int, reduced: bool = False
) -> np.ndarray:
    """Planner limits for one kind of motion with the given slope type."""
    e = cfg.eng
    if motion is Motion.MANUAL:
        a = e("handbetrieb.hb.a_max")
        if reduced:
            a = e("handbetrieb.hb.a_max_red")
        a = _cap(a, cfg, gear)
        d = _cap(e("handbetrieb.hb.d_max") or a, cfg, gear)
        tr = e("handbetrieb.hb.tr")  # 0 = step-shaped
        return make_limits(a, d, tr, tr, tr, tr)
    if motion is Motion.HOMING:
        a = e("getriebe.a_ref", gear) or min(
            e("getriebe.lslope_profil.a_grenz_stufe_1", gear),
            e("getriebe.lslope_profil.a_grenz_stufe_2", gear),
        )
        a = _cap(a, cfg, gear)
        tr = 0.0
        if int(cfg.raw("getriebe.slope_type", gear)) != 0:
            tr = e("getriebe.tr_ref", gear) or e("getriebe.dynamik.tr_min", gear)
        return make_limits(a, a, tr, tr, tr, tr)
    rapid = motion is Motion.RAPID
    if slope == 0:
        pre = "getriebe.lslope_profil."
        if rapid:
            a1, a2 = e(pre + "a_grenz_stufe_1", gear), e(pre + "a_grenz_stufe_2", gear)
            v12 = e(pre + "vb_grenz_stufe_1_2", gear)
        else:
            a1, a2 = e(pre + "a_stufe_1", gear), e(pre + "a_stufe_2", gear)
            v12 = e(pre + "vb_stufe_1_2", gear)
        a1, a2 = _cap(a1, cfg, gear), _cap(a2, cfg, gear)
        return make_limits(a1, a1, a_acc2=a2, a_dec2=a2, v12=v12)
    pre = "getriebe.slope_profil."
    tr_min = e("getriebe.dynamik.tr_min", gear)
    if rapid:
        a = _cap(e(pre + "a_grenz", gear), cfg, gear)
        tr = max(e(pre + "tr_grenz", gear), tr_min)
        trs = [tr, tr, tr, tr]
        a_acc = a_dec = a
    else:
        a_acc = _cap(e(pre + "a_beschl", gear), cfg, gear)
        a_dec = _cap(e(pre + "a_brems", gear), cfg, gear)
        names = ("tr_beschl_zu", "tr_beschl_ab", "tr_brems_zu", "tr_brems_ab")
        trs = [max(e(pre + n, gear), tr_min) for n in names]
    if slope == 3:  # HSC: one ramp time, the longest of the four
        trs = [max(trs)] * 4
    shape = SHAPE_SIN2 if slope == 2 else SHAPE_LINEAR
    return make_limits(a_acc, a_dec, trs[0], trs[1], trs[2], trs[3], shape)


def feedhold_limits(
    cfg: AxisConfig, gear: int, motion: Motion, slope: int, use_feedhold_set: bool
) -> np.ndarray:
    """Braking for feedhold: the feedhold set when P-CHAN-00097 = 1, else the current one."""
    normal = motion_limits(cfg, gear, motion, slope)
    if not use_feedhold_set:
        return normal
    e = cfg.eng
    if motion is Motion.MANUAL:
        a = _cap(e("handbetrieb.hb.a_feedh") or e("handbetrieb.hb.a_max"), cfg, gear)
        tr = e("handbetrieb.hb.tr_feedh")
        return make_limits(a, a, tr, tr, tr, tr)
    if slope == 0:
        a = e("getriebe.lslope_profil.a_feedh", gear) or min(
            e("getriebe.lslope_profil.a_grenz_stufe_1", gear),
            e("getriebe.lslope_profil.a_grenz_stufe_2", gear),
        )
        a = _cap(a, cfg, gear)
        return make_limits(a, a)
    a = _cap(
        e("getriebe.slope_profil.a_feedh", gear) or e("getriebe.slope_profil.a_grenz", gear),
        cfg,
        gear,
    )
    tr = e("getriebe.slope_profil.tr_feedh", gear) or e("getriebe.slope_profil.tr_grenz", gear)
    shape = SHAPE_SIN2 if slope == 2 else SHAPE_LINEAR
    return make_limits(a, a, tr, tr, tr, tr, shape)


def emergency_limits(cfg: AxisConfig, gear: int) -> np.ndarray:
    """Step-shaped braking at a_emergency (0 = a_max) [002 §2.4]."""
    a = cfg.eng("getriebe.dynamik.a_emergency", gear) or cfg.eng("getriebe.dynamik.a_max", gear)
    return make_limits(a, a)


def velocity_limit(cfg: AxisConfig, gear: int, motion: Motion, feed: float | None) -> float:
    """Top speed (unit/s) before override: F for G01, vb_eilgang for G00, hb.vb_max for jog."""
    vb_max = cfg.eng("getriebe.dynamik.vb_max", gear)
    if motion is Motion.RAPID:
        v = cfg.eng("getriebe.vb_eilgang", gear)
    elif motion is Motion.MANUAL:
        v = cfg.eng("handbetrieb.hb.vb_max")
        if feed:
            v = min(v, feed)
    elif motion is Motion.HOMING:
        v = cfg.eng("getriebe.vb_refmax", gear)
    else:
        v = feed or 0.0
    return min(v, vb_max)
