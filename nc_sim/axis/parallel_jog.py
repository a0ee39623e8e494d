"""G201, manual mode with parallel path interpolation [002 §2.6.2]: a path axis is jogged
while the program's path moves it.

The jog moves an offset that the kernel adds to the path's command position (S_MAN_*,
planned on the axis slot's own plan, which the path does not use). The jog has the manual
share of the axis' dynamics (hb_proz_a_max, hb_proz_v_max), the path keeps the rest
(ipo_proz_*, applied where the path is planned). When the path lets the axis go, the offset
becomes part of its position and a jog still running goes on as an ordinary one.
"""

from __future__ import annotations

import math

from nc_sim.axis.dynamics import parallel_manual_dynamics
from nc_sim.axis.motion import AxisMotion
from nc_sim.axis.state import Axis
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.profiles.plan import new_plan, position_move, velocity_change


def on_path(motion: AxisMotion, ax: Axis) -> bool:
    """The channel's path drives the axis now."""
    return int(motion.k.ist[ax.slot, L.I_ROLE]) == L.ROLE_PATH_AXIS


def refused(motion: AxisMotion, ax: Axis) -> Event | None:
    """Jogging a path axis while the path runs needs G201; G200 (the default) refuses it."""
    if motion.ctx.parallel_manual:
        return None
    return motion.fail(
        ax,
        Code.AXIS_BUSY,
        f"{ax.name} moves on the program's path: jogging it needs G201 "
        "(manual mode with parallel path interpolation)",
    )


def jog(
    motion: AxisMotion,
    ax: Axis,
    distance: float | None,
    direction: int,
    feed: float | None,
    override: float,
) -> None:
    """Jog by `distance` (mm | °), or towards the software limit in `direction` until
    `stop`, at the jog feed (unit/s; None: the manual share) times the `override` fraction."""
    k = motion.k
    s = ax.slot
    dyn, v_share = parallel_manual_dynamics(ax.cfg, ax.gear)
    v = (min(feed, v_share.value) if feed else v_share.value) * override
    offset = float(k.st[s, L.S_MAN_P])
    if distance is not None:
        target = offset + distance
    else:  # the limit less where the path is now: the kernel's limit monitor guards the rest
        path_point = float(k.st[s, L.S_P_CMD]) - offset
        limit = k.pr[s, L.P_SWE_POS if direction > 0 else L.P_SWE_NEG] if ax.homed else math.inf
        target = float(limit) - path_point if math.isfinite(limit) else direction * 1e9
    seg = new_plan()
    n = position_move(
        seg, offset, k.st[s, L.S_MAN_V], k.st[s, L.S_MAN_A], target, v, dyn.limits(), k.cycle_s
    )
    k.load_manual_plan(s, seg, n, target)
    ax.jog_on_path = n > 0


def stop(motion: AxisMotion, ax: Axis) -> None:
    """Release of the jog key (or feedhold): the offset brakes with the manual share."""
    k = motion.k
    s = ax.slot
    dyn, _ = parallel_manual_dynamics(ax.cfg, ax.gear)
    seg = new_plan()
    n = velocity_change(
        seg, 0, k.st[s, L.S_MAN_V], k.st[s, L.S_MAN_A], 0.0, dyn.limits(), k.cycle_s
    )
    k.load_manual_plan(s, seg, n, math.nan)
    ax.jog_on_path = n > 0
