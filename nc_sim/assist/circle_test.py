"""The circularity test (ISO 230-4): the NC runs a G02/G03 circle in a plane about where the
axes stand, with overrun arcs before and after so the measured turn is at constant feed, and
records commanded and actual positions of the turn, counter-clockwise and clockwise. What it
found (nc_sim/assist/circle_analysis.py): the ISO figures, the ellipse, the reversal spikes,
backlash, the effective kv of both axes and the cause in words.

Measured either as the standard's annex E does, with the NC's own feedback (the position
the measuring system gives), or as a ballbar does, on the machine's true path: only that
sees what lies outside the position loop (backlash behind a motor encoder, a wrong scale).
The true path is the simulated machine's (R_P_TRUE); a real machine needs the ballbar.

The program is the channel's own: the axes must be path axes of the plane, at rest, with no
program running. A program the channel had loaded is loaded again afterwards.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import dataclass

import numpy as np

from nc_sim.assist.circle_analysis import Turn, analyse
from nc_sim.assist.procedure import Procedure, Wait, on_copy
from nc_sim.assist.result import ExperimentError, Result
from nc_sim.axis.state import Axis
from nc_sim.channel.modal import CENTRE_LETTER, PLANES
from nc_sim.commands import Accepted, CycleStart, Invalid, ProgramLoad, ProgramStop, Refused
from nc_sim.config import MachineConfig
from nc_sim.kernel import layout as L
from nc_sim.machine.channel_ops import PROGRAM_ACTIVE
from nc_sim.machine.machine import Machine
from nc_sim.snapshot import AxisState, ChannelState
from nc_sim.units import MM_MIN_PER_MM_S, AxisKind

BOTH, CW, CCW = 0, 2, 3  # both directions, G02, G03
NC_FEEDBACK, TRUE_PATH = 1, 2
MAX_TURN_S = 120.0  # one revolution longer than this: a larger feed or a smaller radius
CHUNK_CYCLES = 100  # the channel's state is checked this often
REST_LIMIT_S = 30.0  # after its planned time a circle not at rest by then has a fault
DIGITS = 5  # program coordinates to 0.01 µm: far below what the figures resolve


def circle_test_experiment(
    cfg: MachineConfig,
    plane: int = 18,
    radius_mm: float = 10.0,
    feed_mm_min: float = 1000.0,
    direction: int = BOTH,
    start_deg: float = 0.0,
    overrun_deg: float = 90.0,
    path: int = NC_FEEDBACK,
) -> Result:
    """`circle_test` on a fresh copy of the machine `cfg` describes."""
    return on_copy(
        cfg,
        lambda m: circle_test(
            m, plane, radius_mm, feed_mm_min, direction, start_deg, overrun_deg, path
        ),
    )


@dataclass(frozen=True)
class _Plan:
    """One direction's program and the line of its measured turn."""

    g: int
    text: str
    turn_line: int


def _point(centre: tuple[float, float], radius: float, deg: float) -> tuple[float, float]:
    t = math.radians(deg)
    return centre[0] + radius * math.cos(t), centre[1] + radius * math.sin(t)


def _program(
    plane: int,
    centre: tuple[float, float],
    radius: float,
    feed: float,
    g: int,
    start_deg: float,
    overrun_deg: float,
) -> _Plan:
    """G{plane}: radially out to the overrun's start, the overrun arc up to `start_deg`, the
    full turn, the overrun arc beyond it, radially back to the centre. G03 turns from the
    plane's first axis towards its second (counter-clockwise as the angles here count)."""
    a, b, _ = PLANES[plane]
    way = 1.0 if g == CCW else -1.0

    def at(deg: float) -> str:
        pa, pb = _point(centre, radius, deg)
        return f"{a}{pa:.{DIGITS}f} {b}{pb:.{DIGITS}f}"

    def arc(from_deg: float, to_deg: float) -> str:
        pa, pb = _point(centre, radius, from_deg)
        ia, ib = centre[0] - pa, centre[1] - pb
        offsets = f"{CENTRE_LETTER[a]}{ia:.{DIGITS}f} {CENTRE_LETTER[b]}{ib:.{DIGITS}f}"
        return f"G{g:02d} {at(to_deg)} {offsets}"

    lead = start_deg - way * overrun_deg
    lines = [f"G{plane} G90 F{feed:g}", f"G01 {at(lead)}"]
    if overrun_deg > 0.0:
        lines.append(arc(lead, start_deg))
    lines.append(arc(start_deg, start_deg))  # the whole turn: its end is its start
    turn_line = len(lines)
    if overrun_deg > 0.0:
        lines.append(arc(start_deg, start_deg + way * overrun_deg))
    lines += [f"G01 {a}{centre[0]:.{DIGITS}f} {b}{centre[1]:.{DIGITS}f}", "M30"]
    return _Plan(g, "\n".join(lines) + "\n", turn_line)


def plane_axes(m: Machine, plane: int) -> tuple[Axis, Axis]:
    """The plane's two axes of `m`: linear path axes (ExperimentError naming what is not)."""
    if plane not in PLANES:
        raise ExperimentError(f"plane: G17, G18 or G19, not G{plane}")
    names = PLANES[plane][:2]
    missing = [n for n in names if n not in m.channel.axes]
    if missing:
        raise ExperimentError(
            f"G{plane} needs the path axes {' and '.join(names)}: {', '.join(missing)} "
            f"is not one of this machine's ({', '.join(m.channel.axes)})"
        )
    axes = tuple(m.axis(n) for n in names)
    for ax in axes:
        if ax.kind is not AxisKind.LINEAR:
            raise ExperimentError(f"{ax.name} is not a linear axis: the circle needs two")
    return axes[0], axes[1]


