"""A channel's path in the kernel: the geometry ring, the look-ahead window and its plan.

`Path` owns the kernel rows of its path (nc_sim/kernel/layout.py PI_*, E_*, the plan) and the
roles of its axes' slots while it runs: queued elements are written to the ring, the plan is
made again whenever the window, the override or the feedhold changes, and the kernel moves
every path axis from it each cycle. Python mirrors the ring to know which block runs.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from nc_sim.channel.geometry import Element
from nc_sim.channel.planner import (
    AxisDynamics,
    Limits,
    element_limits,
    junction_speed,
    plan_window,
)
from nc_sim.kernel import layout as L
from nc_sim.kernel.arrays import Kernel
from nc_sim.profiles.plan import velocity_change

# the window must fit the plan table (at most 7 segments per element)
MAX_WINDOW = min(L.PATH_ELEMENTS - 1, L.PATH_SEGMENTS // 8)


class Path:
    """The path of one channel over its axes' kernel slots."""

    def __init__(self, k: Kernel, channel_slot: int, axis_slots: list[int]) -> None:
        self.k = k
        self.slot = channel_slot
        self.axis_slots = axis_slots
        self.p = k.claim_path(channel_slot, axis_slots)
        self.queue: deque[Element] = deque()  # the ring from its head, as Python sees it
        self.s_end = 0.0  # path length at the end of the last queued element
        # slots the path leaves alone: a spindle that is not in rotary (C axis) mode
        self.inactive: set[int] = set()

    def set_on_path(self, slot: int, on: bool) -> None:
        """The path drives `slot` (a spindle in rotary axis mode) or leaves it alone."""
        if on:
            self.inactive.discard(slot)
        else:
            self.inactive.add(slot)

    def _on_path(self) -> list[int]:
        return [s for s in self.axis_slots if s not in self.inactive]

    # --- the ring -------------------------------------------------------------------------
    @property
    def count(self) -> int:
        """Elements queued (the one running included)."""
        return len(self.queue)

    def position(self) -> np.ndarray:
        """Where the next queued element starts: the end of the last one, else the axes'
        command positions now."""
        if self.queue:
            return self.queue[-1].end.copy()
        return np.array([self.k.st[s, L.S_P_CMD] for s in self.axis_slots])

    def append(self, e: Element) -> None:
        """Queue an element behind the others (the plan is made by `replan`)."""
        if not self.queue:
            self.s_end = float(self.k.st[self.slot, L.S_P_CMD])
            for s in self._on_path():  # the path drives them from the next cycle on
                self.k.ist[s, L.I_ROLE] = L.ROLE_PATH_AXIS
                self.k.ist[s, L.I_PLAN_N] = 0
                self.k.ist[s, L.I_CURVE] = 0
                self.k.st[s, L.S_TARGET] = np.nan
        e.s0 = self.s_end
        self.s_end += e.length
        pi = self.k.pi[self.p]
        tail = (pi[L.PI_HEAD] + pi[L.PI_COUNT]) % L.PATH_ELEMENTS
        e.write(self.k.pel[self.p, tail])
        pi[L.PI_COUNT] += 1
        self.queue.append(e)

    def sync(self) -> list[Element]:
        """Drop the elements the kernel has passed (after EV_BLOCK); returns them."""
        passed = []
        while len(self.queue) > int(self.k.pi[self.p, L.PI_COUNT]):
            passed.append(self.queue.popleft())
        return passed

    @property
    def current(self) -> Element | None:
        """The element the path is in."""
        return self.queue[0] if self.queue else None

    @property
    def s(self) -> float:
        """Path length now."""
        return float(self.k.st[self.slot, L.S_P_CMD])

    @property
    def speed(self) -> float:
        """Path speed now (mm/s)."""
        return float(self.k.st[self.slot, L.S_V_CMD])

    def at_rest(self) -> bool:
        """The plan has ended with the path standing."""
        return int(self.k.ist[self.slot, L.I_PLAN_N]) == 0 and abs(self.speed) < 1e-9

    def done(self) -> bool:
        """At rest at the end of the last element: every queued block is run."""
        return self.at_rest() and (not self.queue or self.s >= self.s_end - 1e-9)

    def distance_to_go(self) -> float | None:
        """Path length left in the current element."""
        e = self.current
        return None if e is None else max(e.s0 + e.length - self.s, 0.0)

    # --- plans ----------------------------------------------------------------------------
    def replan(
        self,
        dynamics: Callable[[Element], list[AxisDynamics]],
        feed_scale: float,
        override: float,
        first_only: bool = False,
    ) -> None:
        """Plan the window from the state now: `dynamics(e)` the axes' limits for the element,
        path feed F (mm/min) × `feed_scale` (1/60 × override), rapid × `override`; with
        `first_only` (single block) to rest at the end of the element it is in."""
        if not self.queue:
            return
        elems = list(self.queue)[:1] if first_only else list(self.queue)
        limits: list[Limits] = []
        junctions: list[float] = []
        axes = [dynamics(e) for e in elems]
        for i, e in enumerate(elems):
            if e.rapid:
                ax = [replace(a, v_max=a.v_max * override) for a in axes[i]]
                limits.append(element_limits(e, ax, np.inf))
            else:
                limits.append(element_limits(e, axes[i], (e.feed_mm_min or 0.0) * feed_scale))
            if i + 1 < len(elems):
                j = (
                    0.0
                    if e.exact_stop
                    else junction_speed(e, elems[i + 1], axes[i], self.k.cycle_s)
                )
                junctions.append(j)
        if any(lim.v_cap <= 0.0 for lim in limits):  # override 0 %: brake and hold
            self.hold(limits[0].lim)
            return
        st = self.k.st
        c = self.slot
        plan = self.k.pplan[self.p]
        n = plan_window(
            plan,
            st[c, L.S_P_CMD],
            st[c, L.S_V_CMD],
            st[c, L.S_A_CMD],
            elems,
            limits,
            junctions,
            self.k.cycle_s,
        )
        self._load(n, elems[-1].s0 + elems[-1].length)

    def hold(self, lim: np.ndarray) -> None:
        """Brake on the path to rest with `lim` (feedhold, override 0 %) and wait there."""
        st = self.k.st
        n = velocity_change(
            self.k.pplan[self.p],
            0,
            st[self.slot, L.S_V_CMD],
            st[self.slot, L.S_A_CMD],
            0.0,
            lim,
            self.k.cycle_s,
        )
        self._load(n, np.nan)

    def _load(self, n: int, target: float) -> None:
        st, ist, c = self.k.st, self.k.ist, self.slot
        ist[c, L.I_PLAN_N] = n
        ist[c, L.I_PLAN_K] = 0
        st[c, L.S_SEG_TAU] = 0.0
        st[c, L.S_SEG_P0] = st[c, L.S_P_CMD]
        st[c, L.S_SEG_V0] = st[c, L.S_V_CMD]
        st[c, L.S_TARGET] = target
        if n == 0:
            st[c, L.S_V_CMD] = 0.0
            st[c, L.S_A_CMD] = 0.0

    def finish(self) -> None:
        """Give the axes back their own plans, at rest where the path left them."""
        st, ist = self.k.st, self.k.ist
        self.queue.clear()
        self.k.pi[self.p, L.PI_COUNT] = 0
        ist[self.slot, L.I_PLAN_N] = 0
        st[self.slot, L.S_V_CMD] = st[self.slot, L.S_A_CMD] = 0.0
        for s in self._on_path():
            ist[s, L.I_ROLE] = L.ROLE_AXIS
            ist[s, L.I_IN_POS] = 0
            ist[s, L.I_LINE] = 0
            jogging = ist[s, L.I_PLAN_N] > 0  # a G201 manual motion goes on, at its speed
            self.k.absorb_manual(s)
            if not jogging:
                st[s, L.S_V_CMD] = st[s, L.S_A_CMD] = 0.0
                st[s, L.S_TARGET] = st[s, L.S_P_CMD]

    def abandon(self) -> None:
        """Leave the path where it is (emergency stop, error): the axes keep their motion
        and get their own plans from the caller; the ring is emptied."""
        self.queue.clear()
        self.k.pi[self.p, L.PI_COUNT] = 0
        self.k.ist[self.slot, L.I_PLAN_N] = 0
        self.k.st[self.slot, L.S_V_CMD] = self.k.st[self.slot, L.S_A_CMD] = 0.0
        for s in self._on_path():
            self.k.ist[s, L.I_ROLE] = L.ROLE_AXIS
            self.k.ist[s, L.I_PLAN_N] = 0
            self.k.absorb_manual(s)
