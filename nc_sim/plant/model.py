"""The drive cascade and mechanics of one axis as numbers, and their exact discretisation.

Signal flow per drive step Ts (nc_sim/plant/step.py runs it):

    speed setpoint -> PT1 filter -> PI controller (measured motor speed) -> torque limit
      -> one step of computing time -> current setpoint filters (PT2 low pass or general
      second-order: (s²/ωn² + 2·Dn·s/ωn + 1) / (s²/ωd² + 2·Dd·s/ωd + 1)) -> current loop
      (first-order lag T_i) -> motor torque -> mechanics

Mechanics, all referred to the motor shaft: rigid, J = J_M·ratio; or two masses, motor J_M and
load J_L = J_M·(ratio - 1) on a spring k = J_L·(2π·f_ar)² with damping d = 2·D·√(k·J_L), so
the load alone on the spring swings at the anti-resonance f_ar and the whole at the resonance
f_r = f_ar·√(1 + J_L/J_M). Friction and the backlash gap act on the load.

The filters, current loop and mechanics form one linear system driven by inputs held over the
step (torque setpoint, friction torque, backlash correction). It is discretised exactly for
such inputs (zero-order hold): [[Ad, Bd], [0, I]] = expm([[A, B], [0, 0]]·Ts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from nc_sim.plant import layout as PL


@dataclass(frozen=True)
class SecondOrderFilter:
    """A current-setpoint filter: PT2 low pass (numerator 1) or general second order."""

    denominator_hz: float
    denominator_damping: float
    numerator_hz: float = 0.0  # 0: PT2 low pass
    numerator_damping: float = 0.0

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """(a, b, c, d) with H(s) = c·(sI - a)⁻¹·b + d, controllable canonical form."""
        wd = 2.0 * math.pi * self.denominator_hz
        a0, a1 = wd * wd, 2.0 * self.denominator_damping * wd  # s² + a1·s + a0 (scaled by ωd²)
        a = np.array([[0.0, 1.0], [-a0, -a1]])
        b = np.array([[0.0], [1.0]])
        if self.numerator_hz <= 0.0:  # ωd² / (s² + a1·s + a0)
            return a, b, np.array([[a0, 0.0]]), 0.0
        wn = 2.0 * math.pi * self.numerator_hz
        # numerator (ωd²/ωn²)·(s² + 2·Dn·ωn·s + ωn²) = d·s² + n1·s + n0
        d = a0 / (wn * wn)
        n1 = d * 2.0 * self.numerator_damping * wn
        n0 = a0
        return a, b, np.array([[n0 - d * a0, n1 - d * a1]]), d


@dataclass(frozen=True)
class DriveModel:
    """One axis' drive and mechanics in SI units referred to the motor."""

    sampling_s: float  # the drive's step Ts
    substeps: int  # drive steps per NC cycle
    kp: float  # speed controller gain (Nm·s/rad)
    tn_s: float  # integral time, 0: P controller
    torque_limit: float  # Nm
    speed_filter_s: float  # speed setpoint PT1, 0: none
    current_t_s: float  # current loop's time constant (> 0)
    filters: tuple[SecondOrderFilter, ...]  # active current-setpoint filters, in order
    motor_inertia: float  # J_M (kg·m²)
    inertia_ratio: float  # (J_M + J_L) / J_M
    anti_resonance_hz: float  # 0: rigid
    damping: float  # of the coupling at the anti-resonance
    unit_per_rad: float  # load travel per motor radian (mm | °)
    coulomb: float = 0.0  # Nm
    breakaway: float = 0.0  # Nm
    stribeck_rad_s: float = 1.0
    viscous: float = 0.0  # Nm·s/rad on the load
    backlash: float = 0.0  # mm | °
    direct: bool = True  # the NC's measuring system on the load

    @property
    def two_mass(self) -> bool:
        return self.anti_resonance_hz > 0.0 and self.inertia_ratio > 1.0

    @property
    def total_inertia(self) -> float:
        return self.motor_inertia * self.inertia_ratio

    @property
    def load_inertia(self) -> float:
        return self.motor_inertia * (self.inertia_ratio - 1.0)

    @property
    def stiffness(self) -> float:
        """Coupling stiffness k (Nm/rad) that puts the anti-resonance at f_ar."""
        return self.load_inertia * (2.0 * math.pi * self.anti_resonance_hz) ** 2

    @property
    def coupling_damping(self) -> float:
        return 2.0 * self.damping * math.sqrt(self.stiffness * self.load_inertia)

    def speed_loop_time_constant_s(self) -> float:
        """What the NC's lag model takes for the closed speed loop: its equivalent time
        constant, the delay with which it follows a slow setpoint (the first moment of its
        response). On a rigid mass a P loop lags by J/Kp; a PI loop follows a speed ramp
        without error, so only the current loop, the computing time and the setpoint filter
        remain. (Taking J/Kp for a PI loop made a spindle's ramp trip lag monitoring.)"""
        if self.kp <= 0.0:
            return math.inf
        delays = self.current_t_s + 1.5 * self.sampling_s + self.speed_filter_s
        return delays if self.tn_s > 0.0 else self.total_inertia / self.kp + delays

    def continuous(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) of the linear part, states as nc_sim/plant/layout.py's x, inputs u."""
        nx = PL.X_FILTERS + 2 * len(self.filters)
        a = np.zeros((nx, nx))
        b = np.zeros((nx, PL.NU))
        # the signal after each filter as (row over x, factor of the torque input)
        w_x = np.zeros(nx)
        w_u = 1.0
        for i, f in enumerate(self.filters):
            fa, fb, fc, fd = f.state_space()
            j = PL.X_FILTERS + 2 * i
            a[j : j + 2, j : j + 2] = fa
            a[j : j + 2, :] += fb @ w_x[None, :]
            b[j : j + 2, PL.U_TORQUE] += fb[:, 0] * w_u
            out_x = fd * w_x
            out_x[j : j + 2] += fc[0]
            w_x, w_u = out_x, fd * w_u
        # motor torque: the current loop's lag on the filtered setpoint
        t = self.current_t_s
        a[PL.X_TORQUE, :] += w_x / t
        a[PL.X_TORQUE, PL.X_TORQUE] -= 1.0 / t
        b[PL.X_TORQUE, PL.U_TORQUE] = w_u / t
        wm, wl, de, tr = PL.X_WM, PL.X_WL, PL.X_DEF, PL.X_TRAVEL
        if self.two_mass:
            jm, jl = self.motor_inertia, self.load_inertia
            k, d = self.stiffness, self.coupling_damping
            a[wm, PL.X_TORQUE] = 1.0 / jm
            a[wm, de] -= k / jm
            a[wm, wm] -= d / jm
            a[wm, wl] += d / jm
            b[wm, PL.U_PLAY] = 1.0 / jm
            a[wl, de] += k / jl
            a[wl, wm] += d / jl
            a[wl, wl] -= (d + self.viscous) / jl
            b[wl, PL.U_FRICTION] = 1.0 / jl
            b[wl, PL.U_PLAY] = -1.0 / jl
            a[de, wm], a[de, wl] = 1.0, -1.0
            a[tr, wl] = 1.0
        else:
            jt = self.total_inertia
            a[wm, PL.X_TORQUE] = 1.0 / jt
            a[wm, wm] -= self.viscous / jt
            b[wm, PL.U_FRICTION] = 1.0 / jt
            a[tr, wm] = 1.0
        return a, b

    def discrete(self) -> tuple[np.ndarray, np.ndarray]:
        """(Ad, Bd): the linear part over one drive step with its inputs held."""
        a, b = self.continuous()
        nx, nu = b.shape
        m = np.zeros((nx + nu, nx + nu))
        m[:nx, :nx] = a
        m[:nx, nx:] = b
        e = expm(m * self.sampling_s)
        return e[:nx, :nx], e[:nx, nx:]

    def speed_open_loop(self, f_hz: np.ndarray) -> np.ndarray:
        """The speed loop's open loop as the drive runs it, at frequencies `f_hz`: its PI,
        the step of computing time, then filters, current loop and mechanics from torque
        setpoint to measured motor speed, sampled exactly (zero-order hold over Ts). The
        linear part only: what friction and backlash do is not in it."""
        ad, bd = self.discrete()
        z = np.exp(2j * np.pi * np.asarray(f_hz, dtype=float) * self.sampling_s)
        eye = np.eye(ad.shape[0])
        # (zI - Ad)⁻¹·Bd for every z at once, its motor-speed row
        x = np.linalg.solve(
            z[:, None, None] * eye - ad, np.broadcast_to(bd[:, :1], (z.size, *bd[:, :1].shape))
        )
        plant = x[:, PL.X_WM, 0]
        integral = self.sampling_s / self.tn_s * z / (z - 1.0) if self.tn_s > 0.0 else 0.0
        return np.asarray(self.kp * (1.0 + integral) * plant / z)

    def kernel_row(self) -> np.ndarray:
        """The slot's `pl` row for this model."""
        row = np.zeros(PL.PL_COLS)
        ad, bd = self.discrete()
        nx = ad.shape[0]
        row[PL.PL_MODEL] = PL.MODEL_CASCADE
        row[PL.PL_SUBSTEPS] = self.substeps
        row[PL.PL_KP] = self.kp
        row[PL.PL_INV_TN] = 1.0 / self.tn_s if self.tn_s > 0.0 else 0.0
        row[PL.PL_T_MAX] = self.torque_limit
        row[PL.PL_SP_ALPHA] = (
            1.0 - math.exp(-self.sampling_s / self.speed_filter_s)
            if self.speed_filter_s > 0.0
            else 1.0
        )
        row[PL.PL_UNIT_PER_RAD] = self.unit_per_rad
        row[PL.PL_TWO_MASS] = 1.0 if self.two_mass else 0.0
        row[PL.PL_DIRECT] = 1.0 if self.direct else 0.0
        row[PL.PL_COULOMB] = self.coulomb
        row[PL.PL_BREAKAWAY] = max(self.breakaway, self.coulomb)
        row[PL.PL_STRIBECK] = self.stribeck_rad_s
        half = 0.5 * self.backlash
        row[PL.PL_HALF_PLAY] = half / self.unit_per_rad if self.two_mass else half
        row[PL.PL_K] = self.stiffness if self.two_mass else 0.0
        row[PL.PL_D] = self.coupling_damping if self.two_mass else 0.0
        row[PL.PL_NX] = nx
        for i in range(nx):
            row[PL.PL_AD + i * PL.NX_MAX : PL.PL_AD + i * PL.NX_MAX + nx] = ad[i]
            row[PL.PL_BD + i * PL.NU : PL.PL_BD + (i + 1) * PL.NU] = bd[i]
        return row
