"""The spindle's side of G33 thread cutting and G63 tapping [000 §2.8.6-§2.8.7].

`start_thread` couples a thread element to an endlessly rotating spindle: the path waits for
the next zero passage plus S.OFFSET, then follows the spindle's actual angle (nc_sim/channel/
coupling.py gives the law). `start_tap` starts the spindle's own position move through the
hole (it leads, through its ramp-up and ramp-down) with the path coupled to its actual angle;
its acceleration and speed are capped so the path axes keep theirs. Both check what the
manual requires and answer with the job error when they cannot run.
"""

from __future__ import annotations

from nc_sim.axis.dynamics import Motion
from nc_sim.axis.params import speed_controlled
from nc_sim.axis.state import Axis
from nc_sim.channel.coupling import coupling_angle, ramp_length, thread_ramps
from nc_sim.channel.geometry import Element
from nc_sim.errors import Code
from nc_sim.events import Event
from nc_sim.kernel import layout as L
from nc_sim.profiles.plan import LIM_A_ACC, LIM_A_ACC2, LIM_A_DEC, LIM_A_DEC2
from nc_sim.snapshot import AxisState
from nc_sim.spindle.control import SpindleControl
from nc_sim.units import RPM_TO_DEG_S

MM_MIN = 60.0  # mm/s -> mm/min


def start_thread(
    sp: SpindleControl, ax: Axis, e: Element, v_cap: float, a_acc: float, a_dec: float
) -> Event | None:
    """Couple the G33 element `e` to the rotating spindle `ax`; `v_cap` (mm/s), `a_acc` and
    `a_dec` (mm/s²) are what the path axes allow along it."""
    c = e.coupling
    assert c is not None
    motion = sp.motion
    st = motion.k.st[ax.slot]
    where = "G33"
    if ax.cfg.flag("sim.sensorless"):
        return motion.fail(
            ax, Code.THREAD_NOT_POSSIBLE, f"{where}: {ax.name} has no encoder", line=e.line
        )
    if ax.state is not AxisState.ENDLESS or motion.loop_mode(ax) == L.LOOP_CONTROL_LIMIT:
        why = (
            "rotates above its control limit (no position)"
            if ax.state is AxisState.OPEN_LOOP
            else f"does not rotate ({ax.state.name.lower()}): M3/M4 first"
        )
        return motion.fail(ax, Code.THREAD_NOT_POSSIBLE, f"{where}: {ax.name} {why}", line=e.line)
    w = max(abs(float(st[L.S_V_CMD])), abs(float(st[L.S_V_GOAL])))
    v_path = c.k_mm_per_deg * w
    if v_path > v_cap * (1.0 + 1e-9):
        return motion.fail(
            ax,
            Code.THREAD_NOT_POSSIBLE,
            f"{where}: {w / RPM_TO_DEG_S:g} rpm × {c.pitch_mm:g} mm needs "
            f"{v_path * MM_MIN:.1f} mm/min, the axes allow {v_cap * MM_MIN:.1f} mm/min",
            line=e.line,
        )
    if thread_ramps(c, e.length, w, a_acc, a_dec) is None:
        return motion.fail(
            ax,
            Code.THREAD_NOT_POSSIBLE,
            f"{where}: the thread ({e.length:.3f} mm) is shorter than its lead-in and "
            f"lead-out at {w / RPM_TO_DEG_S:g} rpm ({ramp_length(c):.3f} mm)",
            line=e.line,
        )
    c.slot = ax.slot
    c.direction = 1 if float(st[L.S_V_CMD]) >= 0 else -1
    # the zero passage must lie ahead: at least two cycles of rotation away
    margin = 2.0 * w * motion.k.cycle_s
    c.theta0_deg = coupling_angle(float(st[L.S_P_ACT]), c.direction, c.offset_deg, margin)
    motion.log(
        Code.EV_COUPLED,
        ax.name,
        f"G33: waits for {ax.name} at {c.theta0_deg % 360.0:g}° "
        f"(offset {c.offset_deg:g}°), lead {c.pitch_mm:g} mm",
        line=e.line,
    )
    return None


def start_tap(
    sp: SpindleControl, ax: Axis, e: Element, v_cap: float, a_acc: float, a_dec: float
) -> Event | None:
    """Start the G63 element `e`: the spindle `ax` turns through the hole, the path follows."""
    c = e.coupling
    assert c is not None
    motion = sp.motion
    k = motion.k
    where = "G63"
    if speed_controlled(ax.cfg):
        return motion.fail(
            ax,
            Code.TAPPING_NOT_POSSIBLE,
            f"{where}: {ax.name} cannot be position-controlled",
            line=e.line,
        )
    if ax.state is not AxisState.STANDSTILL or not k.ist[ax.slot, L.I_STOPPED]:
        return motion.fail(
            ax,
            Code.TAPPING_NOT_POSSIBLE,
            f"{where}: {ax.name} must stand ({ax.state.name.lower()}): M5 or M19 first",
            line=e.line,
        )
    err = motion.check_motion(ax)
    if err is not None:
        return err
    kd = c.k_mm_per_deg
    w_prog = abs(c.speed_rpm) * RPM_TO_DEG_S
    if kd * w_prog > v_cap * (1.0 + 1e-9):
        return motion.fail(
            ax,
            Code.TAPPING_NOT_POSSIBLE,
            f"{where}: F{kd * w_prog * MM_MIN:g} above what the "
            f"axes allow ({v_cap * MM_MIN:.1f} mm/min)",
            line=e.line,
        )
    # the spindle override acts, within the spindle's and (through the pitch) the axes' limits
    w = min(w_prog * sp.override(ax), sp.v_max(ax), v_cap / kd)
    c.slot = ax.slot
    c.direction = 1 if c.speed_rpm > 0 else -1
    c.theta0_deg = float(k.st[ax.slot, L.S_P_CMD])
    lim = sp.limits(ax).copy()
    # the spindle leads: its acceleration is capped so the path axes keep theirs
    caps = ((LIM_A_ACC, a_acc), (LIM_A_ACC2, a_acc), (LIM_A_DEC, a_dec), (LIM_A_DEC2, a_dec))
    for col, a_path in caps:
        if lim[col] > 0:
            lim[col] = min(float(lim[col]), a_path / kd)
    sp.cancel_task(ax)
    sp.switch_back(ax)
    ax.target = c.theta0_deg + c.direction * e.length / kd
    ax.motion = Motion.FEED
    ax.block_id = 0  # a job error of the spindle stops the program
    motion.set_state(ax, AxisState.MOVING)
    motion.log(
        Code.EV_COUPLED,
        ax.name,
        f"G63: {ax.name} {c.speed_rpm:g} rpm, pitch {c.pitch_mm:g} mm",
        line=e.line,
    )
    motion.plan_move(ax, lim, w, f"G63 tapping of line {e.line}")
    return None
