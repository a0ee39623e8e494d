"""The kernel's arrays for every axis slot of every machine, advanced by one compiled step."""

from __future__ import annotations

import math

import numpy as np

from nc_sim.kernel import layout as L
from nc_sim.kernel.step import run_cycles
from nc_sim.plant import layout as PL
from nc_sim.profiles.plan import MAX_SEGMENTS, SEG_COLS


class Kernel:
    """Owns the state arrays; machines claim slots and share one `run` call."""

    st: np.ndarray  # float state, slots × S_COLS
    pr: np.ndarray  # float parameters, slots × P_COLS
    ist: np.ndarray  # integer state, slots × I_COLS
    seg: np.ndarray  # active plan, slots × MAX_SEGMENTS × SEG_COLS
    pi: np.ndarray  # paths × PI_COLS: channel slot, axis slots, geometry ring head and count
    pel: np.ndarray  # paths × PATH_ELEMENTS × E_COLS: the geometry ring
    pplan: np.ndarray  # paths × PATH_SEGMENTS × SEG_COLS: the 1-D plan over path length
    pl: np.ndarray  # the plant of each slot, slots × PL_COLS (nc_sim/plant/layout.py)
    ps: np.ndarray  # its state, slots × PS_COLS
    probe: np.ndarray  # the drive probe: slot, length, samples done, injection point
    pexc: np.ndarray  # its excitation, one value per drive step
    prec: np.ndarray  # its trace, drive steps × D_COLS

    def __init__(self, cycle_s: float = 0.001, capacity: int = 8) -> None:
        self.cycle_s = cycle_s
        self.n = 0
        self.paths = 0
        self._alloc(capacity)
        self.pi = np.zeros((0, L.PI_COLS), dtype=np.int64)
        self.pel = np.zeros((0, L.PATH_ELEMENTS, L.E_COLS))
        self.pplan = np.zeros((0, L.PATH_SEGMENTS, SEG_COLS))
        self.stop_probe()

    def _alloc(self, capacity: int) -> None:
        old = self.st if hasattr(self, "st") else None
        st = np.zeros((capacity, L.S_COLS))
        pr = np.zeros((capacity, L.P_COLS))
        ist = np.zeros((capacity, L.I_COLS), dtype=np.int64)
        seg = np.zeros((capacity, MAX_SEGMENTS, SEG_COLS))
        pl = np.zeros((capacity, PL.PL_COLS))
        ps = np.zeros((capacity, PL.PS_COLS))
        if old is not None:
            st[: self.n] = self.st[: self.n]
            pr[: self.n] = self.pr[: self.n]
            ist[: self.n] = self.ist[: self.n]
            seg[: self.n] = self.seg[: self.n]
            pl[: self.n] = self.pl[: self.n]
            ps[: self.n] = self.ps[: self.n]
        self.st, self.pr, self.ist, self.seg = st, pr, ist, seg
        self.pl, self.ps = pl, ps

    def claim(self, count: int) -> range:
        """Reserve `count` slots; returns their indices."""
        if self.n + count > self.st.shape[0]:
            self._alloc(max(2 * self.st.shape[0], self.n + count))
        first = self.n
        self.n += count
        for s in range(first, self.n):
            self.st[s, L.S_TARGET] = math.nan
            self.st[s, L.S_MAN_TARGET] = math.nan
            self.st[s, L.S_OVERRIDE] = 1.0
            # no loop-opening speeds and no curve cap until the machine sets them
            for col in (L.P_V_CTRL_LIMIT, L.P_V_SPEED_CTRL, L.P_A_CAP):
                self.pr[s, col] = math.inf
            self.pr[s, L.P_DRV_ALPHA] = 1.0  # an ideal drive
            self.pr[s, L.P_ENC_FACTOR] = 1.0  # an encoder as its parameters say
        return range(first, self.n)

    def claim_path(self, channel_slot: int, axis_slots: list[int]) -> int:
        """Register a channel's path over these axis slots; returns the path index."""
        if len(axis_slots) > L.MAX_PATH_AXES:
            raise ValueError(f"at most {L.MAX_PATH_AXES} path axes")
        p = self.paths
        self.paths += 1
        pi = np.zeros((self.paths, L.PI_COLS), dtype=np.int64)
        pi[:p] = self.pi
        self.pi = pi
        self.pel = np.concatenate([self.pel, np.zeros((1, L.PATH_ELEMENTS, L.E_COLS))])
        self.pplan = np.concatenate([self.pplan, np.zeros((1, L.PATH_SEGMENTS, SEG_COLS))])
        self.pi[p, L.PI_SLOT] = channel_slot
        self.pi[p, L.PI_NAX] = len(axis_slots)
        for i, s in enumerate(axis_slots):
            self.pi[p, L.PI_AX0 + i] = s
        self.ist[channel_slot, L.I_ROLE] = L.ROLE_CHANNEL
        return p

    def load_plan(self, slot: int, seg: np.ndarray, n: int, target: float) -> None:
        """Start a plan on a slot from its current commanded position and velocity."""
        self.seg[slot, :n] = seg[:n]
        self.ist[slot, L.I_PLAN_N] = n
        self.ist[slot, L.I_PLAN_K] = 0
        self.ist[slot, L.I_CURVE] = 0
        self.st[slot, L.S_SEG_TAU] = 0.0
        self.st[slot, L.S_SEG_P0] = self.st[slot, L.S_P_CMD]
        self.st[slot, L.S_SEG_V0] = self.st[slot, L.S_V_CMD]
        self.st[slot, L.S_TARGET] = target
        # a new target is not yet confirmed: the in-position edge (EV_IN_POS) comes again even
        # when the axis already stands there (M19 twice to the same angle)
        self.ist[slot, L.I_IN_POS] = 0
        if n == 0 and not math.isnan(target):
            self.st[slot, L.S_P_CMD] = target
            self.st[slot, L.S_V_CMD] = 0.0

    def load_manual_plan(self, slot: int, seg: np.ndarray, n: int, target: float) -> None:
        """Start a G201 manual motion of a path axis: a plan of its offset (S_MAN_*) from the
        offset's position and velocity now; `target` the offset's end, NaN for a velocity
        plan [002 §2.6.2]."""
        st = self.st
        self.seg[slot, :n] = seg[:n]
        self.ist[slot, L.I_PLAN_N] = n
        self.ist[slot, L.I_PLAN_K] = 0
        st[slot, L.S_SEG_TAU] = 0.0
        st[slot, L.S_SEG_P0] = st[slot, L.S_MAN_P]
        st[slot, L.S_SEG_V0] = st[slot, L.S_MAN_V]
        st[slot, L.S_MAN_TARGET] = target
        if n == 0 and not math.isnan(target):
            st[slot, L.S_MAN_P] = target
            st[slot, L.S_MAN_V] = 0.0

    def absorb_manual(self, slot: int) -> None:
        """The path lets go of a slot: its manual offset becomes part of its position, and a
        manual motion still running goes on as the slot's own plan (the path is at rest, so
        the command position is the path's end plus the offset)."""
        st = self.st
        base = st[slot, L.S_P_CMD] - st[slot, L.S_MAN_P]
        if self.ist[slot, L.I_PLAN_N] > 0:
            st[slot, L.S_SEG_P0] += base
            st[slot, L.S_TARGET] = st[slot, L.S_MAN_TARGET] + base
        for col in (L.S_MAN_P, L.S_MAN_V, L.S_MAN_A):
            st[slot, col] = 0.0
        st[slot, L.S_MAN_TARGET] = math.nan

    def start_probe(self, slot: int, excitation: np.ndarray, point: int) -> None:
        """Probe a slot's drive: add `excitation` (one value per drive step, Nm or rad/s) at
        `point` (PL.INJECT_*) and record the drive trace, one row per drive step, until the
        excitation ends. One probe per kernel: starting one ends the one before."""
        self.probe = np.array([slot, len(excitation), 0, point, 0, 0], dtype=np.int64)
        self.pexc = np.ascontiguousarray(excitation, dtype=np.float64)
        self.prec = np.zeros((len(excitation), PL.D_COLS))

    def start_probe_ring(self, slot: int, steps: int) -> None:
        """Record a slot's drive trace endlessly into a ring of `steps` drive steps, without
        excitation (the scope's drive-rate capture): `probe_ring` reads it."""
        self.start_probe(slot, np.zeros(steps), PL.INJECT_TORQUE)
        self.probe[PL.PR_WRAP] = 1

    def probe_ring(self, first: int, count: int) -> np.ndarray | None:
        """Samples first … first + count - 1 (counted from the probe's start) of a ring
        probe, oldest first; None when the ring no longer (or not yet) holds them all."""
        total, size = int(self.probe[PL.PR_COUNT]), len(self.prec)
        if first < 0 or first + count > total or total - first > size:
            return None
        return np.take(self.prec, np.arange(first, first + count) % size, axis=0)

    def probe_trace(self) -> np.ndarray:
        """The drive trace recorded so far (drive steps × PL.D_COLS)."""
        return self.prec[: int(self.probe[PL.PR_POS])]

    def stop_probe(self) -> None:
        """No probe: no excitation, no drive trace."""
        self.probe = np.array([-1, 0, 0, 0, 0, 0], dtype=np.int64)
        self.pexc = np.zeros(0)
        self.prec = np.zeros((0, PL.D_COLS))

    def load_curve(self, slot: int, v_target: float) -> None:
        """Start a curve-controlled speed change (pr P_CURVE_*) towards v_target."""
        self.ist[slot, L.I_PLAN_N] = 0
        self.ist[slot, L.I_CURVE] = 1
        self.st[slot, L.S_V_TARGET] = v_target
        self.st[slot, L.S_TARGET] = math.nan

    def run(self, n: int, rec: np.ndarray | None = None) -> int:
        """Advance all slots by up to n cycles (fewer when an event is raised)."""
        if rec is None:
            rec = _NO_REC
        k = self.n
        return int(
            run_cycles(
                self.st[:k],
                self.pr[:k],
                self.ist[:k],
                self.seg[:k],
                self.pi,
                self.pel,
                self.pplan,
                self.pl[:k],
                self.ps[:k],
                self.probe,
                self.pexc,
                self.prec,
                rec,
                n,
                self.cycle_s,
            )
        )


_NO_REC = np.zeros((0, 0, L.R_COLS))

__all__ = ["Kernel"]
