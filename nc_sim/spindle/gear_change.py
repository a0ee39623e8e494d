"""Gear stages M40-M45 of the main spindle [000 §2.6, P-CHAN-00052]: the stage for a speed
(the rule is gears.py), the change (a `SpindleTask` to the change position, M4x to the PLC,
its acknowledgement, the new gear record) and what the spindle runs again afterwards."""

from __future__ import annotations

from nc_sim.axis.params import push_params, speed_controlled
from nc_sim.axis.state import Axis
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.snapshot import AxisState
from nc_sim.spindle.gears import (
    GearChoice,
    GearRange,
    m_of,
    range_table,
    select_gear,
    spindle_index,
)
from nc_sim.spindle.interface import SpindleOps
from nc_sim.spindle.task import SpindleTask, TaskPhase
from nc_sim.units import RPM_TO_DEG_S


class GearStages:
    """The gear stages of the spindles of one channel."""

    def __init__(self, sp: SpindleOps) -> None:
        self.sp = sp

    def table(self, ax: Axis) -> tuple[int, list[GearRange]] | None:
        """(spindel index, ranges) when gear change applies to this spindle."""
        cfg = self.sp.cfg
        if not cfg.channel_raw("main_spindle_gear_change") or ax.name != self.sp.cfg.main_spindle:
            return None
        i = spindle_index(self.sp.cfg, ax.name)
        if i is None:
            return None
        return i, range_table(cfg, i)

    def choose(self, ax: Axis, rpm: float, programmed: int | None) -> GearChoice:
        gt = self.table(ax)
        if gt is None:
            if programmed is not None:
                return GearChoice(None, Code.GEAR_CHANGE_OFF, f"M{m_of(programmed)}")
            return self.within_vb_max(ax, rpm) or GearChoice(ax.gear)
        i, table = gt
        automatic = bool(self.sp.cfg.channel_raw(f"spindel[{i}].autom_range"))
        way = int(self.sp.cfg.channel_raw(f"spindel[{i}].range_way"))
        return select_gear(table, ax.gear, rpm, automatic, way, programmed)

    def refused(self, ax: Axis, choice: GearChoice, programmed: int | None) -> Event:
        """The job error of a refused gear choice, with the programmed M40-M45 if any."""
        assert choice.error is not None
        detail = choice.detail or (f"M{m_of(programmed)}" if programmed is not None else "")
        if programmed is None:
            return self.sp.motion.fail(ax, choice.error, detail)
        return self.sp.motion.fail(ax, choice.error, detail, m=m_of(programmed), gear=programmed)

    def within_vb_max(self, ax: Axis, rpm: float) -> GearChoice | None:
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

    def start(
        self, ax: Axis, gear: int, resume: tuple[int, float] | None, block_id: int | None
    ) -> None:
        """Gear change: to the change position at vb_eilgang, M4x to the PLC, wait, adopt."""
        self.sp.cancel_task(ax)
        pos = ax.cfg.eng("getriebe.getr_schalt_pos", ax.gear) % 360.0
        speed = ax.cfg.eng("getriebe.vb_eilgang", ax.gear)
        task = SpindleTask(self.sp, ax, "gear", pos, self.sp.preferred(ax), speed, gear, resume)
        ax.sequence, ax.block_id = task, block_id
        self.sp.motion.log(Code.EV_M_START, ax.name, f"M{m_of(gear)}", m=m_of(gear), gear=gear)
        self.sp.motion.log(
            Code.EV_GEAR_CHANGE_START,
            ax.name,
            f"{ax.name} gear change M{m_of(ax.gear)} -> M{m_of(gear)}",
            gear=gear,
        )
        if not (ax.homed or self.sp.auto_homing(ax)) or speed_controlled(ax.cfg):
            # no position to go to: change at standstill where the spindle stops
            task.phase = TaskPhase.STOP
            self.sp.set_state(ax, AxisState.GEAR_CHANGE)
            self.sp.velocity(ax, 0.0)
            return
        task.advance()

    def acknowledged(self, ax: Axis) -> None:
        """The PLC has changed the gear: adopt the new record and resume."""
        t = ax.sequence
        if not isinstance(t, SpindleTask) or t.kind != "gear":
            return
        old = ax.gear
        ax.gear = t.gear
        push_params(self.sp.motion.k, ax)
        self.sp.motion.log(
            Code.EV_GEAR_CHANGED,
            ax.name,
            f"{ax.name} gear M{m_of(old)} -> M{m_of(ax.gear)}",
            gear=ax.gear,
        )
        ax.sequence = None
        ax.block_id = None
        self.sp.set_state(ax, AxisState.STANDSTILL)
        if t.resume is not None:
            m, rpm = t.resume
            self.sp.endless(ax, m, rpm)

    def timed_out(self, ax: Axis, error: Event) -> None:
        """No acknowledgement of the M40-M45 (job error `error`): the change ends in error."""
        self.sp.motion.set_job_error(ax, error)
        t = ax.sequence
        if isinstance(t, SpindleTask) and t.kind == "gear":
            self.sp.cancel_task(ax)
            self.sp.set_state(ax, AxisState.ERROR)

    def only(self, ax: Axis, gear: int, block_id: int | None) -> Event | None:
        """M40-M45 without S (MDI or the gear buttons): the stage is checked against the speed
        it will run with, as `M4x S..` is: the programmed S of a rotating spindle; at
        standstill there is none, the next S is checked."""
        if self.table(ax) is None:
            return self.refused(ax, GearChoice(None, Code.GEAR_CHANGE_OFF), gear)
        resume = self.resume(ax)
        if resume is not None:
            choice = self.choose(ax, resume[1], gear)
            if choice.error is not None:
                return self.refused(ax, choice, gear)
        if gear == ax.gear:
            return None
        err = self.sp.motion.check_motion(ax)
        if err:
            return err
        self.start(ax, gear, resume, block_id)
        return None

    def resume(self, ax: Axis) -> tuple[int, float] | None:
        """What a rotating spindle runs again after a gear change: (M3|M4, rpm)."""
        if ax.state not in (AxisState.ENDLESS, AxisState.OPEN_LOOP):
            return None
        return (3 if ax.speed_prog > 0 else 4, abs(ax.speed_prog) / RPM_TO_DEG_S)
