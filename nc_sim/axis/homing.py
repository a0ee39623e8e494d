"""CNC-controlled homing G74 of an axis [002 §2.7]: to the reference cam at vb_refmax, off it
at vb_reflow, the zero pulse at the cam's edge sets kenngr.ref_pos, then to ref_pos.
Without reversal (P-AXIS-00157 ref_ohne_rev) the zero pulse is taken where the axis runs onto
the cam, in the search direction; without a cam (P-AXIS-00156 ref_ohne_nocken) the axis
searches the zero pulse alone, at vb_reflow in the homing direction.

A `Sequence` (nc_sim/axis/state.py): the cam events advance its phases, the end of the last
plan ends it. Spindles home by their own task (nc_sim/spindle/task.py).
"""

from __future__ import annotations

from enum import IntEnum

from nc_sim.axis.dynamics import Motion
from nc_sim.axis.motion import AxisMotion
from nc_sim.axis.plant import encoder_reading
from nc_sim.axis.state import Axis
from nc_sim.axis.watchdog import search_s
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.snapshot import AxisState


class HomingPhase(IntEnum):
    TO_CAM = 1
    OFF_CAM = 2
    TO_REF = 3
    TO_MARK = 4  # without a cam: the zero pulse alone


PHASE_NAMES = {
    HomingPhase.TO_CAM: "search for the cam",
    HomingPhase.OFF_CAM: "leaving the cam",
    HomingPhase.TO_REF: "to the reference position",
    HomingPhase.TO_MARK: "search for the zero pulse",
}


class Homing:
    """The homing sequence of one axis."""

    def __init__(self, ax: Axis, motion: AxisMotion, phase: HomingPhase) -> None:
        self.ax = ax
        self.motion = motion
        self.phase = phase
        self.speed = 0.0  # the phase's speed, unit/s (vb_refmax or vb_reflow)
        self.start_pos = self._pos()  # where G74 began
        self.shift = 0.0  # by which the reference moved every position

    def _pos(self) -> float:
        return float(self.motion.k.st[self.ax.slot, L.S_P_ACT])

    def progress(self) -> tuple[str, float, float | None, float]:
        """The phase's name, the distance from where G74 began (signed, unit: the reference
        latched on the way does not count), the distance left to ref_pos in the last phase
        (None while searching: the NC does not know where the cam is) and the phase's speed
        (unit/s)."""
        pos = self._pos()
        to_go = (
            self.ax.cfg.eng("kenngr.ref_pos") - pos if self.phase is HomingPhase.TO_REF else None
        )
        return PHASE_NAMES[self.phase], pos - self.shift - self.start_pos, to_go, self.speed

    @classmethod
    def start(cls, ax: Axis, motion: AxisMotion, block_id: int | None) -> Event | None:
        """G74 of `ax`: from the cam's side it stands on; the job error when it may not move."""
        err = motion.check_motion(ax)
        if err:
            return err
        if ax.state is not AxisState.STANDSTILL:  # a jog or a move runs: it ends first
            return motion.fail(ax, Code.AXIS_BUSY, f"{ax.name} is {ax.state.name.lower()}")
        ax.motion, ax.block_id, ax.slope = Motion.HOMING, block_id, 1
        motion.forget_reference(ax)
        motion.set_state(ax, AxisState.HOMING)
        on_cam = bool(motion.k.ist[ax.slot, L.I_CAM]) == (cls._direction(ax) > 0)
        phase = HomingPhase.OFF_CAM if on_cam else HomingPhase.TO_CAM
        if ax.cfg.flag("kenngr.ref_ohne_nocken"):
            phase = HomingPhase.TO_MARK
        seq = cls(ax, motion, phase)
        ax.sequence = seq
        seq._search()
        return None

    @staticmethod
    def _direction(ax: Axis) -> float:
        return 1.0 if ax.cfg.flag("kenngr.ref_richt") else -1.0

    def _search(self) -> None:
        """To the cam at vb_refmax, or off it at vb_reflow; also resumes after a feedhold."""
        ax, d = self.ax, self._direction(self.ax)
        if self.phase is HomingPhase.TO_CAM:
            v, what = d * ax.cfg.eng("getriebe.vb_refmax", ax.gear), "search for the cam"
        elif self.phase is HomingPhase.TO_MARK:
            v, what = d * ax.cfg.eng("getriebe.vb_reflow", ax.gear), "search for the zero pulse"
        else:
            v, what = -d * ax.cfg.eng("getriebe.vb_reflow", ax.gear), "leaving the cam"
        self.speed = abs(v)
        self.motion.plan_velocity(ax, v, self.motion.limits(ax, Motion.HOMING))
        # the cam lies within the travel: a search over the whole of it finds it
        pr = self.motion.k.pr
        travel = float(pr[ax.slot, L.P_SWE_POS] - pr[ax.slot, L.P_SWE_NEG])
        self.motion.watch(ax, search_s(travel, abs(v)), f"homing: {what}", extend=True)

    def _edge(self) -> None:
        """Cam edge with zero pulse: the position here becomes ref_pos, then to it."""
        ax = self.ax
        k = self.motion.k
        # the zero pulse latches the position at the edge itself, not one cycle later
        latched = encoder_reading(k, ax.slot, float(k.pr[ax.slot, L.P_CAM_POS]))
        before = self._pos()
        self.motion.set_reference(ax, latched)
        self.shift += self._pos() - before
        self.phase = HomingPhase.TO_REF
        ax.target = ax.cfg.eng("kenngr.ref_pos")
        ax.feed = self.speed = ax.cfg.eng("getriebe.vb_reflow", ax.gear)
        self.motion.plan_move(ax, self.motion.limits(ax, Motion.HOMING), ax.feed)

    def on_event(self, ev: int) -> bool:
        """Cam edges advance the search; the end of the plan to ref_pos ends homing."""
        ax = self.ax
        if ev & L.EV_CAM and ax.state is AxisState.HOMING:
            cam = bool(self.motion.k.ist[ax.slot, L.I_CAM])
            d = self._direction(ax)
            if self.phase is HomingPhase.TO_MARK:  # the zero pulse, from either side
                self._edge()
            elif self.phase is HomingPhase.TO_CAM and cam == (d > 0):
                if ax.cfg.flag("kenngr.ref_ohne_rev"):  # on, not back off the cam
                    self._edge()
                else:
                    self.phase = HomingPhase.OFF_CAM
                    self._search()
            elif self.phase is HomingPhase.OFF_CAM and cam != (d > 0):
                self._edge()
        if not ev & L.EV_PLAN_DONE or ax.state is not AxisState.HOMING:
            return False  # (an error reaction, or a move that took over: a plain motion's end)
        if ax.hold or self.phase is not HomingPhase.TO_REF:
            return True  # a feedhold's brake, a search's speed reached
        ax.sequence = None
        self.motion.log(Code.EV_HOMED, ax.name, f"{ax.name} homed")
        self.motion.motion_done(ax)
        return True

    def replan(self) -> bool:
        """A search has no target: it runs again at its speed (override, feedhold released)."""
        if self.phase is HomingPhase.TO_REF:
            return False
        self._search()
        return True
