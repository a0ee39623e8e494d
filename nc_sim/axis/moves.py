"""Single-axis commands: G00/G01 moves, jog (continuous and incremental), homing, stop,
feedhold, override, reset of an axis [002, 003 "jogging a spindle", 004].

A spindle moved or jogged like a rotary axis goes through here too (feed override, feedhold,
G200 dynamics); in spindle mode its override, stop and re-plan are the spindle's, reached
through the narrow `SpindleMode`.
"""

from __future__ import annotations

import math
from typing import Protocol

from nc_sim.axis import parallel_jog
from nc_sim.axis.dynamics import Motion, Sourced, feedhold_limits, param, velocity_in_force
from nc_sim.axis.homing import Homing
from nc_sim.axis.motion import AxisMotion
from nc_sim.axis.state import Axis
from nc_sim.config import MachineConfig
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.snapshot import AxisState
from nc_sim.units import AxisKind, Quantity, feed_per_min, per_second, to_eng

_FAR = 1e9  # jog target of a spindle (a modulo axis: no position range)
# positions the NC represents: SGN32 in 0.1 µm | 0.0001° (the range of P-AXIS-00177/00178);
# an unhomed axis may go anywhere within it, a target beyond it is meaningless (90003)
POSITION_RANGE = to_eng(Quantity.POSITION, 2**31 - 1)


def reduced_speed(ax: Axis, motion: Motion, span: tuple[float, float]) -> Sourced | None:
    """The axis speed the PLC's reduced-speed requests allow (unit/s, not scaled by the
    override), or None while they ask for none [002 §2.8]:

    - `reduced_speed` (a door open): P-AXIS-00155 for rapid traverse (P-AXIS-00214 when it
      is unset), P-AXIS-00214 for every other motion;
    - `reduced_speed_zone` / `reduced_speed_2_zone`: P-AXIS-00030 (zone 2: P-AXIS-00503, or
      P-AXIS-00030 when it is 0) for a motion whose positions `span` (lowest, highest)
      reach into safety zone 1 (P-AXIS-00093 … P-AXIS-00085) or 2
      (P-AXIS-00105 … P-AXIS-00097). The whole motion keeps the zone's speed, so the axis is
      never faster inside the zone (the NC slows only inside it: we are on the safe side).

    It limits the axis whichever motion it takes part in (jog, single-axis move, the path)."""
    limits: list[Sourced] = []
    if ax.units["reduced_speed"]:
        name = "getriebe.rapid_speed_red" if motion is Motion.RAPID else "getriebe.vb_max_red"
        red = param(ax.cfg, name, ax.gear, "reduced_speed")
        if not red.value:
            red = param(ax.cfg, "getriebe.vb_max_red", ax.gear, "reduced_speed")
        limits.append(red)
    lo, hi = span
    for unit, zone, speed in (
        ("reduced_speed_zone", "kenngr.red_speed_zone", "getriebe.vb_max_red_zone"),
        ("reduced_speed_2_zone", "kenngr.red_speed_zone_2", "getriebe.vb_max_red_zone_2"),
    ):
        neg, pos = ax.cfg.eng(zone + "_neg"), ax.cfg.eng(zone + "_pos")
        if ax.units[unit] and neg < pos and lo <= pos and hi >= neg:
            red = param(ax.cfg, speed, ax.gear, "reduced_speed")
            if not red.value:
                red = param(ax.cfg, "getriebe.vb_max_red_zone", ax.gear, "reduced_speed")
            limits.append(red)
    limits = [r for r in limits if r.value > 0]
    return min(limits, key=lambda r: r.value) if limits else None


class SpindleMode(Protocol):
    """What moves need from the spindle part for a spindle in spindle mode."""

    def override(self, ax: Axis) -> float: ...
    def replan(self, ax: Axis) -> None: ...
    def stop(self, ax: Axis) -> None: ...
    def home(self, ax: Axis, block_id: int | None = None) -> Event | None: ...
    def as_rotary_axis(self, ax: Axis) -> Event | None: ...
    def switch_back(self, ax: Axis) -> None: ...
    def target(self, ax: Axis, pos_deg: float, direction: int | None) -> float: ...


