"""The signals a machine records every cycle, by name: `<axis>.<signal>` in display units.

One table serves the headless trace (CSV columns) and live telemetry (websocket frames), so a
name means the same thing everywhere. Each signal is a column of the kernel record scaled to
its display unit.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from nc_sim.kernel import layout as L
from nc_sim.units import RPM_TO_DEG_S, AxisKind


@dataclass(frozen=True)
class Signal:
    """One recorded signal: which kernel slot and record column, and how to scale it."""

    name: str
    axis: str
    slot: int
    column: int
    scale: float
    unit: str
    kind: str  # "float", "bool" or "enum" (state, gear, loop mode, job error code)


def _axis_signals(name: str, kind: AxisKind, slot: int, rotary_capable: bool) -> list[Signal]:
    u = "mm" if kind is AxisKind.LINEAR else "deg"
    spindle = kind is AxisKind.SPINDLE
    rows: list[tuple[str, int, float, str, str]] = []
    if spindle:
        rows += [
            ("speed_cmd_rpm", L.R_V_CMD, 1.0 / RPM_TO_DEG_S, "rpm", "float"),
            ("speed_act_rpm", L.R_V_ACT, 1.0 / RPM_TO_DEG_S, "rpm", "float"),
        ]
    rows += [
        (f"pos_cmd_{u}", L.R_P_CMD, 1.0, u, "float"),
        (f"pos_act_{u}", L.R_P_ACT, 1.0, u, "float"),
        (f"lag_{u}", L.R_LAG, 1.0, u, "float"),
    ]
    if not spindle:
        rows += [
            # the simulated machine's true position (a laser's, a ballbar's reading)
            (f"pos_true_{u}", L.R_P_TRUE, 1.0, u, "float"),
            (f"vel_cmd_{u}_min", L.R_V_CMD, 60.0, f"{u}/min", "float"),
            (f"vel_act_{u}_min", L.R_V_ACT, 60.0, f"{u}/min", "float"),
        ]
    if u == "deg":
        rows.append(("accel_cmd_deg_s2", L.R_A_CMD, 1.0, "deg/s²", "float"))
    else:
        rows.append(("acc_cmd_mm_s2", L.R_A_CMD, 1.0, "mm/s²", "float"))
    if spindle:
        rows += [
            ("speed_reached", L.R_SPEED_REACHED, 1.0, "", "bool"),
            ("stopped", L.R_STOPPED, 1.0, "", "bool"),
            ("gear", L.R_GEAR, 1.0, "", "enum"),
            ("speed_monitoring_active", L.R_MON_ACTIVE, 1.0, "", "bool"),
            ("speed_monitoring_invalid", L.R_MON_INVALID, 1.0, "", "bool"),
            ("open_loop", L.R_OPEN_LOOP, 1.0, "", "enum"),  # 1 control limit, 2 speed control
            ("override_pct", L.R_OVERRIDE, 100.0, "%", "float"),
        ]
    if rotary_capable:  # 1 while the spindle is the rotary axis C (named S1 all the same)
        rows.append(("rotary_mode", L.R_ROTARY_MODE, 1.0, "", "bool"))
    rows += [  # 003 §4.2: HOMED, INPOS, MVPOS/MVNEG, READY (N_act = N_comm, N_act = 0 above)
        ("homed", L.R_HOMED, 1.0, "", "bool"),
        ("in_position", L.R_IN_POS, 1.0, "", "bool"),
        ("mvpos", L.R_MVPOS, 1.0, "", "bool"),
        ("mvneg", L.R_MVNEG, 1.0, "", "bool"),
        ("ready", L.R_READY, 1.0, "", "bool"),
        ("da_digits", L.R_DA, 1.0, "digits", "float"),
        ("state", L.R_STATE, 1.0, "", "enum"),
        ("job_error", L.R_JOB_ERROR, 1.0, "", "enum"),
    ]
    return [Signal(f"{name}.{s}", name, slot, c, f, unit, k) for s, c, f, unit, k in rows]


class SlottedAxis(Protocol):
    """What the signal table needs of an axis: its name, its kind and its kernel slot (a
    machine's `Axis`, or its description in a process without the machine)."""

    @property
    def name(self) -> str: ...

    @property
    def kind(self) -> AxisKind: ...

    @property
    def slot(self) -> int: ...


CHANNEL = "CH"  # the signals' "axis" name for the channel


def channel_signals(slot: int) -> list[Signal]:
    """The channel's signals: program state, current block line, path velocity."""
    rows = [
        ("state", L.R_STATE, 1.0, "", "enum"),  # nc_sim.snapshot.ChannelState
        ("block_line", L.R_LINE, 1.0, "", "enum"),
        ("path_feed_mm_min", L.R_V_CMD, 60.0, "mm/min", "float"),
    ]
    return [Signal(f"{CHANNEL}.{n}", CHANNEL, slot, c, f, u, k) for n, c, f, u, k in rows]


def machine_signals(
    axes: Iterable[SlottedAxis],
    channel_slot: int | None = None,
    rotary_spindle: str | None = None,
) -> list[Signal]:
    """Every signal of a machine's axes (`Machine.axes`), axis by axis, in a stable order,
    then the channel's (`Machine.channel_slot`). `rotary_spindle` (`Machine.rotary_spindle`)
    names the main spindle with rotary-axis capability: it has `rotary_mode` as well, under
    its configured name in either mode, so a recording's columns never change."""
    out: list[Signal] = []
    for ax in axes:
        out += _axis_signals(ax.name, ax.kind, ax.slot, ax.name == rotary_spindle)
    if channel_slot is not None:
        out += channel_signals(channel_slot)
    return out


def signal_columns(signals: list[Signal], rec: np.ndarray) -> np.ndarray:
    """Samples of the given signals from a kernel record (cycles × slots × R_COLS), as a
    signals × cycles float64 array in display units."""
    out = np.empty((len(signals), rec.shape[0]))
    for i, s in enumerate(signals):
        np.multiply(rec[:, s.slot, s.column], s.scale, out=out[i])
    return out


def signal_rows(signals: list[Signal], rec: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """`signal_columns` of the given rows of a record only (`rows`: row indices), reading
    just the signals' own slots and columns (a ring read copies a few values per cycle, not
    every column of every slot)."""
    slots = np.fromiter((s.slot for s in signals), np.intp, len(signals))
    cols = np.fromiter((s.column for s in signals), np.intp, len(signals))
    scale = np.fromiter((s.scale for s in signals), np.float64, len(signals))
    out: np.ndarray = rec[rows[None, :], slots[:, None], cols[:, None]] * scale[:, None]
    return out
