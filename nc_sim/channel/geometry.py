"""Path elements: the geometry of one motion block (a line or an arc) over the path axes.

Positions are vectors over the channel's path axes in their order; an element maps its path
length u (0..length) to a point, with unit tangent and curvature at its ends for the block
transitions. Arcs lie in the plane of two path axes (the active G17/G18/G19 plane); the other
axes move linearly along them (a helix).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nc_sim.channel import canon
from nc_sim.channel.coupling import Coupling
from nc_sim.channel.modal import PLANES
from nc_sim.kernel import layout as L

TWO_PI = 2.0 * math.pi


@dataclass
class Element:
    """One motion block's path: a straight line, or an arc when `arc` is set."""

    line: int  # program line
    rapid: bool  # G00
    start: np.ndarray
    end: np.ndarray
    length: float
    feed_mm_min: float | None  # G01/G02/G03 path feed
    lin: np.ndarray  # position change per unit path length (lines: the direction)
    arc: tuple[int, int, float, float, float, float, float] | None = None
    # (i0, i1, cx, cy, r, phi0, dphi): plane axes' indexes, centre, radius, angles (rad)
    exact_stop: bool = False  # G60: the path stops at its end
    s0: float = 0.0  # path length at its start (set when queued)
    block_id: int = 0  # the MDI block it belongs to (0 in a program)
    modal: tuple[int, int, bool, float | None] = (0, 17, True, None)  # G, plane, G90, F
    actions: list[tuple[canon.Call, int]] = field(default_factory=list)  # start on leaving it
    coupling: Coupling | None = None  # G33/G63: the path follows a spindle
    # G130-G133 of a feed block, per path axis as a fraction (None: 100 %) [002 §2.5.1]
    acceleration_weight: np.ndarray | None = None
    ramp_time_weight: np.ndarray | None = None
    # #VECTOR LIMIT on it: path speed (mm/s), acceleration and deceleration (mm/s²)
    path_limit: tuple[float, float, float] | None = None
    parallel_manual: bool = False  # G201: the path keeps its share of the axes' dynamics

    def tangent(self, at_end: bool) -> np.ndarray:
        """Unit tangent (d point / d u) at the start or the end."""
        t = self.lin.copy()
        if self.arc is not None:
            i0, i1, _cx, _cy, r, phi0, dphi = self.arc
            phi = phi0 + dphi if at_end else phi0
            w = dphi / self.length
            t[i0] = -r * w * math.sin(phi)
            t[i1] = r * w * math.cos(phi)
        return t

    def curvature(self, at_end: bool) -> np.ndarray:
        """d² point / d u² at the start or the end (zero on a line)."""
        k = np.zeros_like(self.lin)
        if self.arc is not None:
            i0, i1, _cx, _cy, r, phi0, dphi = self.arc
            phi = phi0 + dphi if at_end else phi0
            w = dphi / self.length
            k[i0] = -r * w * w * math.cos(phi)
            k[i1] = -r * w * w * math.sin(phi)
        return k

    def weights(self) -> np.ndarray:
        """Largest |d axis / d u| over the element, per axis (how much of the path speed an
        axis may have to carry)."""
        wgt: np.ndarray = np.abs(self.lin)
        if self.arc is not None:
            i0, i1, _cx, _cy, r, _phi0, dphi = self.arc
            wgt[i0] = wgt[i1] = abs(r * dphi / self.length)
        return wgt

    def write(self, row: np.ndarray) -> None:
        """Fill a kernel geometry row (nc_sim/kernel/layout.py E_*)."""
        row[:] = 0.0
        row[L.E_S0] = self.s0
        row[L.E_LEN] = self.length
        row[L.E_LINE] = self.line
        n = len(self.start)
        row[L.E_P0 : L.E_P0 + n] = self.start
        row[L.E_LIN : L.E_LIN + n] = self.lin
        if self.arc is not None:
            i0, i1, cx, cy, r, phi0, dphi = self.arc
            row[L.E_ARC] = 1.0
            row[L.E_I0], row[L.E_I1] = i0, i1
            row[L.E_CX], row[L.E_CY], row[L.E_R] = cx, cy, r
            row[L.E_PHI0], row[L.E_DPHI] = phi0, dphi
        if self.coupling is not None:
            self.coupling.write(row)


