"""Look-ahead path planning: the 1-D plan of path length over the queued elements [002 §1-2.3].

The kernel runs the plan (nc_sim/kernel/step.py `_advance_path`): path length, speed and
acceleration in the channel's slot, every path axis set from the element's geometry. Here:

- each element's speed cap is F (G01/G02/G03, × channel override) or rapid, and no axis above
  its own maximum: v_path ≤ v_max_axis / |d axis / d u| (the weakest axis limits the path),
  nor above the reduced speed the PLC asks for on it [002 §2.8];
  on arcs also the centripetal acceleration (half the weakest plane axis' acceleration) and
  the geometric jerk v³/r² ≤ a / tr_geom (P-AXIS-00199);
- path acceleration and deceleration are the weakest axis' projected on the path, ramp times
  the longest of the axes (so no axis exceeds its jerk a/tr);
- at a corner the speed is limited so no axis' velocity jumps by more than a_trans · cycle
  (P-AXIS-00013: a_trans = a · weight/1000, or a · cycle/ramp time when the weight is 0);
  with P-CHAN-00009 a tangential transition whose curvature changes is limited so no axis'
  acceleration jumps by more than j_trans · cycle (P-AXIS-00154: j_trans = a/tr · weight/1000);
  collinear and tangent blocks without curvature change keep their speed;
- the window ends at rest (unless more blocks come: then it is planned again), a G60 block at
  rest; a backward pass finds the highest speeds from which every later constraint can still
  be kept, a forward pass fills the plan element by element.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nc_sim.channel.geometry import Element
from nc_sim.profiles.plan import (
    LIM_A_ACC,
    LIM_A_ACC2,
    LIM_A_DEC,
    LIM_A_DEC2,
    LIM_SHAPE,
    LIM_TR_ACC_DOWN,
    LIM_TR_ACC_UP,
    LIM_TR_DEC_DOWN,
    LIM_TR_DEC_UP,
    LIM_V12,
    make_limits,
    move_through,
    speed_within,
)

CENTRIPETAL_SHARE = 0.5  # of the weakest plane axis' acceleration, the rest is tangential
_TINY = 1e-9


@dataclass(frozen=True)
class AxisDynamics:
    """What the planner needs of one path axis for one kind of motion (units: mm, s)."""

    v_max: float  # top speed (vb_max, or vb_eilgang for G00)
    lim: np.ndarray  # planner limits row for this motion and slope type
    a_trans: float  # acceleration allowed at a corner (P-AXIS-00013)
    j_trans: float  # jerk allowed at a tangential transition (P-AXIS-00154)
    tr_geom_s: float  # geometric ramp time (P-AXIS-00199)
    v_red: float = math.inf  # the PLC's reduced speed [002 §2.8], whatever the override


@dataclass
class Limits:
    """An element's planning limits: speed cap (path units/s) and the path's limits row."""

    v_cap: float
    lim: np.ndarray


def single_stage(lim: np.ndarray) -> tuple[float, float]:
    """Acceleration and deceleration of a limits row that hold at every speed (the lower
    stage of a step-shaped profile)."""
    a_acc = lim[LIM_A_ACC] if lim[LIM_A_ACC2] <= 0 else min(lim[LIM_A_ACC], lim[LIM_A_ACC2])
    a_dec = lim[LIM_A_DEC] if lim[LIM_A_DEC2] <= 0 else min(lim[LIM_A_DEC], lim[LIM_A_DEC2])
    return float(a_acc), float(a_dec)


@dataclass
class _Stages:
    """The path's step-shaped acceleration (or deceleration) over its axes [002 §2.2.2]: each
    axis gives stage 1 below its changeover speed and stage 2 above it, both seen on the path
    (divided by the axis' share of the path motion, its changeover speed too)."""

    low: float = math.inf  # path acceleration while every axis is in its first stage
    high: float = math.inf  # ... in its second stage
    first_change: float = math.inf  # lowest path speed at which an axis changes stage
    last_change: float = 0.0  # highest

    def add(self, a1: float, a2: float, v12: float, share: float, wgt: float) -> None:
        self.low = min(self.low, share * a1 / wgt)
        self.high = min(self.high, share * a2 / wgt)
        self.first_change = min(self.first_change, v12 / wgt)
        self.last_change = max(self.last_change, v12 / wgt)

    def row(self) -> tuple[float, float, float]:
        """(stage 1, stage 2, changeover path speed) of the one changeover the path plan
        has. Between the axes' changeovers some axes are in one stage and some in the other:
        there the lower of the two holds, so the changeover goes to the first axis' when
        stage 2 is the lower one and to the last axis' otherwise (exact for a single axis
        and for axes that change together)."""
        if self.high == self.low or not math.isfinite(self.first_change):
            return self.low, 0.0, 0.0
        v12 = self.first_change if self.high < self.low else self.last_change
        if not math.isfinite(v12):  # an axis of a single stage never changes: stage 1 above
            return min(self.low, self.high), 0.0, 0.0
        return self.low, self.high, v12


def element_limits(e: Element, axes: list[AxisDynamics], feed_mm_s: float) -> Limits:
    """Speed cap and limits row of one element; `feed_mm_s` is F × override (∞ for G00
    before the axes' rapid speeds, which already carry the override)."""
    weights = e.weights()
    v_cap = feed_mm_s
    acc_stages, dec_stages = _Stages(), _Stages()
    tr = [0.0, 0.0, 0.0, 0.0]
    shape = 0.0
    a_plane = math.inf
    j_geom = math.inf
    plane = (e.arc[0], e.arc[1]) if e.arc is not None else ()
    for i, (ax, wgt) in enumerate(zip(axes, weights, strict=True)):
        if wgt < _TINY:
            continue
        acc, dec = single_stage(ax.lim)
        share = (1.0 - CENTRIPETAL_SHARE) if i in plane else 1.0
        v_cap = min(v_cap, min(ax.v_max, ax.v_red) / wgt)
        acc_stages.add(*_stages_of(ax.lim, LIM_A_ACC, LIM_A_ACC2), share, wgt)
        dec_stages.add(*_stages_of(ax.lim, LIM_A_DEC, LIM_A_DEC2), share, wgt)
        cols = (LIM_TR_ACC_UP, LIM_TR_ACC_DOWN, LIM_TR_DEC_UP, LIM_TR_DEC_DOWN)
        tr = [max(t, float(ax.lim[c])) for t, c in zip(tr, cols, strict=True)]
        shape = max(shape, float(ax.lim[LIM_SHAPE]))
        if i in plane:
            a_plane = min(a_plane, acc, dec)
            if ax.tr_geom_s > 0:
                j_geom = min(j_geom, min(acc, dec) / ax.tr_geom_s)
    if e.arc is not None:
        r = e.arc[4]
        speed_in_plane = weights[e.arc[0]]  # plane speed per unit of path speed
        if math.isfinite(a_plane):
            v_cap = min(v_cap, math.sqrt(CENTRIPETAL_SHARE * a_plane * r) / speed_in_plane)
        if math.isfinite(j_geom):
            v_cap = min(v_cap, (j_geom * r * r) ** (1.0 / 3.0) / speed_in_plane)
    a_acc, a_acc2, v12_acc = acc_stages.row()
    a_dec, a_dec2, v12_dec = dec_stages.row()
    if e.path_limit is not None:  # #VECTOR LIMIT: the path's own limits [002 §2.5.2]
        v_path, acc_path, dec_path = e.path_limit
        v_cap = min(v_cap, v_path)
        a_acc, a_acc2 = min(a_acc, acc_path), min(a_acc2, acc_path)
        a_dec, a_dec2 = min(a_dec, dec_path), min(a_dec2, dec_path)
    if v12_acc != v12_dec:  # the plan has one changeover speed: the lower stage throughout
        a_acc, a_acc2 = min(a_acc, a_acc2 or a_acc), 0.0
        a_dec, a_dec2 = min(a_dec, a_dec2 or a_dec), 0.0
        v12_acc = 0.0
    if not math.isfinite(a_acc):  # moves no axis (cannot happen for a queued element)
        a_acc = a_dec = 1.0
    lim = make_limits(a_acc, a_dec, tr[0], tr[1], tr[2], tr[3], shape, a_acc2, a_dec2, v12_acc)
    return Limits(max(v_cap, 0.0), lim)


def _stages_of(lim: np.ndarray, first: int, second: int) -> tuple[float, float, float]:
    """(stage 1, stage 2, changeover speed) of one axis' limits row; a single-stage row has
    the same acceleration on both sides of an infinite changeover speed."""
    if lim[second] <= 0:
        return float(lim[first]), float(lim[first]), math.inf
    return float(lim[first]), float(lim[second]), float(lim[LIM_V12])


def junction_speed(a: Element, b: Element, axes: list[AxisDynamics], cycle_s: float) -> float:
    """Highest path speed at the transition from a to b [002 §2.3]."""
    ta, tb = a.tangent(at_end=True), b.tangent(at_end=False)
    jump = np.abs(tb - ta)
    v = math.inf
    if float(jump.max()) > 1e-6:  # a corner: the axes' velocities jump
        for ax, dv in zip(axes, jump, strict=True):
            if dv > 1e-12:
                v = min(v, ax.a_trans * cycle_s / dv)
        return v
    ka, kb = a.curvature(at_end=True), b.curvature(at_end=False)
    dk = np.abs(kb - ka)
    for ax, dki in zip(axes, dk, strict=True):
        if dki > 1e-12 and math.isfinite(ax.j_trans):
            v = min(v, math.sqrt(ax.j_trans * cycle_s / dki))
    return v


def plan_window(
    plan: np.ndarray,
    s_now: float,
    v_now: float,
    a_now: float,
    elements: list[Element],
    limits: list[Limits],
    junctions: list[float],
    cycle_s: float,
) -> int:
    """Fill `plan` with the path from (s_now, v_now, a_now) to rest at the end of the last
    element; `junctions[i]` caps the speed between elements i and i+1 (0: stop there).
    Returns the segment count (at most 7 per element: the window must fit the table)."""
    n = len(elements)
    lengths = [e.length for e in elements]
    lengths[0] = max(elements[0].s0 + elements[0].length - s_now, 0.0)
    v_end = [0.0] * n
    for i in range(n - 1, 0, -1):  # backward: from where can element i still keep its end?
        reach = speed_within(lengths[i], v_end[i], limits[i].v_cap, True, limits[i].lim, cycle_s)
        v_end[i - 1] = min(junctions[i - 1], limits[i - 1].v_cap, limits[i].v_cap, reach)
    k, v, a = 0, v_now, a_now
    for i in range(n):
        if lengths[i] <= 1e-12:
            continue
        k, v = move_through(
            plan, k, v, a, lengths[i], limits[i].v_cap, v_end[i], limits[i].lim, cycle_s
        )
        a = 0.0
    return k


__all__ = [
    "AxisDynamics",
    "Limits",
    "element_limits",
    "junction_speed",
    "plan_window",
    "single_stage",
]
