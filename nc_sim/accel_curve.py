"""Speed-dependent spindle acceleration a(n) [000 §2.8.4, DOMAIN §4.1], speeds n in °/s.

    typ 1 hyperbola:   a = b1 / (1 + b2·ν²·(1 + b3·ν²)),  ν = n / n_limit   (n > n_limit)
    typ 2 polynomial:  a = b3·Δn³ + b2·Δn² + b1·Δn + a_konst,  Δn = n - n_limit
    typ 3 asynchronous: a_max below N1, a_max·N1/n up to N2, a_max·N1/n·N2/n above
Below n_limit types 1 and 2 give a_konst; every type is floored at a_min.

The law is plain Python, so parameter checks import it without numba; the kernel compiles
this same function (nc_sim/kernel/curve.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nc_sim.units import Quantity, to_eng

# the least acceleration a curve must give: one unit of the list's accelerations (a_min,
# a_konst, a_max are whole °/s²); below it (1e-304 °/s² from b2 = 1e308) nothing accelerates
A_LEAST = to_eng(Quantity.ACCELERATION, 1)
CURVE_NONE = 0
CURVE_HYPERBOLA = 1
CURVE_POLYNOMIAL = 2
CURVE_ASYNC = 3


def curve_accel(
    typ: int,
    n: float,
    n_limit: float,
    a_konst: float,
    b1: float,
    b2: float,
    b3: float,
    a_min: float,
    a_max3: float,
    n1: float,
    n2: float,
) -> float:
    """Acceleration (°/s²) the curve allows at speed |n| (°/s); the kernel runs it compiled."""
    n = abs(n)
    if typ == CURVE_HYPERBOLA:
        if n <= n_limit or n_limit <= 0.0:
            a = a_konst
        else:
            nu2 = (n / n_limit) ** 2
            a = b1 / (1.0 + b2 * nu2 * (1.0 + b3 * nu2))
    elif typ == CURVE_POLYNOMIAL:
        if n <= n_limit:
            a = a_konst
        else:
            dn = n - n_limit
            a = ((b3 * dn + b2) * dn + b1) * dn + a_konst
    elif typ == CURVE_ASYNC:
        if n <= n1:
            a = a_max3
        elif n <= n2 or n2 <= 0.0:
            a = a_max3 * n1 / n
        else:
            a = a_max3 * n1 / n * n2 / n
    else:
        a = a_konst
    return max(a, a_min)


@dataclass(frozen=True)
class CurveParams:
    """The acceleration curve of one gear record in engineering units (°/s, °/s²)."""

    typ: int
    n_limit: float
    a_konst: float
    b1: float
    b2: float
    b3: float
    a_min: float
    a_max3: float
    n1: float
    n2: float
    a_cap: float  # a_max (and a tool's a_max): the kernel never accelerates faster

    def accel(self, n: float) -> float:
        """Acceleration (°/s²) at speed n (°/s), as the kernel applies it."""
        a = curve_accel(
            self.typ,
            n,
            self.n_limit,
            self.a_konst,
            self.b1,
            self.b2,
            self.b3,
            self.a_min,
            self.a_max3,
            self.n1,
            self.n2,
        )
        return min(a, self.a_cap)

    def speeds(self, v_from: float, v_to: float, steps: int = 256) -> np.ndarray:
        """The speeds the checks sample between v_from and v_to (both included)."""
        return np.linspace(v_from, v_to, steps + 1)

    def dead_speed(self, v_from: float, v_to: float) -> float | None:
        """The first sampled speed between v_from and v_to where the curve gives no usable
        acceleration (below A_LEAST or not finite): a speed change there would never end."""
        for n in self.speeds(v_from, v_to):
            a = self.accel(float(n))
            if not (math.isfinite(a) and a >= A_LEAST):
                return float(n)
        return None