class Moves:
    """Moves, jog and homing of the axes of one channel."""

    def __init__(self, motion: AxisMotion, spindle: SpindleMode, cfg: MachineConfig) -> None:
        self.motion = motion
        self.spindle = spindle
        self.cfg = cfg

    # --- dynamics in force --------------------------------------------------------------
    def as_axis(self, ax: Axis) -> bool:
        """Moves like an axis: a linear axis, or a spindle jogged or moved as a rotary axis
        [003 "jogging a spindle"]; then feed override, feedhold and G200 dynamics apply."""
        return ax.kind is not AxisKind.SPINDLE or ax.state in (AxisState.MOVING, AxisState.JOG)

    def override(self, ax: Axis) -> float:
        """Override in force as a fraction: the spindle override in spindle mode, the
        channel (feed) override for axes and for a spindle moving as a rotary axis."""
        if not self.as_axis(ax):
            return self.spindle.override(ax)
        cap = self.cfg.channel_eng("max_vb_override")
        return min(self.motion.ctx.units["override"] * 1e-3, cap)

    def speed_in_force(self, ax: Axis, motion: Motion) -> tuple[Sourced, float]:
        """The top speed (unit/s) of a kind of motion now with its source, and the override
        fraction that scales it (1.0 when the reduced speed the PLC asks for caps it)."""
        base = velocity_in_force(ax.cfg, ax.gear, motion, ax.feed)
        ovr = self.override(ax)
        v = Sourced(base.value * ovr, base.source, base.param_id, base.kind)
        p = float(self.motion.k.st[ax.slot, L.S_P_CMD])
        to = ax.target if math.isfinite(ax.target) else p  # no target (a search): here
        red = reduced_speed(ax, motion, (min(p, to), max(p, to)))
        if red is not None and red.value < v.value:
            return red, 1.0
        return v, ovr

    def _vmax(self, ax: Axis, motion: Motion) -> float:
        return self.speed_in_force(ax, motion)[0].value

    def replan(self, ax: Axis) -> None:
        """Re-plan the active motion from the current state (override, feedhold release);
        an axis on the channel's path moves with the path's plan."""
        if self.motion.k.ist[ax.slot, L.I_ROLE] == L.ROLE_PATH_AXIS:
            return
        if not self.as_axis(ax):
            self.spindle.replan(ax)
            return
        if ax.motion is None or ax.state in (AxisState.STOPPING, AxisState.ERROR):
            return
        if ax.hold or self.motion.ctx.units["feedhold"]:
            return
        if ax.sequence is not None and ax.sequence.replan():
            return
        self.motion.plan_move(ax, self.motion.limits(ax, ax.motion), self._vmax(ax, ax.motion))

    def feedhold(self, on: bool, axes: list[Axis]) -> None:
        """Feedhold set: moving axes brake to a hold (P-CHAN-00097 chooses the braking);
        released: they resume."""
        if not on:
            for ax in axes:
                if ax.hold:
                    ax.hold = False
                    self.replan(ax)
            return
        use_set = bool(self.cfg.channel_raw("use_drive_curr_limit"))
        for ax in axes:
            if ax.jog_on_path:  # a G201 jog stops with the path (a new key press resumes it)
                parallel_jog.stop(self.motion, ax)
            if (
                self.as_axis(ax)
                and self.motion.k.ist[ax.slot, L.I_ROLE] != L.ROLE_PATH_AXIS  # the path holds
                and ax.state in (AxisState.MOVING, AxisState.JOG, AxisState.HOMING)
                and ax.motion is not None
            ):
                ax.hold = True
                lim = feedhold_limits(ax.cfg, ax.gear, ax.motion, ax.slope, use_set)
                self.motion.plan_move(ax, lim, 0.0)

    # --- moves --------------------------------------------------------------------------
    def position_limits(self, ax: Axis) -> tuple[float, float] | None:
        """Where a programmed motion of `ax` may go: its software limits once homed, else
        the positions the NC represents; None for a spindle (modulo, no range)."""
        if ax.kind is AxisKind.SPINDLE:
            return None
        pr = self.motion.k.pr
        if not ax.homed:  # no software limits yet, but no target beyond what the NC represents
            return -POSITION_RANGE, POSITION_RANGE
        return float(pr[ax.slot, L.P_SWE_NEG]), float(pr[ax.slot, L.P_SWE_POS])

    def _within_limits(self, ax: Axis, target: float) -> Event | None:
        limits = self.position_limits(ax)
        if limits is None:
            return None
        lo, hi = limits
        if not lo - 1e-9 <= target <= hi + 1e-9:
            u = ax.pos_unit
            return self.motion.fail(
                ax,
                Code.SOFTWARE_LIMIT,
                f"{ax.name} target {target:.4f} {u} outside {lo:.4f} … {hi:.4f} {u}",
            )
        return None

    def start_move(
        self,
        ax: Axis,
        target: float,
        motion: Motion,
        feed: float | None,
        block_id: int | None = None,
        state: AxisState = AxisState.MOVING,
    ) -> Event | None:
        """Start a single-axis motion to `target` (feed in unit/s); the job error if refused."""
        err = self.motion.check_motion(ax) or self._within_limits(ax, target)
        if err is None and ax.kind is AxisKind.SPINDLE:
            err = self.spindle.as_rotary_axis(ax)
        elif err is None and ax.state not in (AxisState.STANDSTILL, state):
            # a new target for a move or a jog, but never across homing or another motion
            err = self.motion.fail(ax, Code.AXIS_BUSY, f"{ax.name} is {ax.state.name.lower()}")
        if err:
            return err
        ax.target, ax.motion, ax.feed, ax.block_id = target, motion, feed, block_id
        ax.slope = self.motion.ctx.slope if motion is not Motion.MANUAL else 1
        if motion is Motion.FEED and not feed:
            return self.motion.fail(ax, Code.FEED_MISSING)
        self.motion.set_state(ax, state)
        self.replan(ax)
        return None

    def move(
        self, ax: Axis, target: float, rapid: bool = True, feed_mm_min: float | None = None
    ) -> Event | None:
        """Single-axis G00/G01 move to an absolute position (mm | °); a spindle moves as a
        modulo rotary axis to the angle, the shortest way."""
        err = self.homing_required(ax)
        if err:
            return err
        feed = per_second(feed_mm_min) if feed_mm_min else None
        if ax.kind is AxisKind.SPINDLE:
            target = self.spindle.target(ax, target % 360.0, None)
        return self.start_move(ax, target, Motion.RAPID if rapid else Motion.FEED, feed)

    def homing_required(self, ax: Axis) -> Event | None:
        """P-AXIS-00277: a programmed motion (G00/G01, `move`) of an unhomed axis is refused
        with 90013; jogging and homing stay possible."""
        if ax.homed or not ax.cfg.flag("kenngr.prog_move_requires_homing"):
            return None
        return self.motion.fail(
            ax, Code.NOT_HOMED, f"{ax.name} is not homed (P-AXIS-00277): G74 first"
        )

    def home(self, ax: Axis, block_id: int | None = None) -> Event | None:
        """G74: CNC-controlled homing of an axis, the zero mark of a spindle."""
        if ax.kind is AxisKind.SPINDLE:
            return self.spindle.home(ax, block_id)
        return Homing.start(ax, self.motion, block_id)

    def stop(self, ax: Axis, limits_motion: Motion) -> None:
        """Brake to standstill with the limits of a kind of motion (a spindle: M5)."""
        if not self.as_axis(ax):
            self.spindle.stop(ax)
            return
        self.motion.stop(ax, self.motion.limits(ax, limits_motion))

    # --- jog ----------------------------------------------------------------------------
    def jog_start(self, ax: Axis, direction: int, feed_mm_min: float | None = None) -> Event | None:
        """Continuous jog (G200 dynamics) towards the software limit until `jog_stop`."""
        k = self.motion.k
        d = 1.0 if direction > 0 else -1.0
        if ax.kind is AxisKind.SPINDLE:
            target = k.st[ax.slot, L.S_P_CMD] + d * _FAR
        elif ax.homed:
            target = k.pr[ax.slot, L.P_SWE_POS if d > 0 else L.P_SWE_NEG]
        else:  # towards the end of the position range: far, but a move that ends
            target = d * POSITION_RANGE
        feed = per_second(feed_mm_min) if feed_mm_min else None
        err = self._jog_feed_refused(ax, feed)
        if err:
            return err
        if parallel_jog.on_path(self.motion, ax):
            return self._jog_on_path(ax, None, d, feed)
        return self.start_move(ax, target, Motion.MANUAL, feed, state=AxisState.JOG)

    def _jog_on_path(
        self, ax: Axis, distance: float | None, direction: float, feed: float | None
    ) -> Event | None:
        """A jog of an axis the program's path moves: with G201 on top of the path."""
        err = parallel_jog.refused(self.motion, ax) or self.motion.drive_refusal(ax)
        if err is None:
            parallel_jog.jog(self.motion, ax, distance, int(direction), feed, self.override(ax))
        return err

    def _jog_feed_refused(self, ax: Axis, feed: float | None) -> Event | None:
        """A jog feed above the axis' G200 maximum (P-AXIS-00213) is refused naming that
        limit [002 §2.6.1], not silently cut to it."""
        v_max = ax.cfg.eng("handbetrieb.hb.vb_max")
        if feed is None or feed <= v_max * (1 + 1e-12):
            return None
        f, unit = feed_per_min(feed, ax.kind)
        lim, _ = feed_per_min(v_max, ax.kind)
        return self.motion.fail(
            ax,
            Code.JOG_FEED_TOO_HIGH,
            f"{ax.name} jog feed {round(f, 4):.10g} {unit} is above the manual-mode maximum "
            f"{round(lim, 4):.10g} {unit} (handbetrieb.hb.vb_max, P-AXIS-00213)",
        )

    def jog_stop(self, ax: Axis) -> None:
        """Release of the jog key: brake with the manual-mode deceleration."""
        if ax.jog_on_path:
            parallel_jog.stop(self.motion, ax)
        elif ax.state is AxisState.JOG:
            self.stop(ax, Motion.MANUAL)

    def jog_step(self, ax: Axis, distance: float, feed_mm_min: float | None = None) -> Event | None:
        """Incremental jog by `distance` (mm | °) with G200 dynamics (G201: on top of the path)."""
        feed = per_second(feed_mm_min) if feed_mm_min else None
        if parallel_jog.on_path(self.motion, ax):
            direction = math.copysign(1.0, distance)
            return self._jog_feed_refused(ax, feed) or self._jog_on_path(
                ax, distance, direction, feed
            )
        if ax.state is not AxisState.STANDSTILL:
            return self.motion.fail(ax, Code.AXIS_BUSY)
        target = self.motion.k.st[ax.slot, L.S_P_CMD] + distance
        return self._jog_feed_refused(ax, feed) or self.start_move(ax, target, Motion.MANUAL, feed)

    # --- reset --------------------------------------------------------------------------
    def reset(self, ax: Axis) -> None:
        """CNC reset of one axis: job error cleared, sequence ended, motion stopped (a
        spindle keeps rotating with P-AXIS-00455), back to position control [001 §2.3]."""
        moving = ax.state not in (AxisState.STANDSTILL, AxisState.ERROR)
        spindle = ax.kind is AxisKind.SPINDLE
        keep = spindle and ax.cfg.flag("kenngr.spdl_no_stop_at_reset")
        self.motion.set_job_error(ax, None)
        ax.hold, ax.block_id, ax.sequence = False, None, None
        self.motion.arm_zero_mark(ax, False)
        if spindle:
            self.spindle.switch_back(ax)
        rotating = ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP)
        if moving and not (keep and rotating):
            self.stop(ax, ax.motion or Motion.FEED)
        elif ax.state is AxisState.ERROR:
            self.motion.set_state(ax, AxisState.STANDSTILL)
