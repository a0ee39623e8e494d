"""Spindle behaviours [000, 001, DOMAIN §4]: M3/M4/M5, M19, G74, gear change M40-M45.

Endless rotation runs on the planner (a_beschl/a_brems) or on the speed-dependent curve.
M19, G74, the gear change and M5 with homing are sequences (`SpindleTask`, task.py); the
spindle's part of a block is program.py. Every kernel write goes through `AxisMotion`.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from nc_sim.accel_curve import CurveParams
from nc_sim.axis.dynamics import Dynamics, Motion, Sourced, lowest, motion_dynamics, param
from nc_sim.axis.motion import AxisMotion
from nc_sim.axis.params import changeover_speeds, push_params, speed_controlled
from nc_sim.axis.state import Axis
from nc_sim.axis.watchdog import curve_s
from nc_sim.config import MachineConfig
from nc_sim.errors import Code, NcUsageError
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.plc import Handshake
from nc_sim.profiles.plan import (
    new_plan,
    plan_distance,
    velocity_change,
)
from nc_sim.snapshot import AxisState
from nc_sim.spindle.gear_change import GearStages
from nc_sim.spindle.gears import m_of
from nc_sim.spindle.task import V_EPS, SpindleTask, sign
from nc_sim.units import RPM_TO_DEG_S

ACHSMODE_KEINE_AUTO_RPF = 0x100  # P-AXIS-00015: no automatic homing before M19
DIGITAL_DRIVES = (2, 8)  # SERCOS, CANopen: drive-controlled homing only [000 §2.3]


def _check_rpm(rpm: float | None) -> None:
    """One meaning for a negative S everywhere: refused. M3/M4 (or M19's M3/M4) give the
    direction; only G63 tapping reverses with a negative S [000 §2.8.6], which we lack."""
    if rpm is not None and rpm < 0:
        raise NcUsageError(f"S{rpm:g}: the speed must not be negative (M3/M4 give the direction)")


def _why_not_positioned(ax: Axis) -> str:
    if ax.cfg.flag("sim.sensorless"):
        return f"{ax.name} has no encoder"
    return f"{ax.name} is speed-controlled (OPEN_POSITION_LOOP_MODE, P-AXIS-00320)"


class SpindleControl:
    """The spindle part of a machine's NC: commands, sequences and their kernel events."""

    def __init__(self, motion: AxisMotion, cfg: MachineConfig, handshake: Handshake) -> None:
        self.motion = motion
        self.cfg = cfg
        self.handshake = handshake
        self.gears = GearStages(self)
        motion.mode_events = self.on_loop_events

    # --- configuration ------------------------------------------------------------------
    def preferred(self, ax: Axis) -> int | None:
        """+1/-1 when only one direction is allowed (P-AXIS-00224, P-AXIS-00031)."""
        if not ax.cfg.flag("kenngr.vorz_richtung"):
            return None
        return 1 if ax.cfg.flag("kenngr.beweg_richt") else -1

    def auto_homing(self, ax: Axis) -> bool:
        """Analogue drives home automatically before M19; digital ones only by G74."""
        mode = int(ax.cfg.raw("kenngr.achs_mode"))
        drive = int(ax.cfg.raw("kenngr.antr_typ"))
        return not mode & ACHSMODE_KEINE_AUTO_RPF and drive not in DIGITAL_DRIVES

    def v_max(self, ax: Axis) -> float:
        return self.vb_max_in_force(ax).value

    def vb_max_in_force(self, ax: Axis) -> Sourced:
        """The spindle's top speed (°/s): the gear record's vb_max, or a lower tool limit."""
        v = param(ax.cfg, "getriebe.dynamik.vb_max", ax.gear)
        if ax.tool.vb_max is not None:
            v = lowest(v, Sourced(ax.tool.vb_max, "wz[i].vb_max", "P-TOOL-00014", "tool"))
        return v

    def override(self, ax: Axis) -> float:
        if ax.override_suppressed or not ax.units["override_valid"]:
            ovr = 1.0
        else:
            ovr = ax.units["override"] * 1e-3
        return min(ovr, ax.cfg.eng("kenngr.max_vb_override"))

    def commanded(self, ax: Axis) -> float:
        """Signed command speed (°/s): programmed × override within the tool and gear limits."""
        v = min(abs(ax.speed_prog) * self.override(ax), self.v_max(ax))
        if v > 0:
            v = max(v, ax.tool.vb_min)
        return math.copysign(v, ax.speed_prog)

    def dynamics(self, ax: Axis) -> Dynamics:
        """The spindle's accelerations (G01 set of its gear record) within the tool's a_max."""
        reduced = bool(self.motion.ctx.units["reduced_acceleration"])
        d = motion_dynamics(ax.cfg, ax.gear, Motion.FEED, ax.slope, reduced)
        if ax.tool.a_max is None:
            return d
        tool = Sourced(ax.tool.a_max, "wz[i].a_max", "P-TOOL-00015", "tool")

        def cap(a: Sourced) -> Sourced:
            return lowest(a, tool) if a.value > 0 else a

        a2, d2 = d.a_acc2, d.a_dec2
        return replace(
            d,
            a_acc=cap(d.a_acc),
            a_dec=cap(d.a_dec),
            a_acc2=cap(a2) if a2 is not None else None,
            a_dec2=cap(d2) if d2 is not None else None,
        )

    def limits(self, ax: Axis) -> np.ndarray:
        return self.dynamics(ax).limits()

    # --- primitives ---------------------------------------------------------------------
    def velocity(self, ax: Axis, v: float) -> None:
        """Speed change: along the acceleration curve when one is set, else planned."""
        if int(ax.cfg.raw("getriebe.beschl_kennlinie.typ", ax.gear)) == 0:
            self.motion.plan_velocity(ax, v, self.limits(ax))
            return
        ramp = curve_s(self.curve(ax), float(self.motion.k.st[ax.slot, L.S_V_CMD]), v)
        if ramp.dead_speed is not None:
            self._curve_refused(ax, ramp.dead_speed)
            return
        self.motion.watch(ax, ramp.seconds, "speed change along the acceleration curve")
        self.motion.follow_curve(ax, v)

    def curve(self, ax: Axis) -> CurveParams:
        """The acceleration curve in force (the kernel's copy of the gear record)."""
        pr = self.motion.k.pr[ax.slot]
        return CurveParams(
            int(pr[L.P_CURVE_TYPE]),
            *(
                float(pr[c])
                for c in (
                    L.P_N_LIMIT,
                    L.P_A_KONST,
                    L.P_B1,
                    L.P_B2,
                    L.P_B3,
                    L.P_A_MIN,
                    L.P_CURVE_A_MAX,
                    L.P_N1,
                    L.P_N2,
                    L.P_A_CAP,
                )
            ),
        )

    def _curve_refused(self, ax: Axis, n_deg_s: float) -> None:
        """A curve that cannot reach the speed: job error, brake on the planner, error state."""
        self.motion.fail(
            ax,
            Code.CURVE_NO_ACCELERATION,
            f"{ax.name} M{m_of(ax.gear)}: a(n) at {n_deg_s / RPM_TO_DEG_S:g} rpm is "
            f"{self.curve(ax).accel(n_deg_s):g} °/s² (getriebe[{ax.gear - 1}].beschl_kennlinie)",
            gear=ax.gear,
        )
        self.cancel_task(ax)
        self.motion.set_state(ax, AxisState.ERROR)
        self.motion.monitor_speed(ax, False)
        self.motion.speed_goal(ax, 0.0)
        self.motion.plan_velocity(ax, 0.0, self.limits(ax))

    def set_state(self, ax: Axis, state: AxisState, monitoring: bool = False) -> None:
        """The spindle's state with speed monitoring on (endless rotation) or off."""
        self.motion.set_state(ax, state)
        self.motion.monitor_speed(ax, monitoring)
        if not monitoring:
            self.motion.speed_goal(ax, 0.0)

    def adopt_tool(self, ax: Axis) -> None:
        """Tool dynamics take effect on the transition from standstill [000 §2.8.5]."""
        if ax.tool_pending is None or ax.state is not AxisState.STANDSTILL:
            return
        ax.tool, ax.tool_pending = ax.tool_pending, None
        push_params(self.motion.k, ax)
        self.motion.log(Code.EV_TOOL_DYNAMICS, ax.name, f"{ax.name} tool dynamics {ax.tool}")

    def _direction_ok(self, ax: Axis, d: int) -> Event | None:
        pref = self.preferred(ax)
        if pref is None or d == pref:
            return None
        m = 3 if d > 0 else 4
        err = self.motion.fail(
            ax, Code.SPINDLE_PREFERRED_DIRECTION, f"{ax.name}: M{m} refused", m=m
        )
        self.cancel_task(ax)
        if ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
            self.velocity(ax, 0.0)
        self.set_state(ax, AxisState.ERROR)
        return err

    def cancel_task(self, ax: Axis) -> None:
        """End the task in progress (and the block waiting on it)."""
        self.motion.drop_sequence(ax)

    def switch_back(self, ax: Axis) -> None:
        """Back to position control from the changeover's speed control [001 §2.3]."""
        ax.speed_ctrl = False
        self.motion.arm_speed_control(ax, False)
        if self.motion.loop_mode(ax) == L.LOOP_SPEED_CONTROL and not speed_controlled(ax.cfg):
            self.motion.close_loop(ax)
            self.motion.log(Code.EV_LOOP_CLOSED, ax.name, f"{ax.name} position control")

    def as_rotary_axis(self, ax: Axis) -> Event | None:
        """A spindle jogged or moved like a rotary axis [003 "jogging a spindle"]: from
        standstill (or renewing its jog), position-controlled, so it needs its encoder."""
        if speed_controlled(ax.cfg):
            return self.motion.fail(ax, Code.SPINDLE_SENSORLESS_M19, _why_not_positioned(ax))
        if ax.sequence is not None or ax.state not in (
            AxisState.STANDSTILL,
            AxisState.MOVING,
            AxisState.JOG,
        ):
            return self.motion.fail(ax, Code.AXIS_BUSY, f"{ax.name} is {ax.state.name.lower()}")
        self.switch_back(ax)
        return None

    # --- M3/M4/M5 and S -----------------------------------------------------------------
    def endless(
        self,
        ax: Axis,
        m: int,
        rpm: float | None,
        gear: int | None = None,
        block_id: int | None = None,
    ) -> Event | None:
        """M3/M4 with S (rpm; None keeps the programmed speed), optionally with M40-M45."""
        _check_rpm(rpm)
        err = self.motion.check_motion(ax)
        if err:
            return err
        d = 1 if m == 3 else -1
        err = self._direction_ok(ax, d)
        if err:
            return err
        rpm = rpm if rpm is not None else abs(ax.speed_prog) / RPM_TO_DEG_S
        choice = self.gears.choose(ax, rpm, gear)
        if choice.error is not None:
            return self.gears.refused(ax, choice, gear)
        self.cancel_task(ax)
        self.motion.log(Code.EV_M_START, ax.name, f"M{m} S{rpm:g}", m=m)
        ax.speed_prog = d * rpm * RPM_TO_DEG_S
        assert choice.gear is not None
        if choice.gear != ax.gear:
            self.gears.start(ax, choice.gear, (m, rpm), block_id)
            return None
        self.run_endless(ax)
        return None

    def run_endless(self, ax: Axis) -> None:
        """(Re)plan endless rotation at the commanded speed."""
        self.adopt_tool(ax)
        motion = self.motion
        v = self.commanded(ax)
        v_change = changeover_speeds(ax.cfg)[0]
        in_speed_ctrl = motion.loop_mode(ax) == L.LOOP_SPEED_CONTROL
        # once changed over, a lower speed does not switch back [001 §2.3]
        ax.speed_ctrl = abs(v) > v_change or (ax.speed_ctrl and in_speed_ctrl)
        motion.arm_speed_control(ax, ax.speed_ctrl)
        ax.motion, ax.slope = Motion.FEED, 1
        open_loop = motion.loop_mode(ax) == L.LOOP_CONTROL_LIMIT
        self.set_state(ax, AxisState.OPEN_LOOP if open_loop else AxisState.ENDLESS, True)
        motion.speed_goal(ax, v)
        motion.show_override(ax, self.override(ax))
        self.velocity(ax, v)

    def speed(self, ax: Axis, rpm: float, gear: int | None, block_id: int | None) -> Event | None:
        """S word alone (or S[REV..]): new speed, with a gear change when the table asks."""
        _check_rpm(rpm)
        choice = self.gears.choose(ax, rpm, gear)
        if choice.error is not None:
            return self.gears.refused(ax, choice, gear)
        assert choice.gear is not None
        ax.speed_prog = math.copysign(rpm * RPM_TO_DEG_S, ax.speed_prog or 1.0)
        if choice.gear != ax.gear:
            err = self.motion.check_motion(ax)
            if err:
                return err
            self.gears.start(ax, choice.gear, self.gears.resume(ax), block_id)
        elif ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            self.run_endless(ax)
        return None

    def stop(self, ax: Axis) -> None:
        """M5: brake to standstill (curve or a_brems)."""
        self.cancel_task(ax)
        self.motion.log(Code.EV_M_START, ax.name, "M5", m=5)
        if ax.state in (AxisState.STANDSTILL, AxisState.ERROR):
            return
        self.set_state(ax, AxisState.STOPPING)
        self.velocity(ax, 0.0)

    def m5(self, ax: Axis) -> None:
        """M5; after the control limit an analogue spindle homes on the way to standstill
        [000 §2.7, Fig. 9: "Control limit exceeded -> M5 -> Homing -> Done -> Standstill"]."""
        rotating = ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP, AxisState.STOPPING)
        if not (ax.reference_lost and rotating and self.auto_homing(ax)):
            self.stop(ax)
            return
        self.cancel_task(ax)
        self.motion.log(Code.EV_M_START, ax.name, "M5 (automatic homing)", m=5)
        v = abs(self.motion.k.st[ax.slot, L.S_V_CMD])
        self._run(SpindleTask(self, ax, "M5", 0.0, None, v), None)  # the mark at speed

    # --- M19, G74, gear change ----------------------------------------------------------
    def position(
        self,
        ax: Axis,
        pos_deg: float,
        direction: int | None,
        rpm: float | None,
        block_id: int | None = None,
    ) -> Event | None:
        """M19: position to `pos_deg` (0..360) in `direction` (+1 M3, -1 M4, None)."""
        _check_rpm(rpm)
        if speed_controlled(ax.cfg):
            return self.motion.fail(ax, Code.SPINDLE_SENSORLESS_M19, _why_not_positioned(ax), m=19)
        err = self.motion.check_motion(ax)
        if err:
            return err
        if direction is not None:
            err = self._direction_ok(ax, direction)
            if err:
                return err
        else:
            direction = self.preferred(ax)
        too_fast = self.gears.within_vb_max(ax, rpm) if rpm else None
        if too_fast is not None:
            return self.motion.fail(ax, Code.GEAR_NO_RANGE, too_fast.detail)
        speed = rpm * RPM_TO_DEG_S if rpm else ax.cfg.eng("getriebe.vb_eilgang", ax.gear)
        self.cancel_task(ax)
        self.motion.log(Code.EV_M_START, ax.name, f"M19 S.POS={pos_deg:g}", m=19)
        self._run(SpindleTask(self, ax, "M19", pos_deg % 360.0, direction, speed), block_id)
        return None

    def home(self, ax: Axis, block_id: int | None = None) -> Event | None:
        """G74: rotate to the zero mark, take ref_pos there, stop on it with exact stop."""
        if speed_controlled(ax.cfg):
            return self.motion.fail(ax, Code.SPINDLE_SENSORLESS_M19, _why_not_positioned(ax))
        err = self.motion.check_motion(ax)
        if err:
            return err
        v = self.motion.k.st[ax.slot, L.S_V_CMD]
        d = self.preferred(ax) or (
            sign(v) if abs(v) > V_EPS else (1 if ax.cfg.flag("kenngr.ref_richt") else -1)
        )
        self.cancel_task(ax)
        ref = ax.cfg.eng("kenngr.ref_pos") % 360.0
        task = SpindleTask(self, ax, "G74", ref, d, ax.cfg.eng("getriebe.vb_refmax", ax.gear))
        self.motion.forget_reference(ax)
        self._run(task, block_id)
        return None

    def _run(self, task: SpindleTask, block_id: int | None) -> None:
        """Start a task on its spindle (for the block `block_id`)."""
        task.ax.sequence, task.ax.block_id = task, block_id
        task.advance()

    def target(self, ax: Axis, pos_deg: float, direction: int | None) -> float:
        """Absolute target for an angle [000 §2.3.2]: shortest way from standstill, else
        the first such angle the spindle can still stop at in the required direction."""
        st = self.motion.k.st[ax.slot]
        p, v, a = st[L.S_P_CMD], st[L.S_V_CMD], st[L.S_A_CMD]
        standing = abs(v) <= V_EPS and abs(a) <= V_EPS
        if standing and direction is None:
            return float(p + ((pos_deg - p + 180.0) % 360.0 - 180.0))
        d = direction if direction is not None else sign(v)
        seg = new_plan()
        n = velocity_change(seg, 0, v, a, 0.0, self.limits(ax), self.motion.k.cycle_s)
        brake, _v = plan_distance(seg, 0, n, v)
        p_stop = p + brake
        delta = (d * (pos_deg - p_stop)) % 360.0
        if v * d < -V_EPS and delta < 1e-9:  # after a reversal, still approach in d
            delta = 360.0
        return float(p_stop + d * delta)

    def replan(self, ax: Axis) -> None:
        """Override or override_valid changed."""
        if ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            self.run_endless(ax)
        elif ax.sequence is not None:
            ax.sequence.replan()

    # --- kernel events ------------------------------------------------------------------
    def on_loop_events(self, ax: Axis, ev: int) -> None:
        """The spindle's mode follows the kernel's loop: above the control limit the loop
        opens and the reference is lost [000 §2.7]; speed control above P-AXIS-00767."""
        if not ev & L.EV_LOOP:
            return
        mode = self.motion.loop_mode(ax)
        log = self.motion.log
        if mode == L.LOOP_CONTROL_LIMIT:
            ax.homed, ax.reference_lost = False, True
            log(Code.EV_LOOP_OPENED, ax.name, f"{ax.name} above the control limit")
            log(Code.EV_REFERENCE_LOST, ax.name)
            if ax.state is AxisState.ENDLESS:
                self.set_state(ax, AxisState.OPEN_LOOP, True)
        elif mode == L.LOOP_SPEED_CONTROL:
            log(Code.EV_LOOP_OPENED, ax.name, f"{ax.name} speed control")
        else:  # a task waiting for the loop to close continues (SpindleTask.on_event)
            log(Code.EV_LOOP_CLOSED, ax.name, f"{ax.name} position control")
            if ax.state is AxisState.OPEN_LOOP:
                self.set_state(ax, AxisState.ENDLESS, True)