def circle_test(
    m: Machine,
    plane: int = 18,
    radius_mm: float = 10.0,
    feed_mm_min: float = 1000.0,
    direction: int = BOTH,
    start_deg: float = 0.0,
    overrun_deg: float = 90.0,
    path: int = NC_FEEDBACK,
) -> Procedure:
    """A circle of `radius_mm` at `feed_mm_min` in G`plane` about where the axes stand, from
    `start_deg` (from the plane's first axis towards its second) with `overrun_deg` of arc
    before and after the measured turn; counter-clockwise (G03), clockwise (G02) or both
    (`direction` 0), measured on the NC's feedback or the true path (`path`)."""
    axes = plane_axes(m, plane)
    ch = m.channel
    if ch.state in PROGRAM_ACTIVE or ch.progress.mdi:
        raise ExperimentError("a program or MDI block runs: the circle needs the channel idle")
    moving = [ax.name for ax in axes if ax.state is not AxisState.STANDSTILL]
    if moving:
        raise ExperimentError(f"{', '.join(moving)} must stand still to start")
    turn_s = 2.0 * math.pi * radius_mm / (feed_mm_min / MM_MIN_PER_MM_S)
    if turn_s > MAX_TURN_S:
        raise ExperimentError(
            f"one turn of R{radius_mm:g} at F{feed_mm_min:g} takes {turn_s:.0f} s (at most "
            f"{MAX_TURN_S:g} s): a higher feed or a smaller radius"
        )
    centre = (float(m.k.st[axes[0].slot, L.S_P_CMD]), float(m.k.st[axes[1].slot, L.S_P_CMD]))
    order = (CCW, CW) if direction == BOTH else (direction,)
    plans = [
        _program(plane, centre, radius_mm, feed_mm_min, g, start_deg, overrun_deg) for g in order
    ]
    one_s = turn_s * (1.0 + 2.0 * overrun_deg / 360.0) + 2.0 * radius_mm / (
        feed_mm_min / MM_MIN_PER_MM_S
    )
    planned_s = len(plans) * (one_s + 1.0)
    column = L.R_P_ACT if path == NC_FEEDBACK else L.R_P_TRUE
    saved = ch.progress.program
    turns: list[Turn] = []
    try:
        for plan in plans:
            turn = yield from _run(m, axes, plan, column, planned_s)
            turns.append(turn)
    except GeneratorExit:
        if not m.estop:
            m.submit(ProgramStop())
        raise
    finally:
        if saved is not None and ch.state not in PROGRAM_ACTIVE:
            m.submit(ProgramLoad(saved.name, saved.text))
    inputs: dict[str, float | int | str] = {
        "axis": f"{axes[0].name}{axes[1].name}",
        "plane": plane,
        "radius_mm": radius_mm,
        "feed_mm_min": feed_mm_min,
        "direction": direction,
        "start_deg": start_deg,
        "overrun_deg": overrun_deg,
        "path": path,
    }
    return analyse(axes, turns, radius_mm, feed_mm_min, path == TRUE_PATH, inputs)


def _run(
    m: Machine,
    axes: tuple[Axis, Axis],
    plan: _Plan,
    column: int,
    planned_s: float,
) -> Generator[Wait, np.ndarray, Turn]:
    """Run one direction's program; the measured turn's commanded and actual positions."""
    out = m.submit(ProgramLoad(f"circle G{plan.g:02d}", plan.text))
    if isinstance(out, Accepted):
        out = m.submit(CycleStart())
    if not isinstance(out, Accepted):
        why = out.message if isinstance(out, Invalid) else str(out)
        if isinstance(out, Refused):
            why = out.error.message
        raise ExperimentError(f"the circle was refused: {why}")
    ch = m.channel
    line_col = (m.channel_slot, L.R_LINE)
    cmd: list[np.ndarray] = []
    act: list[np.ndarray] = []
    lag: list[np.ndarray] = []
    vel: list[np.ndarray] = []
    slots = [ax.slot for ax in axes]
    waited = 0.0
    phase = f"G{plan.g:02d}: the circle runs"
    while True:
        rec = yield Wait(CHUNK_CYCLES, phase, planned_s)
        waited += rec.shape[0] * m.k.cycle_s
        on = rec[:, line_col[0], line_col[1]] == plan.turn_line
        if np.any(on):
            rows = rec[on][:, slots]
            cmd.append(rows[:, :, L.R_P_CMD])
            act.append(rows[:, :, column])
            lag.append(rows[:, :, L.R_LAG])
            vel.append(rows[:, :, L.R_V_CMD])
        if ch.state is ChannelState.ERROR:
            error = ch.aborted_with
            raise ExperimentError(
                "the circle ended in a job error"
                + (f": {error.message}" if error is not None else "")
            )
        ended = ch.state not in PROGRAM_ACTIVE and not ch.braking
        if ended and all(ax.state is AxisState.STANDSTILL for ax in axes):
            break
        if waited > planned_s + REST_LIMIT_S:
            raise ExperimentError("the circle did not end in its time: a fault of the axes")
    if not cmd:
        raise ExperimentError("the measured turn was never reached (a program stop?)")
    return Turn(
        plan.g,
        np.concatenate(cmd),
        np.concatenate(act),
        np.concatenate(lag),
        np.concatenate(vel),
        m.k.cycle_s,
    )