def _vector(
    axes: tuple[str, ...], end: tuple[tuple[str, float], ...], start: np.ndarray
) -> np.ndarray:
    out = start.copy()
    index = {a: i for i, a in enumerate(axes)}
    for name, value in end:
        if name in index:
            out[index[name]] = value
    return out


def straight(
    axes: tuple[str, ...],
    start: np.ndarray,
    call: canon.StraightTraverse | canon.StraightFeed | canon.ThreadFeed | canon.TapFeed,
    feed_mm_min: float | None,
    linear: np.ndarray | None = None,
    radius_mm: np.ndarray | None = None,
) -> Element | None:
    """The element of a G00/G01 (or G33/G63) block from `start`; None when it does not move.
    Its path length is over the `linear` axes (mask, default all): a rotary axis follows in
    proportion, and alone its degrees are the path (F in °/min). With `radius_mm` (per axis,
    from RX/RY/RZ [003 §1.2]) a rotary axis' degrees count as the arc at that radius."""
    end = _vector(axes, call.end, start)
    d = end - start
    if radius_mm is not None and linear is not None:
        arc_mm = np.radians(d) * radius_mm * (1.0 - linear)  # rotary axes only
        length = float(np.hypot(np.linalg.norm(d * linear), np.linalg.norm(arc_mm)))
        if length < 1e-9:
            length = _length(d, linear)
    else:
        length = _length(d, linear)
    if length < 1e-9:
        return None
    rapid = isinstance(call, canon.StraightTraverse)
    return Element(call.line, rapid, start, end, length, None if rapid else feed_mm_min, d / length)


def _length(d: np.ndarray, linear: np.ndarray | None) -> float:
    """Path length of a move `d`: over the linear axes, else (a rotary axis alone) all."""
    if linear is not None:
        along = float(np.linalg.norm(d * linear))
        if along >= 1e-9:
            return along
    return float(np.linalg.norm(d))


def arc(
    axes: tuple[str, ...],
    start: np.ndarray,
    call: canon.ArcFeed,
    feed_mm_min: float | None,
    linear: np.ndarray | None = None,
) -> Element | None:
    """The element of a G02/G03 block from `start` (a full circle when it ends where it
    starts); None when its plane's axes are not path axes."""
    first, second, _normal = PLANES[call.plane]
    if first not in axes or second not in axes:
        return None
    i0, i1 = axes.index(first), axes.index(second)
    end = _vector(axes, call.end, start)
    cx, cy = call.centre
    r = math.hypot(start[i0] - cx, start[i1] - cy)
    if r < 1e-9:
        return None
    phi0 = math.atan2(start[i1] - cy, start[i0] - cx)
    phi1 = math.atan2(end[i1] - cy, end[i0] - cx)
    dphi = (phi1 - phi0) % TWO_PI if call.turn > 0 else -((phi0 - phi1) % TWO_PI)
    if abs(dphi) < 1e-12:
        dphi = TWO_PI * call.turn  # a full circle
    other = end - start
    other[i0] = other[i1] = 0.0
    along = other if linear is None else other * linear  # a rotary axis follows the arc
    length = math.hypot(r * abs(dphi), float(np.linalg.norm(along)))
    lin = other / length
    # the arc ends on its circle: the next block starts there (within the 2 µm tolerance)
    end[i0] = cx + r * math.cos(phi0 + dphi)
    end[i1] = cy + r * math.sin(phi0 + dphi)
    return Element(
        call.line, False, start, end, length, feed_mm_min, lin, (i0, i1, cx, cy, r, phi0, dphi)
    )


def point_at(e: Element, u: float) -> np.ndarray:
    """The point at path length u into the element (the kernel's mapping, for checks)."""
    p = e.start + e.lin * u
    if e.arc is not None:
        i0, i1, cx, cy, r, phi0, dphi = e.arc
        phi = phi0 + dphi * u / e.length
        p[i0] = cx + r * math.cos(phi)
        p[i1] = cy + r * math.sin(phi)
    return p
