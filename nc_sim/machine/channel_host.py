"""The machine as its channel sees it (nc_sim/channel/channel.py `ChannelHost`): actions
that are not path motion, the path axes' limits, and what runs for which action."""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from nc_sim.axis.dynamics import (
    Motion,
    feedhold_limits,
    motion_limits,
    path_share,
    velocity_limit,
)
from nc_sim.axis.moves import reduced_speed
from nc_sim.channel import canon
from nc_sim.channel.execution import PLC_INFO
from nc_sim.channel.geometry import Element, point_at
from nc_sim.channel.planner import AxisDynamics, element_limits, single_stage
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.machine.core import MachineCore
from nc_sim.plc import Waiter
from nc_sim.profiles.plan import (
    LIM_A_ACC,
    LIM_A_ACC2,
    LIM_A_DEC,
    LIM_A_DEC2,
    LIM_TR_ACC_DOWN,
    LIM_TR_ACC_UP,
    LIM_TR_DEC_DOWN,
    LIM_TR_DEC_UP,
)
from nc_sim.snapshot import AxisState
from nc_sim.spindle.coupled import start_tap, start_thread
from nc_sim.spindle.gears import spindle_index
from nc_sim.spindle.program import program_end, spindle_call, tool_dynamics
from nc_sim.units import AxisKind

if TYPE_CHECKING:
    from nc_sim.axis.state import Axis

_M_OF: dict[type[canon.Call], int] = {canon.SpindleOff: 5, canon.SpindleOrient: 19}
_SYNC_PARAM = {
    canon.SpindleOff: "m5_synch",
    canon.SpindleOrient: "m19_synch",
    canon.SpindleSpeed: "s_synch",
}


