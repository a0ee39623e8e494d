"""Which parameter set drives which motion [002 §2.2, §2.4, §2.6, §2.7].

Returns planner limit rows (`nc_sim.profiles.plan.make_limits`) for G01 feed, G00 rapid,
manual mode G200 (jog), homing, feedhold and emergency stop, for the slope type in force
(P-CHAN-00071 or `#SLOPE[TYPE=...]`): 0 step-shaped, 1 trapezoidal, 2 sine-square, 3 HSC.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from nc_sim.config import AxisConfig
from nc_sim.profiles.plan import SHAPE_LINEAR, SHAPE_SIN2, make_limits
from nc_sim.snapshot import LimitKind


class Motion(StrEnum):
    FEED = "G01"
    RAPID = "G00"
    MANUAL = "G200"
    HOMING = "G74"


@dataclass(frozen=True)
class Sourced:
    """A dynamic limit (engineering unit) and where it comes from: a parameter of the list
    (`source` its name with the gear record's index, `param_id` its ID), the programmed F or
    S, the reduced speed or acceleration the PLC asks for (a parameter too), a tool's limit."""

    value: float
    source: str
    param_id: str | None = None
    kind: LimitKind = "parameter"


def param(cfg: AxisConfig, name: str, gear: int = 1, kind: LimitKind = "parameter") -> Sourced:
    """A parameter's value in engineering units with its list name and ID."""
    concrete, pid = cfg.ref(name, gear)
    return Sourced(cfg.eng(name, gear), concrete, pid, kind)


def _or(a: Sourced, b: Sourced) -> Sourced:
    """`a`, or `b` where the list leaves `a` at 0 (0 = take the other)."""
    return a if a.value else b


def lowest(*xs: Sourced) -> Sourced:
    """The lowest limit (the first of equal ones)."""
    return min(xs, key=lambda x: x.value)


def _highest(*xs: Sourced) -> Sourced:
    return max(xs, key=lambda x: x.value)


def _cap(a: Sourced, cfg: AxisConfig, gear: int) -> Sourced:
    a_max = param(cfg, "getriebe.dynamik.a_max", gear)
    return lowest(a, a_max) if a.value > 0 else a_max


@dataclass(frozen=True)
class Dynamics:
    """Accelerations and ramp times of one kind of motion, each with its source."""

    a_acc: Sourced
    a_dec: Sourced
    tr: tuple[Sourced, Sourced, Sourced, Sourced]  # acc up, acc down, dec up, dec down
    shape: float = SHAPE_LINEAR
    a_acc2: Sourced | None = None  # step-shaped: the second stage above v12
    a_dec2: Sourced | None = None
    v12: float = 0.0

    def limits(self) -> np.ndarray:
        """The planner's limit row (`nc_sim.profiles.plan.make_limits`)."""
        a2 = self.a_acc2.value if self.a_acc2 is not None else 0.0
        d2 = self.a_dec2.value if self.a_dec2 is not None else 0.0
        t = [x.value for x in self.tr]
        return make_limits(
            self.a_acc.value, self.a_dec.value, t[0], t[1], t[2], t[3], self.shape, a2, d2, self.v12
        )

    def jerk(self) -> Sourced | None:
        """Jerk while acceleration builds up (a / tr); None when step-shaped (not limited)."""
        tr = self.tr[0]
        if tr.value <= 0.0:
            return None
        a = self.a_acc
        return Sourced(a.value / tr.value, f"{a.source} / {tr.source}", tr.param_id, tr.kind)


def motion_dynamics(
    cfg: AxisConfig, gear: int, motion: Motion, slope: int, reduced: bool = False
) -> Dynamics:
    """Accelerations and ramp times of a kind of motion with the given slope type, each with
    the parameter it comes from."""

    def p(name: str) -> Sourced:
        return param(cfg, name, gear)

    if motion is Motion.MANUAL:
        a = p("handbetrieb.hb.a_max")
        if reduced:
            a = param(cfg, "handbetrieb.hb.a_max_red", gear, "reduced_acceleration")
        a = _cap(a, cfg, gear)
        d = _cap(_or(p("handbetrieb.hb.d_max"), a), cfg, gear)
        tr = p("handbetrieb.hb.tr")  # 0 = step-shaped
        return Dynamics(a, d, (tr, tr, tr, tr))
    if motion is Motion.HOMING:
        a = _or(
            p("getriebe.a_ref"),
            lowest(
                p("getriebe.lslope_profil.a_grenz_stufe_1"),
                p("getriebe.lslope_profil.a_grenz_stufe_2"),
            ),
        )
        a = _cap(a, cfg, gear)
        tr = Sourced(0.0, "getriebe.slope_type")
        if int(cfg.raw("getriebe.slope_type", gear)) != 0:
            tr = _or(p("getriebe.tr_ref"), p("getriebe.dynamik.tr_min"))
        return Dynamics(a, a, (tr, tr, tr, tr))
    rapid = motion is Motion.RAPID
    if slope == 0:
        pre = "getriebe.lslope_profil."
        if rapid:
            a1, a2 = p(pre + "a_grenz_stufe_1"), p(pre + "a_grenz_stufe_2")
            v12 = cfg.eng(pre + "vb_grenz_stufe_1_2", gear)
        else:
            a1, a2 = p(pre + "a_stufe_1"), p(pre + "a_stufe_2")
            v12 = cfg.eng(pre + "vb_stufe_1_2", gear)
        a1, a2 = _cap(a1, cfg, gear), _cap(a2, cfg, gear)
        step = Sourced(0.0, "P-CHAN-00071 slope_type 0")
        return Dynamics(a1, a1, (step, step, step, step), a_acc2=a2, a_dec2=a2, v12=v12)
    pre = "getriebe.slope_profil."
    tr_min = p("getriebe.dynamik.tr_min")
    if rapid:
        a_acc = a_dec = _cap(p(pre + "a_grenz"), cfg, gear)
        tr = _highest(p(pre + "tr_grenz"), tr_min)
        trs = [tr, tr, tr, tr]
    else:
        a_acc = _cap(p(pre + "a_beschl"), cfg, gear)
        a_dec = _cap(p(pre + "a_brems"), cfg, gear)
        names = ("tr_beschl_zu", "tr_beschl_ab", "tr_brems_zu", "tr_brems_ab")
        trs = [_highest(p(pre + n), tr_min) for n in names]
    if slope == 3:  # HSC: one ramp time, the longest of the four
        trs = [_highest(*trs)] * 4
    shape = SHAPE_SIN2 if slope == 2 else SHAPE_LINEAR
    return Dynamics(a_acc, a_dec, (trs[0], trs[1], trs[2], trs[3]), shape)


def _share(whole: Sourced, cfg: AxisConfig, name: str) -> Sourced:
    part, pid = cfg.ref(name)
    return Sourced(whole.value * cfg.eng(name), f"{part} × {whole.source}", pid)


def parallel_manual_dynamics(cfg: AxisConfig, gear: int) -> tuple[Dynamics, Sourced]:
    """G201, the manual motion of a path axis while the path runs [002 §2.6.2]: its share
    hb_proz_a_max (P-AXIS-00082) of the axis acceleration P-AXIS-00008, with the manual ramp
    time P-AXIS-00359, and its top speed, the share hb_proz_v_max (P-AXIS-00083) of P-AXIS-00212."""
    a = _share(param(cfg, "getriebe.dynamik.a_max", gear), cfg, "handbetrieb.ipo.hb_proz_a_max")
    tr = param(cfg, "handbetrieb.hb.tr", gear)
    v = _share(param(cfg, "getriebe.dynamik.vb_max", gear), cfg, "handbetrieb.ipo.hb_proz_v_max")
    return Dynamics(a, a, (tr, tr, tr, tr)), v


def path_share(cfg: AxisConfig) -> tuple[float, float]:
    """G201: the fractions of P-AXIS-00212 and P-AXIS-00008 the path may use, ipo_proz_v_max
    (P-AXIS-00095) and ipo_proz_a_max (P-AXIS-00094); the rest is manual mode's [002 §2.6.2]."""
    return cfg.eng("handbetrieb.ipo.ipo_proz_v_max"), cfg.eng("handbetrieb.ipo.ipo_proz_a_max")


def motion_limits(
    cfg: AxisConfig, gear: int, motion: Motion, slope: int, reduced: bool = False
) -> np.ndarray:
    """Planner limits for one kind of motion with the given slope type."""
    return motion_dynamics(cfg, gear, motion, slope, reduced).limits()


def feedhold_limits(
    cfg: AxisConfig, gear: int, motion: Motion, slope: int, use_feedhold_set: bool
) -> np.ndarray:
    """Braking for feedhold: the feedhold set when P-CHAN-00097 = 1, else the current one."""
    normal = motion_limits(cfg, gear, motion, slope)
    if not use_feedhold_set:
        return normal
    e = cfg.eng
    if motion is Motion.MANUAL:
        a = _cap_value(e("handbetrieb.hb.a_feedh") or e("handbetrieb.hb.a_max"), cfg, gear)
        tr = e("handbetrieb.hb.tr_feedh")
        return make_limits(a, a, tr, tr, tr, tr)
    if slope == 0:
        a = e("getriebe.lslope_profil.a_feedh", gear) or min(
            e("getriebe.lslope_profil.a_grenz_stufe_1", gear),
            e("getriebe.lslope_profil.a_grenz_stufe_2", gear),
        )
        a = _cap_value(a, cfg, gear)
        return make_limits(a, a)
    a = _cap_value(
        e("getriebe.slope_profil.a_feedh", gear) or e("getriebe.slope_profil.a_grenz", gear),
        cfg,
        gear,
    )
    tr = e("getriebe.slope_profil.tr_feedh", gear) or e("getriebe.slope_profil.tr_grenz", gear)
    shape = SHAPE_SIN2 if slope == 2 else SHAPE_LINEAR
    return make_limits(a, a, tr, tr, tr, tr, shape)


def _cap_value(a: float, cfg: AxisConfig, gear: int) -> float:
    return _cap(Sourced(a, ""), cfg, gear).value


def emergency_limits(cfg: AxisConfig, gear: int) -> np.ndarray:
    """Step-shaped braking at a_emergency (0 = a_max) [002 §2.4]."""
    a = cfg.eng("getriebe.dynamik.a_emergency", gear) or cfg.eng("getriebe.dynamik.a_max", gear)
    return make_limits(a, a)


def velocity_in_force(cfg: AxisConfig, gear: int, motion: Motion, feed: float | None) -> Sourced:
    """Top speed (unit/s) before override and its source: F for G01, vb_eilgang for G00,
    hb.vb_max (or a lower jog feed) for jog, vb_refmax for homing; capped by vb_max."""
    vb_max = param(cfg, "getriebe.dynamik.vb_max", gear)
    if motion is Motion.RAPID:
        v = param(cfg, "getriebe.vb_eilgang", gear)
    elif motion is Motion.MANUAL:
        v = param(cfg, "handbetrieb.hb.vb_max")
        if feed:
            v = lowest(v, Sourced(feed, "jog feed", None, "programmed"))
    elif motion is Motion.HOMING:
        v = param(cfg, "getriebe.vb_refmax", gear)
    else:
        v = Sourced(feed or 0.0, "F", None, "programmed")
    return lowest(v, vb_max)


def velocity_limit(cfg: AxisConfig, gear: int, motion: Motion, feed: float | None) -> float:
    """Top speed (unit/s) before override (`velocity_in_force` without its source)."""
    return velocity_in_force(cfg, gear, motion, feed).value
