"""Spindle behaviours [000, 001, DOMAIN §4]: M3/M4/M5, M19, G74, gear change M40-M45.

Endless rotation runs on the planner (a_beschl/a_brems) or on the speed-dependent curve.
M19, G74 and the gear change are sequences (`SpindleTask`) advanced by kernel events:

    back to position control (decelerate to P-AXIS-00768 if the loop is open)
    -> zero mark (homing, or automatic homing before M19 on analogue drives)
    -> position plan to the target in the required direction -> exact stop
    -> gear change only: M4x to the PLC, its acknowledgement, the new gear record, resume
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from nc_sim.accel_curve import CurveParams
from nc_sim.axis.dynamics import Motion
from nc_sim.axis.params import changeover_speeds, push_params, speed_controlled
from nc_sim.axis.state import Axis, SpindleTask, TaskPhase, ToolLimits
from nc_sim.axis.watchdog import curve_s, plan_s
from nc_sim.blocks import SpindleCmd
from nc_sim.errors import Code, NcUsageError
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.plc import Waiter
from nc_sim.profiles.plan import (
    LIM_A_ACC,
    LIM_A_ACC2,
    LIM_A_DEC,
    LIM_A_DEC2,
    new_plan,
    plan_distance,
    position_move,
    velocity_change,
)
from nc_sim.snapshot import AxisState
from nc_sim.spindle.gears import GearChoice, GearRange, m_of, select_gear
from nc_sim.units import RPM_TO_DEG_S

if TYPE_CHECKING:
    from nc_sim.machine.machine import Machine

ACHSMODE_KEINE_AUTO_RPF = 0x100  # P-AXIS-00015: no automatic homing before M19
DIGITAL_DRIVES = (2, 8)  # SERCOS, CANopen: drive-controlled homing only [000 §2.3]
_V_EPS = 1e-9


def _sign(x: float) -> int:
    return 1 if x > 0 else -1


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

    def __init__(self, machine: Machine) -> None:
        self.m = machine

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

    def gear_table(self, ax: Axis) -> tuple[int, list[GearRange]] | None:
        """(spindel index, ranges) when gear change applies to this spindle."""
        cfg = self.m.cfg
        if not cfg.channel_raw("main_spindle_gear_change") or ax.name != self.m.main_spindle:
            return None
        i = self.m.spindle_index(ax)
        if i is None:
            return None
        pre = f"spindel[{i}].range_table"
        table = [
            GearRange(
                float(cfg.channel_raw(f"{pre}[{g}].min_speed")),
                float(cfg.channel_raw(f"{pre}[{g}].max_speed")),
            )
            for g in range(6)
        ]
        return i, table

    def v_max(self, ax: Axis) -> float:
        v = ax.cfg.eng("getriebe.dynamik.vb_max", ax.gear)
        return min(v, ax.tool.vb_max) if ax.tool.vb_max is not None else v

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

    def limits(self, ax: Axis) -> np.ndarray:
        lim = self.m._limits(ax, Motion.FEED)
        if ax.tool.a_max is not None:
            for col in (LIM_A_ACC, LIM_A_DEC, LIM_A_ACC2, LIM_A_DEC2):
                if lim[col] > 0:
                    lim[col] = min(lim[col], ax.tool.a_max)
        return lim

    # --- primitives ---------------------------------------------------------------------
    def velocity(self, ax: Axis, v: float) -> None:
        """Speed change: along the acceleration curve when one is set, else planned."""
        if int(ax.cfg.raw("getriebe.beschl_kennlinie.typ", ax.gear)) == 0:
            self.m._plan_velocity(ax, v, self.limits(ax))
            return
        ramp = curve_s(self.curve(ax), float(self.m.k.st[ax.slot, L.S_V_CMD]), v)
        if ramp.dead_speed is not None:
            self._curve_refused(ax, ramp.dead_speed)
            return
        self.m._watch(ax, ramp.seconds, "speed change along the acceleration curve")
        self.m.k.load_curve(ax.slot, v)

    def curve(self, ax: Axis) -> CurveParams:
        """The acceleration curve in force (the kernel's copy of the gear record)."""
        pr = self.m.k.pr[ax.slot]
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
        self.m._fail(
            ax,
            Code.CURVE_NO_ACCELERATION,
            f"{ax.name} M{m_of(ax.gear)}: a(n) at {n_deg_s / RPM_TO_DEG_S:g} rpm is "
            f"{self.curve(ax).accel(n_deg_s):g} °/s² (getriebe[{ax.gear - 1}].beschl_kennlinie)",
            gear=ax.gear,
        )
        self.cancel_task(ax)
        self.m._set_state(ax, AxisState.ERROR)
        self.m.k.ist[ax.slot, L.I_MON_ACTIVE] = 0
        self.m.k.st[ax.slot, L.S_V_GOAL] = 0.0
        self.m._plan_velocity(ax, 0.0, self.limits(ax))

    def _state(self, ax: Axis, state: AxisState, monitoring: bool = False) -> None:
        self.m._set_state(ax, state)
        self.m.k.ist[ax.slot, L.I_MON_ACTIVE] = int(monitoring)
        if not monitoring:
            self.m.k.st[ax.slot, L.S_V_GOAL] = 0.0

    def _adopt_tool(self, ax: Axis) -> None:
        """Tool dynamics take effect on the transition from standstill [000 §2.8.5]."""
        if ax.tool_pending is None or ax.state is not AxisState.STANDSTILL:
            return
        ax.tool, ax.tool_pending = ax.tool_pending, None
        push_params(self.m.k, ax)
        self.m.log(Code.EV_TOOL_DYNAMICS, ax.name, f"{ax.name} tool dynamics {ax.tool}")

    def _direction_ok(self, ax: Axis, d: int) -> Event | None:
        pref = self.preferred(ax)
        if pref is None or d == pref:
            return None
        m = 3 if d > 0 else 4
        err = self.m._fail(ax, Code.SPINDLE_PREFERRED_DIRECTION, f"{ax.name}: M{m} refused", m=m)
        self.cancel_task(ax)
        if ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
            self.velocity(ax, 0.0)
        self._state(ax, AxisState.ERROR)
        return err

    def cancel_task(self, ax: Axis) -> None:
        self.m.k.ist[ax.slot, L.I_MARK_ARMED] = 0
        if ax.task is not None:
            ax.task = None
            self.m._abort_block(ax)

    def switch_back(self, ax: Axis) -> None:
        """Back to position control from the changeover's speed control [001 §2.3]."""
        ax.speed_ctrl = False
        ist = self.m.k.ist
        ist[ax.slot, L.I_SPEED_CTRL_ARMED] = 0
        if ist[ax.slot, L.I_OPEN_LOOP] == L.LOOP_SPEED_CONTROL and not speed_controlled(ax.cfg):
            ist[ax.slot, L.I_OPEN_LOOP] = L.LOOP_CLOSED
            self.m.log(Code.EV_LOOP_CLOSED, ax.name, f"{ax.name} position control")

    def as_rotary_axis(self, ax: Axis) -> Event | None:
        """A spindle jogged or moved like a rotary axis [003 "jogging a spindle"]: from
        standstill (or renewing its jog), position-controlled, so it needs its encoder."""
        if speed_controlled(ax.cfg):
            return self.m._fail(ax, Code.SPINDLE_SENSORLESS_M19, _why_not_positioned(ax))
        if ax.task is not None or ax.state not in (
            AxisState.STANDSTILL,
            AxisState.MOVING,
            AxisState.JOG,
        ):
            return self.m._fail(ax, Code.AXIS_BUSY, f"{ax.name} is {ax.state.name.lower()}")
        self.switch_back(ax)
        return None

    # --- gear selection -----------------------------------------------------------------
    def _gear_for(self, ax: Axis, rpm: float, programmed: int | None) -> GearChoice:
        gt = self.gear_table(ax)
        if gt is None:
            if programmed is not None:
                return GearChoice(None, Code.GEAR_CHANGE_OFF, f"M{m_of(programmed)}")
            return self._within_vb_max(ax, rpm) or GearChoice(ax.gear)
        i, table = gt
        automatic = bool(self.m.cfg.channel_raw(f"spindel[{i}].autom_range"))
        way = int(self.m.cfg.channel_raw(f"spindel[{i}].range_way"))
        return select_gear(table, ax.gear, rpm, automatic, way, programmed)

    def _gear_refused(self, ax: Axis, choice: GearChoice, programmed: int | None) -> Event:
        """The job error of a refused gear choice, with the programmed M40-M45 if any."""
        assert choice.error is not None
        detail = choice.detail or (f"M{m_of(programmed)}" if programmed is not None else "")
        if programmed is None:
            return self.m._fail(ax, choice.error, detail)
        return self.m._fail(ax, choice.error, detail, m=m_of(programmed), gear=programmed)

    def _within_vb_max(self, ax: Axis, rpm: float) -> GearChoice | None:
        """The refusal of a speed above the active gear record's maximum (P-AXIS-00212)."""
        top_rpm = ax.cfg.eng("getriebe.dynamik.vb_max", ax.gear) / RPM_TO_DEG_S
        if abs(rpm) <= top_rpm + 1e-9:
            return None
        return GearChoice(
            None,
            Code.GEAR_NO_RANGE,
            f"S{abs(rpm):.10g} rpm is above the maximum speed of {ax.name}, {top_rpm:.10g} rpm "
            f"(getriebe[{ax.gear - 1}].dynamik.vb_max, P-AXIS-00212)",
        )

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
        err = self.m._check_motion(ax)
        if err:
            return err
        d = 1 if m == 3 else -1
        err = self._direction_ok(ax, d)
        if err:
            return err
        rpm = rpm if rpm is not None else abs(ax.speed_prog) / RPM_TO_DEG_S
        choice = self._gear_for(ax, rpm, gear)
        if choice.error is not None:
            return self._gear_refused(ax, choice, gear)
        self.cancel_task(ax)
        self.m.log(Code.EV_M_START, ax.name, f"M{m} S{rpm:g}", m=m)
        ax.speed_prog = d * rpm * RPM_TO_DEG_S
        assert choice.gear is not None
        if choice.gear != ax.gear:
            self.start_gear(ax, choice.gear, (m, rpm), block_id)
            return None
        self.run_endless(ax)
        return None

    def run_endless(self, ax: Axis) -> None:
        """(Re)plan endless rotation at the commanded speed."""
        self._adopt_tool(ax)
        k = self.m.k
        v = self.commanded(ax)
        v_change = changeover_speeds(ax.cfg)[0]
        in_speed_ctrl = k.ist[ax.slot, L.I_OPEN_LOOP] == L.LOOP_SPEED_CONTROL
        # once changed over, a lower speed does not switch back [001 §2.3]
        ax.speed_ctrl = abs(v) > v_change or (ax.speed_ctrl and in_speed_ctrl)
        k.ist[ax.slot, L.I_SPEED_CTRL_ARMED] = int(ax.speed_ctrl)
        ax.motion, ax.slope = Motion.FEED, 1
        open_loop = k.ist[ax.slot, L.I_OPEN_LOOP] == L.LOOP_CONTROL_LIMIT
        self._state(ax, AxisState.OPEN_LOOP if open_loop else AxisState.ENDLESS, True)
        k.st[ax.slot, L.S_V_GOAL] = v
        k.st[ax.slot, L.S_OVERRIDE] = self.override(ax)
        self.velocity(ax, v)

    def speed(self, ax: Axis, rpm: float, gear: int | None, block_id: int | None) -> Event | None:
        """S word alone (or S[REV..]): new speed, with a gear change when the table asks."""
        _check_rpm(rpm)
        choice = self._gear_for(ax, rpm, gear)
        if choice.error is not None:
            return self._gear_refused(ax, choice, gear)
        assert choice.gear is not None
        ax.speed_prog = math.copysign(rpm * RPM_TO_DEG_S, ax.speed_prog or 1.0)
        if choice.gear != ax.gear:
            err = self.m._check_motion(ax)
            if err:
                return err
            self.start_gear(ax, choice.gear, self._resume(ax), block_id)
        elif ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            self.run_endless(ax)
        return None

    def stop(self, ax: Axis) -> None:
        """M5: brake to standstill (curve or a_brems)."""
        self.cancel_task(ax)
        self.m.log(Code.EV_M_START, ax.name, "M5", m=5)
        if ax.state in (AxisState.STANDSTILL, AxisState.ERROR):
            return
        self._state(ax, AxisState.STOPPING)
        self.velocity(ax, 0.0)

    def m5(self, ax: Axis) -> None:
        """M5; after the control limit an analogue spindle homes on the way to standstill
        [000 §2.7, Fig. 9: "Control limit exceeded -> M5 -> Homing -> Done -> Standstill"]."""
        rotating = ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP, AxisState.STOPPING)
        if not (ax.reference_lost and rotating and self.auto_homing(ax)):
            self.stop(ax)
            return
        self.cancel_task(ax)
        self.m.log(Code.EV_M_START, ax.name, "M5 (automatic homing)", m=5)
        v = abs(self.m.k.st[ax.slot, L.S_V_CMD])
        ax.task = SpindleTask("M5", 0.0, None, v)  # passes the zero mark at speed
        self.advance(ax)

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
            return self.m._fail(ax, Code.SPINDLE_SENSORLESS_M19, _why_not_positioned(ax), m=19)
        err = self.m._check_motion(ax)
        if err:
            return err
        if direction is not None:
            err = self._direction_ok(ax, direction)
            if err:
                return err
        else:
            direction = self.preferred(ax)
        too_fast = self._within_vb_max(ax, rpm) if rpm else None
        if too_fast is not None:
            return self.m._fail(ax, Code.GEAR_NO_RANGE, too_fast.detail)
        speed = rpm * RPM_TO_DEG_S if rpm else ax.cfg.eng("getriebe.vb_eilgang", ax.gear)
        self.cancel_task(ax)
        self.m.log(Code.EV_M_START, ax.name, f"M19 S.POS={pos_deg:g}", m=19)
        ax.task = SpindleTask("M19", pos_deg % 360.0, direction, speed)
        ax.block_id = block_id
        self.advance(ax)
        return None

    def home(self, ax: Axis, block_id: int | None = None) -> Event | None:
        """G74: rotate to the zero mark, take ref_pos there, stop on it with exact stop."""
        if speed_controlled(ax.cfg):
            return self.m._fail(ax, Code.SPINDLE_SENSORLESS_M19, _why_not_positioned(ax))
        err = self.m._check_motion(ax)
        if err:
            return err
        v = self.m.k.st[ax.slot, L.S_V_CMD]
        d = self.preferred(ax) or (
            _sign(v) if abs(v) > _V_EPS else (1 if ax.cfg.flag("kenngr.ref_richt") else -1)
        )
        self.cancel_task(ax)
        ref = ax.cfg.eng("kenngr.ref_pos") % 360.0
        ax.task = SpindleTask("G74", ref, d, ax.cfg.eng("getriebe.vb_refmax", ax.gear))
        ax.block_id = block_id
        ax.homed = False
        self.m.k.ist[ax.slot, L.I_HOMED] = 0
        self.advance(ax)
        return None

    def start_gear(
        self, ax: Axis, gear: int, resume: tuple[int, float] | None, block_id: int | None
    ) -> None:
        """Gear change: to the change position at vb_eilgang, M4x to the PLC, wait, adopt."""
        self.cancel_task(ax)
        pos = ax.cfg.eng("getriebe.getr_schalt_pos", ax.gear) % 360.0
        speed = ax.cfg.eng("getriebe.vb_eilgang", ax.gear)
        ax.task = SpindleTask("gear", pos, self.preferred(ax), speed, gear=gear, resume=resume)
        ax.block_id = block_id
        self.m.log(Code.EV_M_START, ax.name, f"M{m_of(gear)}", m=m_of(gear), gear=gear)
        self.m.log(
            Code.EV_GEAR_CHANGE_START,
            ax.name,
            f"{ax.name} gear change M{m_of(ax.gear)} -> M{m_of(gear)}",
            gear=gear,
        )
        if not (ax.homed or self.auto_homing(ax)) or speed_controlled(ax.cfg):
            # no position to go to: change at standstill where the spindle stops
            ax.task.phase = TaskPhase.STOP
            self._state(ax, AxisState.GEAR_CHANGE)
            self.velocity(ax, 0.0)
            return
        self.advance(ax)

    def advance(self, ax: Axis) -> None:
        """Take the task in progress to its next phase."""
        t = ax.task
        if t is None:
            return
        k = self.m.k
        s = ax.slot
        state = AxisState.HOMING if t.kind in ("G74", "M5") else AxisState.POSITIONING
        if t.kind == "gear":
            state = AxisState.GEAR_CHANGE
        self._adopt_tool(ax)
        ax.speed_ctrl = False  # M19 and G74 run position-controlled [001 §2.3]
        k.ist[s, L.I_SPEED_CTRL_ARMED] = 0
        v = k.st[s, L.S_V_CMD]
        mode = k.ist[s, L.I_OPEN_LOOP]
        if mode != L.LOOP_CLOSED:
            # decelerate to the switch-back speed P-AXIS-00768 (and below the control limit)
            # before position control resumes [001 §4.2]
            v_close = min(
                changeover_speeds(ax.cfg)[1],
                ax.cfg.eng("getriebe.vb_regelgrenze", ax.gear) or math.inf,
            )
            if abs(v) > v_close + _V_EPS or mode == L.LOOP_CONTROL_LIMIT:
                t.phase = TaskPhase.DECEL
                self._state(ax, state)
                if abs(v) > v_close + _V_EPS:
                    self.velocity(ax, math.copysign(v_close, v))
                return  # the control limit closes in the kernel: EV_LOOP continues
            self.switch_back(ax)
        if not ax.homed and (t.kind == "G74" or self.auto_homing(ax)):
            t.phase = TaskPhase.SEEK_MARK
            k.ist[s, L.I_MARK_ARMED] = 1
            self._state(ax, state)
            d = t.direction or (_sign(v) if abs(v) > _V_EPS else 1)
            v_seek = ax.cfg.eng("getriebe.vb_refmax", ax.gear)
            if v * d > _V_EPS:  # already turning the right way: pass the mark at speed
                v_seek = max(v_seek, min(abs(v), t.speed * self.override(ax)))
            self.velocity(ax, d * v_seek)
            # the mark passes once per revolution
            self.m._watch(ax, 360.0 / v_seek, "search for the zero mark", extend=True)
            return
        if t.kind == "M5":  # homed on the way: now brake to standstill
            t.phase = TaskPhase.STOP
            self._state(ax, AxisState.STOPPING)
            self.velocity(ax, 0.0)
            return
        if not ax.homed:
            self.m._fail(
                ax,
                Code.SPINDLE_NOT_HOMED,
                f"{ax.name}: {t.kind} needs a reference",
                m=19 if t.kind == "M19" else None,
            )
            self.cancel_task(ax)
            self.velocity(ax, 0.0)
            self._state(ax, AxisState.ERROR)
            return
        t.phase = TaskPhase.POSITION
        self._state(ax, state)
        ax.target = self.target(ax, t.pos_deg, t.direction)
        self.plan_position(ax)

    def target(self, ax: Axis, pos_deg: float, direction: int | None) -> float:
        """Absolute target for an angle [000 §2.3.2]: shortest way from standstill, else
        the first such angle the spindle can still stop at in the required direction."""
        st = self.m.k.st[ax.slot]
        p, v, a = st[L.S_P_CMD], st[L.S_V_CMD], st[L.S_A_CMD]
        standing = abs(v) <= _V_EPS and abs(a) <= _V_EPS
        if standing and direction is None:
            return float(p + ((pos_deg - p + 180.0) % 360.0 - 180.0))
        d = direction if direction is not None else _sign(v)
        seg = new_plan()
        n = velocity_change(seg, 0, v, a, 0.0, self.limits(ax), self.m.k.cycle_s)
        brake, _v = plan_distance(seg, 0, n, v)
        p_stop = p + brake
        delta = (d * (pos_deg - p_stop)) % 360.0
        if v * d < -_V_EPS and delta < 1e-9:  # after a reversal, still approach in d
            delta = 360.0
        return float(p_stop + d * delta)

    def plan_position(self, ax: Axis) -> None:
        """Position plan to ax.target at the task speed × override."""
        t = ax.task
        assert t is not None
        k = self.m.k
        st = k.st[ax.slot]
        v_max = min(t.speed * self.override(ax), self.v_max(ax))
        k.st[ax.slot, L.S_OVERRIDE] = self.override(ax)
        if v_max <= 0:  # override 0 %: hold; the move resumes with the override
            self.m._plan_velocity(ax, 0.0, self.limits(ax))
            self.m._unwatch(ax)  # held by the operator, not stuck
            return
        seg = new_plan()
        n = position_move(
            seg,
            st[L.S_P_CMD],
            st[L.S_V_CMD],
            st[L.S_A_CMD],
            ax.target,
            v_max,
            self.limits(ax),
            k.cycle_s,
        )
        self.m._watch(ax, plan_s(seg, n), f"{t.kind}: positioning to {t.pos_deg:g}°")
        k.load_plan(ax.slot, seg, n, ax.target)

    def replan(self, ax: Axis) -> None:
        """Override or override_valid changed."""
        if ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            self.run_endless(ax)
        elif ax.task is not None and ax.task.phase is TaskPhase.POSITION:
            self.plan_position(ax)

    def _latch_zero_mark(self, ax: Axis) -> None:
        """The zero mark just passed: the position there becomes ref_pos."""
        k = self.m.k
        s = ax.slot
        pr = k.pr
        cam = pr[s, L.P_CAM_POS]
        x_edge = cam + round((k.st[s, L.S_X_MOTOR] - cam) / 360.0) * 360.0
        latched = pr[s, L.P_ENC_SIGN] * pr[s, L.P_SIGN_FB] * x_edge + pr[s, L.P_ENC_OFFSET]
        shift = ax.cfg.eng("kenngr.ref_pos") - latched
        pr[s, L.P_ENC_OFFSET] += shift
        for col in (L.S_P_ACT, L.S_P_CMD, L.S_SEG_P0):
            k.st[s, col] += shift
        ax.homed, ax.reference_lost = True, False
        k.ist[s, L.I_HOMED] = 1
        k.ist[s, L.I_MARK_ARMED] = 0
        self.m.log(Code.EV_HOMED, ax.name, f"{ax.name} reference at the zero mark")

    def _task_done(self, ax: Axis) -> None:
        t = ax.task
        assert t is not None
        if t.kind == "gear":
            t.phase = TaskPhase.WAIT_PLC
            self._state(ax, AxisState.GEAR_CHANGE)
            self.m.handshake.output(
                m_of(t.gear),
                ax.name,
                Waiter(
                    lambda: self.gear_acknowledged(ax),
                    lambda ev: self.gear_timeout(ax, ev),
                    ax.name,
                ),
                t.gear,
            )
            # the PLC's own timeout (90004) ends it first; this bounds it as every phase
            timeout = self.m.cfg.channel_eng("plc.m_ack_timeout")
            self.m._watch(ax, timeout, f"gear change: M{m_of(t.gear)} acknowledgement")
            return
        ax.task = None
        self._state(ax, AxisState.STANDSTILL)
        ax.motion, ax.block_id = None, None
        if t.kind == "M5":
            self.m.log(Code.EV_MOTION_DONE, ax.name, f"{ax.name} stopped (M5)", m=5)
            return
        self.m.log(
            Code.EV_IN_POSITION,
            ax.name,
            f"{ax.name} at {t.pos_deg:g}° ({t.kind})",
            m=19 if t.kind == "M19" else None,  # the in-position that ends M19 [000 §2.3]
        )

    def gear_acknowledged(self, ax: Axis) -> None:
        """The PLC has changed the gear: adopt the new record and resume."""
        t = ax.task
        if t is None or t.kind != "gear":
            return
        old = ax.gear
        ax.gear = t.gear
        push_params(self.m.k, ax)
        self.m.log(
            Code.EV_GEAR_CHANGED,
            ax.name,
            f"{ax.name} gear M{m_of(old)} -> M{m_of(ax.gear)}",
            gear=ax.gear,
        )
        ax.task = None
        ax.block_id = None
        self._state(ax, AxisState.STANDSTILL)
        if t.resume is not None:
            m, rpm = t.resume
            self.endless(ax, m, rpm)

    def gear_timeout(self, ax: Axis, error: Event) -> None:
        """No acknowledgement of the M40-M45 (job error `error`): the change ends in error."""
        self.m._set_job_error(ax, error)
        if ax.task is not None and ax.task.kind == "gear":
            self.cancel_task(ax)
            self._state(ax, AxisState.ERROR)

    # --- kernel events ------------------------------------------------------------------
    def on_events(self, ax: Axis, ev: int) -> bool:
        """Spindle reactions; returns True when the plan-done event was consumed here."""
        k = self.m.k
        s = ax.slot
        if ev & L.EV_LOOP:
            mode = int(k.ist[s, L.I_OPEN_LOOP])
            if mode == L.LOOP_CONTROL_LIMIT:
                ax.homed, ax.reference_lost = False, True
                self.m.log(Code.EV_LOOP_OPENED, ax.name, f"{ax.name} above the control limit")
                self.m.log(Code.EV_REFERENCE_LOST, ax.name)
                if ax.state is AxisState.ENDLESS:
                    self._state(ax, AxisState.OPEN_LOOP, True)
            elif mode == L.LOOP_SPEED_CONTROL:
                self.m.log(Code.EV_LOOP_OPENED, ax.name, f"{ax.name} speed control")
            else:
                self.m.log(Code.EV_LOOP_CLOSED, ax.name, f"{ax.name} position control")
                if ax.state is AxisState.OPEN_LOOP:
                    self._state(ax, AxisState.ENDLESS, True)
                elif ax.task is not None and ax.task.phase is TaskPhase.DECEL:
                    self.advance(ax)
        t = ax.task
        if t is None:
            return False
        if ev & L.EV_CAM and t.phase is TaskPhase.SEEK_MARK:
            self._latch_zero_mark(ax)
            self.advance(ax)
            return True
        if ev & L.EV_PLAN_DONE:
            if t.phase is TaskPhase.DECEL and k.ist[s, L.I_OPEN_LOOP] != L.LOOP_CONTROL_LIMIT:
                self.advance(ax)
                return True
            elif t.phase is TaskPhase.STOP:
                self._task_done(ax)
        if ev & L.EV_IN_POS and t.phase is TaskPhase.POSITION:
            self._task_done(ax)
        return True

    # --- blocks -------------------------------------------------------------------------
    def block(self, ax: Axis, sc: SpindleCmd, gear: int | None, block_id: int) -> bool:
        """One spindle's part of an MDI block; False when it ended in a job error."""
        for g in sc.g:
            if g == 167:  # override off until the next S[REV..] [000 §2.4.1]
                ax.override_suppressed = True
            elif g == 135:
                ax.ff_weight = ax.ff_set
            elif g == 136:
                if sc.ff_weight is not None:
                    ax.ff_set = max(0.0, min(sc.ff_weight, 100.0)) / 100.0
                if ax.ff_weight > 0:
                    ax.ff_weight = ax.ff_set
            elif g == 137:
                ax.ff_weight = 0.0
            self.m.k.pr[ax.slot, L.P_FF] = ax.ff_weight
        if sc.speed_rpm is not None and 167 not in sc.g and sc.m != 19:
            ax.override_suppressed = False
        if sc.default_dynamics:
            ax.tool_pending = ToolLimits()
            self.m.log(Code.EV_TOOL_DYNAMICS, ax.name, f"{ax.name} default dynamics pending")
        err: Event | None = None
        if sc.m in (3, 4):
            err = self.endless(ax, sc.m, sc.speed_rpm, gear, block_id)
        elif sc.m == 5:
            self.m5(ax)
        elif sc.m == 19:
            err = self.position(ax, sc.pos_deg or 0.0, sc.direction, sc.speed_rpm, block_id)
        elif 74 in sc.g:
            err = self.home(ax, block_id)
        elif sc.speed_rpm is not None:
            err = self.speed(ax, sc.speed_rpm, gear, block_id)
        elif gear is not None:
            err = self.gear_only(ax, gear, block_id)
        elif sc.g:  # G135-G137, G167 alone: the new weighting or override now
            self.replan(ax)
        return err is None

    def gear_only(self, ax: Axis, gear: int, block_id: int | None) -> Event | None:
        """M40-M45 without S (MDI or the gear buttons): the stage is checked against the speed
        it will run with, as `M4x S..` is: the programmed S of a rotating spindle; at
        standstill there is none, the next S is checked."""
        if self.gear_table(ax) is None:
            return self._gear_refused(ax, GearChoice(None, Code.GEAR_CHANGE_OFF), gear)
        resume = self._resume(ax)
        if resume is not None:
            choice = self._gear_for(ax, resume[1], gear)
            if choice.error is not None:
                return self._gear_refused(ax, choice, gear)
        if gear == ax.gear:
            return None
        err = self.m._check_motion(ax)
        if err:
            return err
        self.start_gear(ax, gear, resume, block_id)
        return None

    def _resume(self, ax: Axis) -> tuple[int, float] | None:
        """What a rotating spindle runs again after a gear change: (M3|M4, rpm)."""
        if ax.state not in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            return None
        return (3 if ax.speed_prog > 0 else 4, abs(ax.speed_prog) / RPM_TO_DEG_S)
