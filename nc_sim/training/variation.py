"""Per-seat numbers: an exercise's fault sizes and starting values that differ from seat to
seat, so neighbours in a class cannot copy each other's answer.

    [[vary]]
    key = "faults[0].factor"   # a number of a fault (faults[i].<field>) or of a starting
    min = 0.35                 # value (start[i].value)
    max = 0.60
    step = 0.005               # the values lie on this grid from min to max

A class's seats get different numbers as long as the grid has enough of them: seat n takes
the grid point (a·n + b) mod N, a ≈ 0.618·N coprime to N (seats next to each other a good
part of the range apart) and b drawn from a seed made of the class and the exercise, so
the same seat of the same class gets the same numbers after any restart.
"""

from __future__ import annotations

import math
import random
import re
import zlib
from dataclasses import dataclass
from typing import Literal

KEY_RE = re.compile(r"(faults|start)\[(\d{1,2})\]\.([a-z_]{1,32})")
MAX_STEPS = 100_000  # values on a grid: more would be a typo'd step
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0  # seat after seat spreads evenly over the range


@dataclass(frozen=True)
class Vary:
    """One number of the exercise drawn per seat from min..max on a grid of `step`."""

    key: str
    section: Literal["faults", "start"]
    index: int
    field: str
    lo: float
    hi: float
    step: float

    @property
    def steps(self) -> int:
        """The grid points above `lo` (0: one value only)."""
        return round((self.hi - self.lo) / self.step)

    def pick(self, rng: random.Random, seat: int) -> float:
        """Seat `seat`'s value: a different grid point for each of N seats in a row."""
        n = self.steps + 1
        a = max(1, round(n * GOLDEN))  # neighbours a good part of the range apart
        while math.gcd(a, n) != 1:
            a += 1
        b = rng.randrange(n)
        return round(self.lo + self.step * ((a * seat + b) % n), 12)


def seat_seed(class_id: str, exercise_id: str) -> int:
    """The seed of a class's numbers in an exercise (stable across processes, unlike hash)."""
    return zlib.crc32(f"{class_id}/{exercise_id}".encode())


def draw(vary: tuple[Vary, ...], seed: int, seat: int) -> dict[str, float]:
    """Every varied number's value for one seat of a class: key -> value."""
    rng = random.Random(seed)
    return {v.key: v.pick(rng, seat) for v in vary}
