"""A spindle's part of a block [000 §2.4-§2.8]: its canonical calls (M3/M4/M5/M19/S with
M40-M45, G135-G137 feedforward, G167), the D word's tool dynamics, and the spindle stop at
program end."""

from __future__ import annotations

from nc_sim.axis.state import Axis, ToolLimits
from nc_sim.channel import canon
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.spindle.control import SpindleControl
from nc_sim.units import AxisKind

SpindleCall = (
    canon.SpindleOn
    | canon.SpindleOff
    | canon.SpindleOrient
    | canon.SpindleSpeed
    | canon.SpindleSettings
)


def spindle_call(sp: SpindleControl, ax: Axis, call: SpindleCall, block_id: int) -> Event | None:
    """Carry out one spindle call of a block on `ax`; the job error when it was refused."""
    match call:
        case canon.SpindleSettings():
            _settings(sp, ax, call)
            return None
        case canon.SpindleOn():
            if call.speed_rpm is not None:
                ax.override_suppressed = call.override_off
            return sp.endless(ax, call.m, call.speed_rpm, call.gear, block_id)
        case canon.SpindleOff():
            sp.m5(ax)
            return None
        case canon.SpindleOrient():
            return sp.position(ax, call.pos_deg or 0.0, call.direction, call.speed_rpm, block_id)
        case canon.SpindleSpeed():
            ax.override_suppressed = call.override_off
            return sp.speed(ax, call.speed_rpm, call.gear, block_id)


def _settings(sp: SpindleControl, ax: Axis, call: canon.SpindleSettings) -> None:
    """G135-G137 feedforward, G167 override off, DEFAULT_DYNAMIC_DATA."""
    if call.feedforward == 135:
        ax.ff_weight = ax.ff_set
    elif call.feedforward == 136:
        if call.ff_weight_pct is not None:
            ax.ff_set = call.ff_weight_pct / 100.0
        if ax.ff_weight > 0:
            ax.ff_weight = ax.ff_set
    elif call.feedforward == 137:
        ax.ff_weight = 0.0
    if call.feedforward is not None:
        sp.motion.set_feedforward(ax, ax.ff_weight)
    if call.override_off:  # until the next programmed speed [000 §2.4.1]
        ax.override_suppressed = True
    if call.default_dynamics:
        ax.tool_pending = ToolLimits()
        sp.motion.log(Code.EV_TOOL_DYNAMICS, ax.name, f"{ax.name} default dynamics pending")
    if call.feedforward is not None or call.override_off:
        sp.replan(ax)  # the new weighting or override now


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
