"""Objective checks of an exercise, evaluated on a running machine.

The service keeps one `ExerciseMonitor` per seat next to its machine and calls
`feed(machine, rows, first_cycle)` about ten times a second with the kernel's sample rows
recorded since the last call (`Simulation.run(n, rec)` fills them: shape (n, slots, R_COLS),
rows[0] is cycle `first_cycle`), then `results()`. Events come from `machine.events`, read by
the monitor's own cursor. Evaluation is vectorised over the rows of one slot per check, so
fifty seats at 10 Hz stay cheap.

Two sorts of check: achievements (`event`, `in_position`, `speed_reached`) are passed from
the sample or event that shows them; states (`gain`, `no_event`) hold or not as the machine
is now. Every result keeps the first cycle it passed (the score weighs that time) and a
detail with the measured figure.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.params.curves import GEARS
from nc_sim.units import RPM_TO_DEG_S

if TYPE_CHECKING:  # the gateway imports the checks without the kernel
    from nc_sim.machine.machine import Machine

# a constant-speed stretch is measured once the lag has settled: SETTLE_TAU time constants
# (1/kv) after the speed became constant, then averaged over at least AVERAGE_TAU more
SETTLE_TAU = 10.0
AVERAGE_TAU = 5.0
MIN_AVERAGE_S = 0.2
LAG_INCREMENTS = 20.0  # the mean lag must span this many encoder increments to be measured
V_SAME = 1e-9  # relative change of the commanded speed still counted as constant


# --- the check kinds (what a file's [[checks]] entry says) ---------------------------------


@dataclass(frozen=True)
class GainCheck:
    """The measured loop gain k = v/lag of `axis` over a steady constant-speed stretch
    (position-controlled, settled) is within `within_pct` % of the active gear record's kv
    [004 §3.6.2] (of axis `against`'s first gear record when given)."""

    kind: ClassVar[str] = "gain"
    axis: str
    within_pct: float
    # the kv of this axis instead of its own: both follow alike, e.g. the plane's axes of a
    # circle without the servo mismatch's ellipse
    against: str | None = None
    # the kv the exercise started with is the reference, and a changed kv fails: a task that
    # says "keep kv" is not solved by lowering kv to the gain the faulty drive delivers
    keep_kv: bool = False


@dataclass(frozen=True)
class EventCheck:
    """An event `code` happened since the exercise started (of `axis`, to gear stage `gear`
    when given), e.g. EV_GEAR_CHANGED to gear 2, EV_ROTARY_MODE."""

    kind: ClassVar[str] = "event"
    code: Code
    axis: str | None = None
    gear: int | None = None


@dataclass(frozen=True)
class NoEventCheck:
    """`axis` has been in use for `window_s` without any of `codes` (of it): its first motion
    since the last such event (or the start) lies `window_s` back, and it moved in at least
    `busy_pct` % of that window's seconds. A student who does nothing, moved once a moment
    ago, or moved a few seconds and then waited, does not pass."""

    kind: ClassVar[str] = "no_event"
    codes: tuple[Code, ...]
    axis: str
    window_s: float
    busy_pct: float = 50.0


@dataclass(frozen=True)
class InPositionCheck:
    """`axis` stands in position (its exact-stop signal) within `tolerance` (mm | °) of
    `target`, modulo 360° for a spindle; in gear stage `gear` when given. The rotary-axis name
    of the main spindle (C) asks for rotary axis mode, its spindle name for spindle mode."""

    kind: ClassVar[str] = "in_position"
    axis: str
    target: float
    tolerance: float
    gear: int | None = None


@dataclass(frozen=True)
class SpeedReachedCheck:
    """Spindle `axis` reports speed reached at a commanded speed of at least `speed_rpm`
    (in gear stage `gear` when given)."""

    kind: ClassVar[str] = "speed_reached"
    axis: str
    speed_rpm: float
    gear: int | None = None


@dataclass(frozen=True)
class DirectionCheck:
    """`axis` moves the way the NC commands it, as the slide itself does (a dial gauge's
    view, not the NC's actual value): at constant commanded speed the load's true velocity
    has the command's sign. A sign "fixed" on the actual value (lr_hw[i].vz_istw) instead of
    the command value closes the loop but drives the slide backwards [004 §3.5]."""

    kind: ClassVar[str] = "direction"
    axis: str


@dataclass(frozen=True)
class MarginsCheck:
    """`axis`' speed loop, on the plant it drives now (faults included), keeps stability
    template `template` (1 stiff 45°/8 dB, 2 medium 55°/12 dB, 3 soft 60°/20 dB:
    nc_sim/plant/tuning.py) and, when `bandwidth_pct` > 0, reaches that share of the highest
    closed-loop bandwidth the template allows on that plant (nc_sim/training/margins.py)."""

    kind: ClassVar[str] = "margins"
    axis: str
    template: int
    bandwidth_pct: float = 0.0


@dataclass(frozen=True)
class FindingCheck:
    """The student names the axis that carries the exercise's `fault` (its kind; "backlash")
    and its size, within `within_pct` %, in at most `attempts` answers. What cannot be put
    right with a parameter is found and reported: the NC of the manuals has no backlash
    compensation. Answers are graded where they are kept (the gateway's seat, by
    nc_sim/training/findings.py), not by the monitor."""

    kind: ClassVar[str] = "finding"
    fault: str
    within_pct: float
    attempts: int = 2


Rule = (
    GainCheck
    | MarginsCheck
    | FindingCheck
    | EventCheck
    | NoEventCheck
    | InPositionCheck
    | SpeedReachedCheck
    | DirectionCheck
)
RULES: tuple[type[Rule], ...] = (
    GainCheck,
    MarginsCheck,
    FindingCheck,
    DirectionCheck,
    EventCheck,
    NoEventCheck,
    InPositionCheck,
    SpeedReachedCheck,
)


@dataclass(frozen=True)
class Check:
    """One check of an exercise: its id, the text the student sees, its points, its rule, and
    the checks that must hold with it for it to pass (`requires`): a gain measured while the
    slide runs the wrong way is no solution."""

    id: str
    text: str
    points: float
    rule: Rule
    requires: tuple[str, ...] = ()


@dataclass(frozen=True)
class CheckResult:
    """A check's state on a seat: passed now, the first cycle it passed, the measured figure."""

    id: str
    passed: bool
    first_passed_cycle: int | None
    detail: str


# --- evaluation ------------------------------------------------------------------------------


class _Evaluator(Protocol):
    passed: bool
    first_passed_cycle: int | None
    detail: str

    def feed(self, rows: np.ndarray, first_cycle: int, events: list[Event], now: int) -> None:
        """rows: this check's slot, shape (n, R_COLS); now: the cycle of the last row."""


def _passed_at(ev: _Evaluator, passed: bool, cycle: int) -> None:
    ev.passed = passed
    if passed and ev.first_passed_cycle is None:
        ev.first_passed_cycle = cycle


def _first(cond: np.ndarray) -> int | None:
    hit = np.flatnonzero(cond)
    return int(hit[0]) if hit.size else None


class _Gain:
    """Constant-speed stretches of one slot, carried across feeds; the newest one measured
    long enough decides."""

    def __init__(self, rule: GainCheck, m: Machine, slot: int) -> None:
        self.rule = rule
        self.ax = m.axis(rule.axis)
        self.ref = m.axis(rule.against) if rule.against else None
        self.cycle_s = m.k.cycle_s
        self.inc = float(m.k.pr[slot, L.P_ENC_INC])
        self.passed = False
        self.first_passed_cycle: int | None = None
        self.detail = f"no steady constant-speed stretch of {rule.axis} measured yet"
        # each gear record's kv as the exercise started (keep_kv: the reference)
        self.kv_start = {g: self.ax.cfg.eng("getriebe.kv", g) for g in range(1, GEARS + 1)}
        self.run_len = 0  # samples in the current stretch (0: none)
        self.run_v = 0.0
        self.run_gear = 0
        self.sum_v = self.sum_lag = 0.0
        self.n = 0  # settled samples summed

    def _kv(self, gear: int) -> float:
        if self.ref is not None:
            return self.ref.cfg.eng("getriebe.kv", 1)
        if self.rule.keep_kv:
            return self.kv_start.get(max(1, gear), self.ax.cfg.eng("getriebe.kv", max(1, gear)))
        return self.ax.cfg.eng("getriebe.kv", max(1, gear))

    def _kv_changed(self, gear: int) -> str:
        """The gear record's kv changed since the start, for a rule that keeps it ("" when
        not)."""
        kv0, kv = self.kv_start[gear], self.ax.cfg.eng("getriebe.kv", gear)
        if abs(kv - kv0) <= 1e-9 * kv0:
            return ""
        name = self.ax.cfg.ref("getriebe.kv", gear)[0]
        return f"{name} changed from {kv0:.2f} to {kv:.2f} 1/s: the task keeps kv"

    def feed(self, rows: np.ndarray, first_cycle: int, events: list[Event], now: int) -> None:
        v = rows[:, L.R_V_CMD]
        a = rows[:, L.R_A_CMD]
        gear = rows[:, L.R_GEAR].astype(np.int64)
        steady = (
            (rows[:, L.R_OPEN_LOOP] == 0)
            & (rows[:, L.R_READY] != 0)
            & (rows[:, L.R_JOB_ERROR] == 0)
            & (a == 0.0)
            & (v != 0.0)
        )
        v_prev = np.concatenate(([self.run_v], v[:-1]))
        g_prev = np.concatenate(([self.run_gear], gear[:-1]))
        s_prev = np.concatenate(([self.run_len > 0], steady[:-1]))
        same = (np.abs(v - v_prev) <= V_SAME * np.abs(v)) & (gear == g_prev)
        start = steady & ~(s_prev & same)
        idx = np.arange(v.size)
        last_start = np.maximum.accumulate(np.where(start, idx, -1))
        pos = np.where(last_start >= 0, idx - last_start + 1, self.run_len + idx + 1)
        pos = np.where(steady, pos, 0)
        # the stretches in this chunk: the carried one (if it goes on), then each start
        bounds = [0, *np.flatnonzero(start).tolist(), v.size]
        for lo, hi in itertools.pairwise(bounds):
            if lo == hi:
                continue
            if start[lo]:  # a new stretch: what the last one summed is its measurement
                self.sum_v = self.sum_lag = 0.0
                self.n = 0
            seg_pos = pos[lo:hi]
            live = seg_pos > 0
            if not live.any():
                continue
            g = int(gear[lo:hi][live][0])
            kv = self._kv(g)
            # settled by the slower of the reference and the gain set (they differ when the
            # task keeps kv and the student changed it)
            slow = min(kv, self.ax.cfg.eng("getriebe.kv", max(1, g)))
            settle = round(SETTLE_TAU / slow / self.cycle_s)
            use = seg_pos > settle
            self.sum_v += float(np.sum(v[lo:hi][use]))
            self.sum_lag += float(np.sum(rows[lo:hi, L.R_LAG][use]))
            self.n += int(np.count_nonzero(use))
            self._measure(kv, slow, max(1, g), first_cycle + hi - 1)
        self.run_len = int(pos[-1]) if v.size else self.run_len
        if v.size:
            self.run_v, self.run_gear = float(v[-1]), int(gear[-1])

    def _measure(self, kv: float, slow: float, gear: int, cycle: int) -> None:
        need = max(MIN_AVERAGE_S, AVERAGE_TAU / slow) / self.cycle_s
        if self.n < need:
            return
        v, lag = self.sum_v / self.n, self.sum_lag / self.n
        unit = self.ax.pos_unit
        if abs(lag) < LAG_INCREMENTS * self.inc:
            self.detail = f"lag {lag:.4f} {unit} too small to measure: run {self.rule.axis} faster"
            return
        k = v / lag
        dev_pct = (k / kv - 1.0) * 100.0
        changed = self._kv_changed(gear) if self.rule.keep_kv else ""
        _passed_at(self, abs(dev_pct) <= self.rule.within_pct and not changed, cycle)
        whose = f" of {self.ref.name}" if self.ref is not None else ""
        self.detail = (
            f"k = {k:.2f} 1/s against kv{whose} {kv:.2f} 1/s ({dev_pct:+.1f} %)"
            f" at v = {v:.3f} {unit}/s, lag {lag:.4f} {unit}" + (f"; {changed}" if changed else "")
        )


class _Direction:
    """The newest constant-speed moment at a feed decides: the plant's true velocity
    (S_V_MOTOR, which the rows do not carry) against the commanded one."""

    def __init__(self, rule: DirectionCheck, m: Machine, slot: int) -> None:
        self.rule = rule
        self.m = m
        self.slot = slot
        self.unit = m.axis(rule.axis).pos_unit
        self.passed = False
        self.first_passed_cycle: int | None = None
        self.detail = f"{rule.axis} not yet seen moving at constant speed"

    def feed(self, rows: np.ndarray, first_cycle: int, events: list[Event], now: int) -> None:
        if rows.shape[0] == 0:
            return
        last = rows[-1]
        steady = last[L.R_A_CMD] == 0.0 and last[L.R_OPEN_LOOP] == 0 and last[L.R_READY] != 0
        if not steady or last[L.R_MVPOS] == last[L.R_MVNEG]:
            return  # at rest or accelerating: the drive's own lag could show either sign
        v_cmd = float(self.m.k.st[self.slot, L.S_V_CMD])
        v_true = float(self.m.k.st[self.slot, L.S_V_MOTOR])
        if v_cmd == 0.0 or v_true == 0.0:
            return
        agrees = (v_cmd > 0.0) == (v_true > 0.0)
        _passed_at(self, agrees, now)
        u = self.unit
        self.detail = f"commanded {v_cmd:+.2f} {u}/s, the slide moves {v_true:+.2f} {u}/s" + (
            "" if agrees else ": the wrong way, although the NC's actual value follows"
        )


class _Event:
    def __init__(self, rule: EventCheck, m: Machine) -> None:
        self.rule = rule
        self.axis = m.axis(rule.axis).name if rule.axis else None
        self.passed = False
        self.first_passed_cycle: int | None = None
        what = f" of {rule.axis}" if rule.axis else ""
        gear = f" to gear stage {rule.gear}" if rule.gear else ""
        self.want = f"{rule.code.name} ({int(rule.code)}){what}{gear}"
        self.detail = f"no {self.want} yet"

    def feed(self, rows: np.ndarray, first_cycle: int, events: list[Event], now: int) -> None:
        if self.passed:
            return
        for e in events:
            if (
                e.code == self.rule.code
                and (self.axis is None or e.axis == self.axis)
                and (self.rule.gear is None or e.gear == self.rule.gear)
            ):
                _passed_at(self, True, e.cycle)
                self.detail = f"{self.want} at {e.t_s:.1f} s: {e.message}"
                return


class _NoEvent:
    def __init__(self, rule: NoEventCheck, m: Machine) -> None:
        self.rule = rule
        self.axis = m.axis(rule.axis).name
        self.codes = frozenset(int(c) for c in rule.codes)
        self.window = round(rule.window_s / m.k.cycle_s)
        self.cycle_s = m.k.cycle_s
        self.per_s = max(1, round(1.0 / m.k.cycle_s))  # cycles a second
        self.busy: set[int] = set()  # the seconds (cycle // per_s) in which the axis moved
        self.last_event: Event | None = None
        self.first_moved: int | None = None  # first motion since the last event (or start)
        self.last_moved: int | None = None
        self.passed = False
        self.first_passed_cycle: int | None = None
        self.detail = f"{rule.axis} has not moved yet"

    def feed(self, rows: np.ndarray, first_cycle: int, events: list[Event], now: int) -> None:
        for e in events:
            if e.code in self.codes and e.axis == self.axis:
                self.last_event = e
        moving = (rows[:, L.R_MVPOS] != 0) | (rows[:, L.R_MVNEG] != 0)
        cycles = first_cycle + np.flatnonzero(moving)
        after = self.last_event.cycle if self.last_event is not None else -1
        if self.first_moved is not None and self.first_moved <= after:
            self.first_moved = None  # the event ended that stretch of use
        if cycles.size:
            self.last_moved = int(cycles[-1])
            if self.first_moved is None:
                later = cycles[cycles > after]
                self.first_moved = int(later[0]) if later.size else None
            self.busy.update(np.unique(cycles // self.per_s).tolist())
        since = now - self.window
        self.busy = {b for b in self.busy if (b + 1) * self.per_s > since}
        # the seconds of the window it moved in, of those after the last such event
        busy_s = sum(1 for b in self.busy if (b + 1) * self.per_s > max(since, after))
        need_s = int(np.ceil(self.rule.busy_pct / 100.0 * self.rule.window_s - 1e-9))
        names = "/".join(
            str(c) for c in sorted(self.codes)
        )  # job error numbers, as the NC shows them
        quiet = self.last_event is None or self.last_event.cycle <= since
        long_enough = self.first_moved is not None and self.first_moved <= since
        moved_now = self.last_moved is not None and self.last_moved > since
        busy = busy_s >= need_s
        _passed_at(self, quiet and long_enough and moved_now and busy, now)
        ax, w = self.rule.axis, self.rule.window_s
        if self.first_moved is None:
            ago = ""
            if self.last_event is not None:
                t = (now - self.last_event.cycle) * self.cycle_s
                ago = f" since {names} {t:.0f} s ago ({self.last_event.message})"
            self.detail = f"{ax} has not moved{ago}"
        elif not long_enough:
            left = (self.first_moved + self.window - now) * self.cycle_s
            self.detail = f"{ax} in use without {names}: {w - left:.0f} of {w:g} s"
        elif not moved_now:
            self.detail = f"{ax} has not moved in the last {w:g} s"
        elif not busy:
            self.detail = (
                f"{ax} moved in {busy_s} of the last {w:g} s without {names}:"
                f" in use means moving in {need_s} of them"
            )
        else:
            self.detail = f"{ax} in use for {w:g} s without {names} (moving in {busy_s} s of them)"


class _Standing:
    """in_position and speed_reached: a condition per sample; passed while the newest holds."""

    def __init__(self, rule: InPositionCheck | SpeedReachedCheck, m: Machine, slot: int) -> None:
        self.rule = rule
        ax = m.axis(rule.axis)
        self.modulo = float(m.k.pr[slot, L.P_MODULO])
        # the main spindle's names: C asks for rotary axis mode, S1 / S for spindle mode
        self.rotary: bool | None = None
        if m.cax is not None and ax is m.cax.ax:
            self.rotary = rule.axis == m.cax.c_name
        self.unit = ax.pos_unit
        self.cycle_s = m.k.cycle_s
        self.passed = False
        self.first_passed_cycle: int | None = None
        self.detail = "not yet"

    def feed(self, rows: np.ndarray, first_cycle: int, events: list[Event], now: int) -> None:
        if rows.shape[0] == 0:
            return
        rule = self.rule
        cond = np.ones(rows.shape[0], dtype=bool)
        if rule.gear is not None:
            cond &= rows[:, L.R_GEAR] == rule.gear
        if self.rotary is not None:
            cond &= (rows[:, L.R_ROTARY_MODE] != 0) == self.rotary
        if isinstance(rule, InPositionCheck):
            err = rows[:, L.R_P_ACT] - rule.target
            if self.modulo > 0.0:
                err = (err + 0.5 * self.modulo) % self.modulo - 0.5 * self.modulo
            cond &= (rows[:, L.R_IN_POS] != 0) & (np.abs(err) <= rule.tolerance)
            last = (
                f"{rule.axis} at {float(rows[-1, L.R_P_ACT]):.3f} {self.unit}"
                f" ({float(err[-1]):+.3f} from {rule.target:g}),"
                f" {'in position' if rows[-1, L.R_IN_POS] else 'not in position'}"
            )
        else:
            v_rpm = np.abs(rows[:, L.R_V_CMD]) / RPM_TO_DEG_S
            cond &= (rows[:, L.R_SPEED_REACHED] != 0) & (v_rpm >= rule.speed_rpm * (1 - 1e-9))
            act = float(rows[-1, L.R_V_ACT]) / RPM_TO_DEG_S
            reached = "speed reached" if rows[-1, L.R_SPEED_REACHED] else "speed not reached"
            last = f"{rule.axis} commanded {float(v_rpm[-1]):.0f} rpm, at {act:.0f} rpm, {reached}"
        if rule.gear is not None:
            last += f", gear stage {int(rows[-1, L.R_GEAR])}"
        i = _first(cond)
        if i is not None and self.first_passed_cycle is None:
            self.first_passed_cycle = first_cycle + i
        self.passed = bool(cond[-1])
        self.detail = last


class ExerciseMonitor:
    """The checks of one exercise on one seat's machine, from the moment it is made (the
    exercise's start). Raises ValueError for a check naming an axis the machine lacks."""

    def __init__(self, checks: tuple[Check, ...], machine: Machine) -> None:
        self.checks = checks
        self.start_cycle = machine.cycle
        self.cursor = machine.events.cursor  # only what happens from now on counts
        self.missed_events = 0
        self._slots: list[int | None] = []
        self._evals: list[_Evaluator] = []
        self._judged: list[Check] = []  # the checks the monitor judges (not the findings)
        # a check with requirements: the first cycle it held with them all (None: not yet)
        self._joint: dict[str, int | None] = {c.id: None for c in checks if c.requires}
        for i, c in enumerate(checks):
            rule = c.rule
            if isinstance(rule, FindingCheck):
                continue
            axis = getattr(rule, "axis", None)
            slot: int | None = None
            if axis:
                try:
                    slot = machine.axis(axis).slot
                    against = getattr(rule, "against", None)
                    if against:
                        machine.axis(against)
                except ValueError as e:
                    raise ValueError(f"checks[{i}] ({c.id}): {e}") from None
            self._slots.append(slot)
            self._evals.append(_make(rule, machine, slot))
            self._judged.append(c)

    def feed(self, machine: Machine, rows: np.ndarray, first_cycle: int) -> None:
        """The sample rows recorded since the last call (rows[0] is cycle `first_cycle`) and
        the events logged since."""
        read = machine.events.since(self.cursor)
        self.cursor = read.cursor
        self.missed_events += read.dropped
        now = first_cycle + rows.shape[0] - 1 if rows.shape[0] else machine.cycle
        for slot, ev in zip(self._slots, self._evals, strict=True):
            ev.feed(rows[:, slot if slot is not None else 0, :], first_cycle, read.entries, now)
        for cid, joint in self._joint.items():
            if joint is None and self._holds(cid):
                self._joint[cid] = now

    def _holds(self, cid: str) -> bool:
        """The check passes now, and every check it requires too."""
        by_id = {c.id: ev for c, ev in zip(self._judged, self._evals, strict=True)}
        c = next(c for c in self._judged if c.id == cid)
        return by_id[cid].passed and all(by_id[r].passed for r in c.requires)

    def results(self) -> list[CheckResult]:
        """Each judged check's state now, in the exercise's order (a finding is not judged
        here)."""
        out = []
        by_id = {c.id: ev for c, ev in zip(self._judged, self._evals, strict=True)}
        for c, ev in zip(self._judged, self._evals, strict=True):
            if not c.requires:
                out.append(CheckResult(c.id, ev.passed, ev.first_passed_cycle, ev.detail))
                continue
            failing = [r for r in c.requires if not by_id[r].passed]
            detail = ev.detail
            if failing and ev.passed:
                detail += f" — not counted while {', '.join(failing)} fails"
            out.append(CheckResult(c.id, self._holds(c.id), self._joint[c.id], detail))
        return out


def _make(rule: Rule, m: Machine, slot: int | None) -> _Evaluator:
    match rule:
        case GainCheck():
            assert slot is not None
            return _Gain(rule, m, slot)
        case DirectionCheck():
            assert slot is not None
            return _Direction(rule, m, slot)
        case MarginsCheck():
            from nc_sim.training.margins import MarginsEvaluator  # the plant, only in workers

            return MarginsEvaluator(rule.axis, rule.template, rule.bandwidth_pct, m)
        case EventCheck():
            return _Event(rule, m)
        case NoEventCheck():
            return _NoEvent(rule, m)
        case InPositionCheck() | SpeedReachedCheck():
            assert slot is not None
            return _Standing(rule, m, slot)
        case FindingCheck():
            raise AssertionError("a finding is graded by the gateway, not the monitor")


__all__ = ["RULES", "Check", "CheckResult", "ExerciseMonitor", "Rule"]
