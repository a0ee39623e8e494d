"""The acceleration curve a(n) (nc_sim/accel_curve.py) compiled for the kernel's cycle."""

from __future__ import annotations

from numba import njit

from nc_sim import accel_curve

curve_accel = njit(cache=True)(accel_curve.curve_accel)
