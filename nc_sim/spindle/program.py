"""A spindle's part of a program block [000 §2.4-§2.8]: G135-G137 feedforward, G167, the D
word's tool dynamics, M3/M4/M5/M19/G74/S/M40-M45, and the spindle stop at program end."""

from __future__ import annotations

from nc_sim.axis.state import Axis, ToolLimits
from nc_sim.blocks import SpindleCmd
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.spindle.control import SpindleControl
from nc_sim.units import AxisKind


def spindle_block(
    sp: SpindleControl, ax: Axis, sc: SpindleCmd, gear: int | None, block_id: int
) -> bool:
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
        sp.motion.set_feedforward(ax, ax.ff_weight)
    if sc.speed_rpm is not None and 167 not in sc.g and sc.m != 19:
        ax.override_suppressed = False
    if sc.default_dynamics:
        ax.tool_pending = ToolLimits()
        sp.motion.log(Code.EV_TOOL_DYNAMICS, ax.name, f"{ax.name} default dynamics pending")
    err: Event | None = None
    if sc.m in (3, 4):
        err = sp.endless(ax, sc.m, sc.speed_rpm, gear, block_id)
    elif sc.m == 5:
        sp.m5(ax)
    elif sc.m == 19:
        err = sp.position(ax, sc.pos_deg or 0.0, sc.direction, sc.speed_rpm, block_id)
    elif 74 in sc.g:
        err = sp.home(ax, block_id)
    elif sc.speed_rpm is not None:
        err = sp.speed(ax, sc.speed_rpm, gear, block_id)
    elif gear is not None:
        err = sp.gears.only(ax, gear, block_id)
    elif sc.g:  # G135-G137, G167 alone: the new weighting or override now
        sp.replan(ax)
    return err is None


def tool_dynamics(sp: SpindleControl, axes: list[Axis], number: int) -> None:
    """D word: the tool's dynamic limits go to its spindle at the next start [000 §2.8.5]."""
    cfg = sp.cfg
    pre = f"wz[{number}]."
    nr = int(cfg.tools.get(pre + "log_ax_nr_spdl", 0))
    sp.motion.log(Code.EV_TOOL_DYNAMICS, "", f"D{number}")
    if nr == 0:  # the tool carries no spindle dynamics
        return
    target = None
    for ax in axes:
        if ax.kind is AxisKind.SPINDLE and int(ax.cfg.raw("kopf.achs_nr")) == nr:
            target = ax
    if target is None:
        return
    vb_max = cfg.tool_eng(pre + "vb_max")
    a_max = cfg.tool_eng(pre + "a_max")
    target.tool_pending = ToolLimits(cfg.tool_eng(pre + "vb_min"), vb_max, a_max)


def program_end(sp: SpindleControl, axes: list[Axis]) -> None:
    """M30/M2: spindles stop only with the HLI flag "spindle stop at program end"."""
    sp.motion.log(Code.EV_PROGRAM_END)
    for ax in axes:
        if ax.kind is AxisKind.SPINDLE and ax.units["spindle_stop_at_program_end"]:
            sp.stop(ax)
