"""Spindle-coupled path motion: G33 thread cutting and G63 tapping [000 §2.8.6-§2.8.7].

A coupled element is a straight path element whose path length follows the spindle's actual
angle (the kernel's `_advance_coupled`), not the look-ahead plan. `Coupling` holds what the
interpreter programmed and, once the element starts (the machine's `start_coupling`), the
spindle slot, direction, coupling angle and, for a thread, its lead-in and lead-out angles.

Thread law, with phi the rotation since the coupling angle and k the path per degree:

    u(phi) = k·phi²/(2·PHI_IN)                     0 <= phi < PHI_IN        (accelerate)
           = k·(phi - PHI_IN/2)                    up to PHI_TOT - PHI_OUT  (synchronised)
           = L - k·(PHI_TOT - phi)²/(2·PHI_OUT)    up to PHI_TOT            (brake)

PHI = k·w²/a gives the path acceleration a at the spindle speed w (°/s); PHI_TOT =
L/k + (PHI_IN + PHI_OUT)/2. The coupling angle is the next zero passage plus S.OFFSET, so
every pass of a thread, and every start of a multi-start thread, meets its own groove.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nc_sim.kernel import layout as L

REV_DEG = 360.0


@dataclass
class Coupling:
    """What couples an element to a spindle (see the module docstring)."""

    kind: int  # L.COUPLE_THREAD or L.COUPLE_TAP
    spindle: str  # "S" (the main spindle) or a spindle's name
    pitch_mm: float  # path length per spindle revolution
    speed_rpm: float = 0.0  # G63: the tapping speed, signed (negative: reverse)
    offset_deg: float = 0.0  # G33: S.OFFSET, the start after the zero passage
    # set when the element starts
    slot: int = -1
    direction: int = 1
    theta0_deg: float = 0.0
    phi_in_deg: float = 0.0
    phi_out_deg: float = 0.0
    phi_tot_deg: float = 0.0

    @property
    def k_mm_per_deg(self) -> float:
        return self.pitch_mm / REV_DEG

    def write(self, row: np.ndarray) -> None:
        """Fill the coupling columns of a kernel geometry row."""
        row[L.E_SPDL] = self.slot + 1
        row[L.E_KIND] = self.kind
        row[L.E_K] = self.k_mm_per_deg
        row[L.E_DIR] = self.direction
        row[L.E_TH0] = self.theta0_deg
        row[L.E_PHI_IN] = self.phi_in_deg
        row[L.E_PHI_OUT] = self.phi_out_deg
        row[L.E_PHI_TOT] = self.phi_tot_deg


def coupling_angle(angle_deg: float, direction: int, offset_deg: float, margin_deg: float) -> float:
    """The first angle at least `margin_deg` ahead of `angle_deg` in `direction` that lies
    `offset_deg` after a zero passage (angle ≡ offset mod 360)."""
    if direction > 0:
        turns = math.ceil((angle_deg + margin_deg - offset_deg) / REV_DEG)
    else:
        turns = math.floor((angle_deg - margin_deg - offset_deg) / REV_DEG)
    return offset_deg + REV_DEG * turns


def thread_ramps(
    c: Coupling, length_mm: float, w_deg_s: float, a_acc: float, a_dec: float
) -> float | None:
    """Set the lead-in and lead-out angles of a thread for the spindle speed `w_deg_s` and the
    path's acceleration and deceleration (mm/s²); None when the thread is too short to reach
    its speed and stop again (the distance it would need, mm, is then `ramp_length`)."""
    k = c.k_mm_per_deg
    c.phi_in_deg = k * w_deg_s * w_deg_s / a_acc
    c.phi_out_deg = k * w_deg_s * w_deg_s / a_dec
    c.phi_tot_deg = length_mm / k + 0.5 * (c.phi_in_deg + c.phi_out_deg)
    if ramp_length(c) > length_mm:
        return None
    return c.phi_tot_deg


def ramp_length(c: Coupling) -> float:
    """Path length the lead-in and lead-out of a thread take (mm)."""
    return 0.5 * c.k_mm_per_deg * (c.phi_in_deg + c.phi_out_deg)
