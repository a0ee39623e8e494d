"""Progress and the time-weighted score of one seat, as process-industry trainers weigh them.

The rule: a check counts once it has passed (its first pass is kept, as a trainer's
checklist ticks it off; `CheckResult.passed` shows whether it still holds). Each counted
check earns its points × the time weight of its first pass, t seconds after the start:

    w(t) = 1                                    for t ≤ par
    w(t) = 1 − 0.5 · (t − par) / (2 · par)      for par < t < 3 · par   (1 → 0.5)
    w(t) = 0.5                                  for t ≥ 3 · par

Times are seconds of the seat (simulated time), as the gateway keeps them across the
seat machine's rebuilds. The score is the sum of these, minus the cost of every hint taken,
never below 0.
Progress is the number of counted checks against all of them.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass

from nc_sim.training.exercise import Exercise

LATE_FACTOR = 3.0  # at this multiple of the par time the weight reaches its floor
FLOOR_WEIGHT = 0.5


def time_weight(t_s: float, par_time_s: float) -> float:
    """The weight of a check first passed t_s seconds after the start (see the module)."""
    if t_s <= par_time_s:
        return 1.0
    late = (t_s - par_time_s) / ((LATE_FACTOR - 1.0) * par_time_s)
    return max(FLOOR_WEIGHT, 1.0 - (1.0 - FLOOR_WEIGHT) * late)


@dataclass(frozen=True)
class CheckScore:
    id: str
    points: float  # the check's full points
    earned: float  # points × weight, 0 while not passed
    weight: float | None  # None while not passed
    passed_after_s: float | None


@dataclass(frozen=True)
class Score:
    """A seat's standing in its exercise."""

    passed: int  # checks passed (at least once)
    total: int
    points: float  # earned minus hint costs, ≥ 0
    max_points: float
    hint_cost: float
    checks: tuple[CheckScore, ...]


def score(
    exercise: Exercise,
    first_passed_s: Mapping[str, float],
    hints_taken: Collection[int] = (),
) -> Score:
    """Progress and score from the checks' first passes: check id -> seconds after the start
    (checks not named have not passed); `hints_taken` are indices into exercise.hints (each
    counted once). Raises ValueError for a check the exercise lacks or an unknown hint index."""
    known = {c.id for c in exercise.checks}
    unknown = sorted(set(first_passed_s) - known)
    if unknown:
        raise ValueError(f"checks {unknown} are not the exercise's checks")
    rows: list[CheckScore] = []
    for c in exercise.checks:
        if c.id not in first_passed_s:
            rows.append(CheckScore(c.id, c.points, 0.0, None, None))
            continue
        t_s = max(0.0, first_passed_s[c.id])
        w = time_weight(t_s, exercise.par_time_s)
        rows.append(CheckScore(c.id, c.points, c.points * w, w, t_s))
    for i in hints_taken:
        if not 0 <= i < len(exercise.hints):
            raise ValueError(f"no hint {i}: the exercise has {len(exercise.hints)}")
    cost = sum(exercise.hints[i].cost for i in set(hints_taken))
    earned = sum(r.earned for r in rows)
    return Score(
        passed=sum(r.weight is not None for r in rows),
        total=len(rows),
        points=max(0.0, earned - cost),
        max_points=exercise.max_points,
        hint_cost=cost,
        checks=tuple(rows),
    )