class MachineChannelHost:
    """Carries the channel's actions out on the machine's axes, spindles and PLC."""

    def __init__(self, m: MachineCore, path_axes: list[Axis]) -> None:
        self.m = m
        self.path_axes = path_axes
        self.m_pending: dict[int, int] = {}  # action -> M functions not yet acknowledged
        self.stopping: dict[int, Axis] = {}  # M5 action -> its spindle (until standstill)
        # M3/M4/S action -> its spindle (speed reached) and the cycle it was commanded in
        self.reaching: dict[int, tuple[Axis, int]] = {}
        self.homing: dict[int, list[list[str]]] = {}  # G74 action -> order groups to come
        self.moving = False  # the path axes move for the channel (not for a jog)
        self.next_id = 1  # numbers of actions
        self.path_start: list[float] = []  # the path axes' positions where the path started
        self.tapping: Axis | None = None  # the spindle a G63 element follows

    @property
    def cycle(self) -> int:
        return self.m.cycle

    def new_action_id(self) -> int:
        self.next_id += 1
        return self.next_id - 1

    def spindle_name(self, name: str) -> str:
        return (self.m.main_spindle or name) if name == "S" else name

    def block_done(self, block_id: int, text: str) -> None:
        self.m.log(Code.EV_BLOCK_DONE, "", text, block=block_id)

    def block_dropped(self, block_id: int, text: str, cause: Event) -> None:
        self.m.log(
            Code.EV_BLOCK_DROPPED,
            "",
            f"{text} (by {cause.code})",
            block=block_id,
            value=float(cause.seq),
        )

    def channel_error(self, ev: Event | None) -> None:
        """A job error stops the program or the MDI blocks (nc_sim/channel `abort`)."""
        self.m.channel.abort(ev)

    def block_target(self, ax: Axis) -> float | None:
        """A path axis' target: where the block the path is in ends for it [000 §2.9]."""
        e = self.m.channel.path.current
        if e is None or ax not in self.path_axes:
            return None
        return float(e.end[self.path_axes.index(ax)])

    def path_left(self) -> None:
        """The path was abandoned mid-way: each path axis still moving brakes on its own,
        and so does a tapping spindle."""
        tap, self.tapping = self.tapping, None
        if tap is not None and tap.state is AxisState.MOVING:
            tap.block_id = None
            self.m.motion.stop(tap, self.m.sp.limits(tap))
        if not self.moving:
            return
        self.moving = False
        inactive = self.m.channel.path.inactive
        for a in self.path_axes:
            a.jog_on_path = False  # its offset stopped with the path, where it was
            if a.state is AxisState.MOVING and a.slot not in inactive:
                self.m.moves.stop(a, Motion.FEED)

    def synch_plc(self, ax: Axis, m: int) -> bool:
        """M3/M4/M5/M19 with the PLC_INFO bit are output to the PLC [000 §2.5]."""
        i = spindle_index(self.m.cfg, ax.name)
        if i is None or m not in (3, 4, 5, 19):
            return False
        return bool(int(self.m.cfg.channel_raw(f"spindel[{i}].m{m}_synch")) & PLC_INFO)

    def _spindle(self, name: str, line: int) -> Axis | Event:
        """The spindle a call of program `line` names, else the job error (logged)."""
        m = self.m
        if name not in m.by_name and not (name == "S" and m.main_spindle):
            return m.motion.fail(None, Code.UNKNOWN_AXIS, f"line {line}: no spindle")
        ax = m.axis(name)
        if ax.kind is not AxisKind.SPINDLE:
            return m.motion.fail(ax, Code.NOT_A_SPINDLE, f"line {line}")
        return ax

    # --- actions --------------------------------------------------------------------------
    def start_action(self, call: canon.Call, action_id: int) -> Event | None:
        m = self.m
        seen = m.events.cursor
        ok = True
        match call:
            case (
                canon.SpindleOn()
                | canon.SpindleOff()
                | canon.SpindleOrient()
                | canon.SpindleSpeed()
                | canon.SpindleSettings()
            ):
                found = self._spindle(call.spindle, call.line)
                if isinstance(found, Event):
                    return found
                ax = found
                cax = m.cax
                spindle_mode = isinstance(
                    call, canon.SpindleOn | canon.SpindleOff | canon.SpindleOrient
                )
                if spindle_mode and cax is not None and ax is cax.ax and not cax.spindle_mode:
                    # in neither mode (the PLC acknowledged none): change over first
                    return self._after_changeover(call, action_id)
                if (
                    isinstance(call, canon.SpindleOn | canon.SpindleSpeed)
                    and call.gear is not None
                    and not m.gear_change_enabled
                ):
                    self.output(call.gear + 39, "", action_id)  # a free M function then
                    call = replace(call, gear=None)
                if isinstance(call, canon.SpindleOff):
                    self.stopping[action_id] = ax
                elif isinstance(call, canon.SpindleOn | canon.SpindleSpeed):
                    self.reaching[action_id] = (ax, m.cycle)
                ok = spindle_call(m.sp, ax, call, action_id) is None
                mfunc = _M_OF.get(type(call)) or getattr(call, "m", None)
                if ok and mfunc is not None and self.synch_plc(ax, mfunc):
                    self.output(mfunc, ax.name, action_id)
            case canon.SelectGear():
                main = m.main_spindle
                if m.gear_change_enabled and main:
                    ok = m.sp.gears.only(m.axis(main), call.stage, action_id) is None
                elif m.gear_change_enabled:
                    return m.motion.fail(None, Code.GEAR_CHANGE_OFF, f"line {call.line}")
                else:  # M40-M45 are free M functions (P-CHAN-00052)
                    self.output(call.stage + 39, "", action_id)
            case canon.SelectTool():
                if call.d is not None:
                    tool_dynamics(m.sp, m.axes, call.d)
            case canon.SetSlope():
                m.slope = call.slope_type
            case canon.Home():
                for name, _order in call.axes:
                    known = name in m.by_name or (m.cax is not None and name == m.cax.c_name)
                    if not known and not (name == "S" and m.main_spindle):
                        return m.motion.fail(None, Code.UNKNOWN_AXIS, f"line {call.line}: {name}")
                orders = sorted({o for _n, o in call.axes})
                groups = [[n for n, o in call.axes if o == order] for order in orders]
                self.homing[action_id] = groups
                ok = self._home_next(action_id)
            case canon.MFunction():
                self.output(call.m, "", action_id)
            case canon.RotaryMode():
                if m.cax is None:
                    return m.motion.fail(
                        None, Code.CHANGEOVER_NOT_POSSIBLE, f"line {call.line}: no C axis"
                    )
                ok = m.cax.request(call.rotary, action_id) is None
        if ok:
            return None
        return next((e for e in m.events.since(seen).entries if e.error), None) or m.log(
            Code.CHANNEL_ERROR_STATE, "", f"line {call.line} could not start", line=call.line
        )

    def _after_changeover(self, call: canon.Call, action_id: int) -> Event | None:
        """A spindle function while the spindle is in no mode: the changeover to spindle
        mode, then the function (its job error stops the block)."""
        cax = self.m.cax
        assert cax is not None
        return cax.request(False, action_id, partial(self._start_or_fail, call, action_id))

    def _start_or_fail(self, call: canon.Call, action_id: int) -> Event | None:
        """Start the action; its job error stops the block."""
        err = self.start_action(call, action_id)
        if err is not None:
            self.channel_error(err)
        return err

    def output(self, mfunc: int, axis: str, action_id: int) -> None:
        """An M function to the PLC, waited for by `action_id`."""
        waiter = Waiter(
            partial(self.acknowledged, action_id), partial(self._m_timed_out, action_id)
        )
        self.m.handshake.output(mfunc, axis, waiter)
        self.m_pending[action_id] = self.m_pending.get(action_id, 0) + 1

    def _m_timed_out(self, action_id: int, ev: Event) -> None:
        """No acknowledgement in time: the block that waits for it stops in error."""
        if action_id in self.m_pending:
            self.channel_error(ev)

    def acknowledged(self, action_id: int | None) -> None:
        """The PLC acknowledged an M function of this action."""
        if action_id in self.m_pending:
            self.m_pending[action_id] -= 1
            if self.m_pending[action_id] <= 0:
                del self.m_pending[action_id]

    def _home_next(self, action_id: int) -> bool:
        groups = self.homing.get(action_id)
        if not groups:
            self.homing.pop(action_id, None)
            return True
        m = self.m
        # a spindle homes beside the program: nothing waits for it, but its job error stops
        # the program (block 0) [000 §2.7]
        return all(
            m.moves.home(ax, 0 if ax.kind is AxisKind.SPINDLE else action_id) is None
            for ax in (m.axis(name) for name in groups.pop(0))
        )

    def busy(self, action_id: int) -> bool:
        axes = self.m.axes
        if action_id in self.homing:
            # the next G74 group starts when the axes of this one are homed (its spindle
            # homes unsynchronised, the block does not wait for it) [000 §2.7]
            if not any(a.block_id == action_id for a in axes) and not self._home_next(action_id):
                self.homing.pop(action_id, None)
            if action_id in self.homing:
                return True
        if any(a.block_id == action_id for a in axes):
            return True
        if self.m_pending.get(action_id, 0) > 0:
            return True
        ax = self.stopping.get(action_id)
        if ax is not None:
            if ax.state is not AxisState.STANDSTILL or not self.m.k.ist[ax.slot, L.I_STOPPED]:
                return True
            del self.stopping[action_id]
        reaching = self.reaching.get(action_id)
        if reaching is not None:
            ax, since = reaching
            turning = ax.state in (AxisState.ENDLESS, AxisState.OPEN_LOOP)
            # the flag of the cycle the speed was commanded in still compares with the old
            # speed: only a later cycle's says whether the new one is reached [000 §2.5.2]
            fresh = self.m.cycle > since
            if turning and not (fresh and self.m.k.ist[ax.slot, L.I_SPEED_REACHED]):
                return True
            del self.reaching[action_id]
        return False

    def next_wakeup(self) -> int | None:
        """The next cycle to look again without a kernel event: a stopped spindle (M5) is
        "spindle stopped" only once its actual speed has decayed, which raises no event."""
        k = self.m.k
        for ax in self.stopping.values():
            if ax.state is AxisState.STANDSTILL and not k.ist[ax.slot, L.I_STOPPED]:
                return self.m.cycle + 1
        return None

    def sync_of(self, call: canon.Call) -> int:
        if not isinstance(
            call, canon.SpindleOn | canon.SpindleOff | canon.SpindleOrient | canon.SpindleSpeed
        ):
            return 0
        i = spindle_index(self.m.cfg, self.m.axis(call.spindle).name)
        if i is None:
            return 0
        name = f"m{call.m}_synch" if isinstance(call, canon.SpindleOn) else _SYNC_PARAM[type(call)]
        sync = int(self.m.cfg.channel_raw(f"spindel[{i}].{name}"))
        gear = self._gear_change_of(call)
        if gear is not None:  # the gear change's M40-M45 synchronises as m_synch says
            sync |= int(self.m.cfg.channel_raw(f"m_synch[{39 + gear}]"))
        return sync

    def path_limits(self, call: canon.VectorLimit) -> tuple[float, float, float]:
        cfg = self.m.cfg
        # P-CHAN-00351: MM_S2, or mm/min² (MM_M2, the default)
        per_s2 = 1.0 if str(cfg.channel_raw("vector.acc_dec_unit")).upper() == "MM_S2" else 1 / 3600

        def limit(value: canon.PathLimit, default: str, scale: float) -> float:
            if value is None:
                return math.inf
            raw = float(cfg.channel_raw(default)) if value == "default" else value
            return raw * scale

        return (
            limit(call.velocity, "vector.velocity", 1 / 60),
            limit(call.acceleration, "vector.acceleration", per_s2),
            limit(call.deceleration, "vector.deceleration", per_s2),
        )

    def _gear_change_of(self, call: canon.Call) -> int | None:
        """The gear stage a speed of the main spindle changes to (M40-M45 as 1-6), None
        without a change [000 §2.8.2]: judged from the stage in force when the block is
        prepared."""
        m = self.m
        if not isinstance(call, canon.SpindleOn | canon.SpindleSpeed) or not m.gear_change_enabled:
            return None
        ax = m.axis(call.spindle)
        if ax.name != m.main_spindle or call.speed_rpm is None:
            return None
        choice = m.sp.gears.choose(ax, call.speed_rpm, call.gear)
        return choice.gear if choice.error is None and choice.gear != ax.gear else None

    def manual_mode(self, parallel: bool) -> None:
        self.m.motion.ctx.parallel_manual = parallel

    def program_end(self, call: canon.ProgramEnd) -> None:
        program_end(self.m.sp, self.m.axes)

    # --- the path -------------------------------------------------------------------------
    def start_coupling(self, e: Element) -> Event | None:
        c = e.coupling
        assert c is not None
        m = self.m
        ax = self._spindle(c.spindle, e.line)
        if isinstance(ax, Event):
            return ax
        lim = element_limits(e, self.dynamics(e), math.inf)
        a_acc, a_dec = single_stage(lim.lim)
        if c.kind == L.COUPLE_TAP:
            err = start_tap(m.sp, ax, e, lim.v_cap, a_acc, a_dec)
            if err is None:
                self.tapping = ax
            return err
        return start_thread(m.sp, ax, e, lim.v_cap, a_acc, a_dec)

    def path_in_position(self) -> bool:
        k = self.m.k
        inactive = self.m.channel.path.inactive
        return all(
            abs(k.st[a.slot, L.S_P_CMD] - k.st[a.slot, L.S_P_ACT]) <= k.pr[a.slot, L.P_INPOS_WIN]
            for a in self.path_axes
            if a.slot not in inactive and not a.jog_on_path  # a G201 jog is not the path's
        )

    def check_element(self, e: Element) -> Event | None:
        m = self.m
        moved = np.abs(e.end - e.start) > 1e-12
        if e.arc is not None:
            moved[e.arc[0]] = moved[e.arc[1]] = True
        inactive = m.channel.path.inactive
        for i, ax in enumerate(self.path_axes):
            if ax.slot in inactive:
                continue  # the C axis while the main spindle is a spindle
            if moved[i]:
                err = m.motion.drive_refusal(ax) or m.moves.homing_required(ax)
                if err:
                    return err
            # the path drives every path axis, so none may move on its own (jog, move)
            on_path = self.moving and m.k.ist[ax.slot, L.I_ROLE] == L.ROLE_PATH_AXIS
            standing = ax.state is AxisState.STANDSTILL or (
                not moved[i] and ax.state is AxisState.ERROR
            )
            if not (standing or (on_path and ax.state is AxisState.MOVING)):
                what = "moving on its own" if ax.state is AxisState.MOVING else ax.state.name
                return m.motion.fail(ax, Code.AXIS_BUSY, f"{ax.name} is {what.lower()}")
            if not moved[i]:
                continue
            limits = m.moves.position_limits(ax)
            if limits is not None:
                lo, hi = limits
                samples = 2 if e.arc is None else 65
                for j in range(samples):
                    p = point_at(e, e.length * j / (samples - 1))[i]
                    if not lo - 1e-9 <= p <= hi + 1e-9:
                        where = "" if e.block_id else f"line {e.line}: "  # MDI: no line
                        what = "target" if j == samples - 1 else "path point"
                        u = ax.pos_unit
                        return m.motion.fail(
                            ax,
                            Code.SOFTWARE_LIMIT,
                            f"{where}{ax.name} {what} {p:.4f} {u} outside {lo:.4f} … {hi:.4f} {u}",
                        )
        return None

    def dynamics(self, e: Element) -> list[AxisDynamics]:
        motion = Motion.RAPID if e.rapid else Motion.FEED
        reduced = bool(self.m.channel_units["reduced_acceleration"])
        cycle = self.m.k.cycle_s
        corr = bool(self.m.cfg.channel_raw("corr_v_trans_jerk"))
        spans = _spans(e)
        acc_mode = int(self.m.cfg.channel_raw("prog_start.slope.acceleration"))
        ramp_mode = int(self.m.cfg.channel_raw("prog_start.slope.ramp_time"))
        out: list[AxisDynamics] = []
        for i, ax in enumerate(self.path_axes):
            g = ax.gear
            lim = motion_limits(ax.cfg, g, motion, self.m.slope, reduced)
            if e.acceleration_weight is not None:  # G130/G131, capped at a_max
                a_max = ax.cfg.eng("getriebe.dynamik.a_max", g)
                cols = _ACC_WEIGHTED[acc_mode]
                lim[cols] = np.minimum(lim[cols] * e.acceleration_weight[i], a_max)
            if e.ramp_time_weight is not None:  # G132/G133
                cols = _RAMP_WEIGHTED[ramp_mode]
                lim[cols] = lim[cols] * e.ramp_time_weight[i]
            if motion is Motion.RAPID:
                v_max = velocity_limit(ax.cfg, g, motion, None)
            else:
                v_max = ax.cfg.eng("getriebe.dynamik.vb_max", g)
            if e.parallel_manual:  # G201: the path's share, the rest is the jog's
                v_part, a_part = path_share(ax.cfg)
                v_max = min(v_max, v_part * ax.cfg.eng("getriebe.dynamik.vb_max", g))
                lim[_ACCELERATIONS] = lim[_ACCELERATIONS] * a_part
            a = float(lim[LIM_A_ACC])
            tr = float(lim[LIM_TR_ACC_UP])
            w = float(ax.cfg.raw("getriebe.dynamik.a_trans_weight", g))
            # P-AXIS-00013: 0 weights the acceleration with cycle/ramp time [002 §2.3.1]
            a_trans = a * w / 1000.0 if w > 0 else a * min(1.0, cycle / tr if tr > 0 else 1.0)
            j_trans = math.inf
            if corr:  # P-CHAN-00009 with P-AXIS-00154 [002 §2.3.2]
                rw = float(ax.cfg.raw("getriebe.dynamik.r_trans_weight", g))
                j_axis = a / max(tr, cycle)
                j_trans = j_axis * (rw / 1000.0 if rw > 0 else min(1.0, cycle / max(tr, cycle)))
            tr_geom = ax.cfg.eng("getriebe.dynamik.tr_geom", g) or ax.cfg.eng(
                "getriebe.dynamik.tr_min", g
            )
            # a door open, a safety zone: each axis at its reduced speed
            red = reduced_speed(ax, motion, spans[len(out)])
            v_red = math.inf if red is None else red.value
            out.append(AxisDynamics(v_max, lim, a_trans, j_trans, tr_geom, v_red))
        return out

    def hold_limits(self, e: Element | None) -> np.ndarray:
        use_set = bool(self.m.cfg.channel_raw("use_drive_curr_limit"))
        motion = Motion.RAPID if e is not None and e.rapid else Motion.FEED
        dyn = [
            AxisDynamics(
                math.inf,
                feedhold_limits(ax.cfg, ax.gear, motion, self.m.slope, use_set),
                0.0,
                math.inf,
                0.0,
            )
            for ax in self.path_axes
        ]
        if e is None:
            return dyn[0].lim
        return element_limits(e, dyn, math.inf).lim

    def path_moving(self, line: int | None) -> None:
        if line is None and not self.moving:
            return
        st = self.m.k.st
        if line is not None and not self.moving:
            self.path_start = [float(st[a.slot, L.S_P_CMD]) for a in self.path_axes]
        self.moving = line is not None
        if line is None:
            self.tapping = None  # the tap's spindle ends its move by itself
        inactive = self.m.channel.path.inactive
        for i, ax in enumerate(self.path_axes):
            if ax.slot in inactive:
                continue
            if line is not None and ax.state is AxisState.STANDSTILL:
                ax.motion = Motion.FEED
                self.m.motion.set_state(ax, AxisState.MOVING)
            elif line is None and ax.state is AxisState.MOVING and ax.motion is Motion.FEED:
                ax.motion = None
                self.m.motion.set_state(ax, AxisState.STANDSTILL)
                if st[ax.slot, L.S_P_CMD] != self.path_start[i]:  # it moved on the path
                    self.m.log(Code.EV_MOTION_DONE, ax.name)
            if line is None and ax.jog_on_path and self.m.k.ist[ax.slot, L.I_ROLE] == L.ROLE_AXIS:
                # the path let go of it while a G201 jog runs: the jog goes on as one of its own
                ax.jog_on_path = False
                ax.motion, ax.feed = Motion.MANUAL, None
                ax.target = float(st[ax.slot, L.S_TARGET])
                self.m.motion.set_state(ax, AxisState.JOG)


# what G130/G131 weight by P-CHAN-00001: all accelerations, those while the speed grows,
# those while it falls; G132/G133 by P-CHAN-00073: all ramp times, or one of T_R,accel,inc
# (tr_beschl_zu), T_R,accel,red (tr_beschl_ab), T_R,decel,inc (tr_brems_zu), T_R,decel,red
# (tr_brems_ab) [002 §3.2.1]
_ACCELERATIONS = [LIM_A_ACC, LIM_A_DEC, LIM_A_ACC2, LIM_A_DEC2]
_ACC_WEIGHTED = {
    0: _ACCELERATIONS,
    1: [LIM_A_ACC, LIM_A_ACC2],
    2: [LIM_A_DEC, LIM_A_DEC2],
}
_RAMP_WEIGHTED = {
    0: [LIM_TR_ACC_UP, LIM_TR_ACC_DOWN, LIM_TR_DEC_UP, LIM_TR_DEC_DOWN],
    1: [LIM_TR_ACC_UP],
    2: [LIM_TR_ACC_DOWN],
    3: [LIM_TR_DEC_UP],
    4: [LIM_TR_DEC_DOWN],
}


def _spans(e: Element, samples: int = 16) -> list[tuple[float, float]]:
    """Each path axis' lowest and highest position on the element (an arc sampled)."""
    if e.arc is None:
        return [(min(a, b), max(a, b)) for a, b in zip(e.start, e.end, strict=True)]
    pts = np.array([point_at(e, e.length * i / samples) for i in range(samples + 1)])
    return [(float(c.min()), float(c.max())) for c in pts.T]
