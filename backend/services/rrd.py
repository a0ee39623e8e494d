"""Rerun recordings (.rrd) of captures and of continuous recording.

Entity paths are `<machine>/<axis>/<signal>`. Every block goes out with `send_columns` on two
indexes: the `sim_time` timeline (simulated seconds since power-on) and the `cycle` sequence.
Numeric signals are `Scalars`; the operating state is text (`TextLog` at each change, with
the state's name); events and job errors are text logs at `<machine>/events`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import rerun as rr

from nc_sim.events import Event
from nc_sim.snapshot import AxisState

APP_ID = "inbetrieb"


def entity(machine: str, signal: str) -> str:
    """`S1.speed_act_rpm` of machine `demo` -> `demo/S1/speed_act_rpm` (a drive signal
    `X.drive.torque_nm` -> `demo/X/drive/torque_nm`)."""
    return f"{machine}/{signal.replace('.', '/')}"


def state_name(code: float) -> str:
    try:
        return AxisState(int(code)).name
    except ValueError:
        return f"STATE_{int(code)}"


def _indexes(cycles: np.ndarray, cycle_s: float) -> list[rr.TimeColumn]:
    return [
        rr.TimeColumn("sim_time", duration=cycles * cycle_s),
        rr.TimeColumn("cycle", sequence=cycles),
    ]


@dataclass
class RrdWriter:
    """Logs blocks of samples of one machine's signals to a recording stream."""

    stream: rr.RecordingStream
    machine: str
    signals: Sequence[str]
    cycle_s: float
    last_state: dict[str, float] = field(default_factory=dict)  # state text only on change

    def block(self, first_cycle: int, data: np.ndarray) -> None:
        """Samples of cycles first_cycle … (signals × count), one column batch per signal."""
        if data.shape[1] == 0:
            return
        cycles = np.arange(first_cycle, first_cycle + data.shape[1], dtype=np.int64)
        for name, y in zip(self.signals, data, strict=True):
            path = entity(self.machine, name)
            if name.endswith(".state"):
                self._states(path, name, cycles, y)
                continue
            self.stream.send_columns(
                path, indexes=_indexes(cycles, self.cycle_s), columns=rr.Scalars.columns(scalars=y)
            )

    def _states(self, path: str, name: str, cycles: np.ndarray, y: np.ndarray) -> None:
        prev = np.r_[self.last_state.get(name, np.nan), y[:-1]]
        at = np.flatnonzero(y != prev)
        self.last_state[name] = float(y[-1])
        if at.size:
            self.stream.send_columns(
                path,
                indexes=_indexes(cycles[at], self.cycle_s),
                columns=rr.TextLog.columns(text=[state_name(v) for v in y[at]]),
            )

    def events(self, events: Sequence[Event]) -> None:
        """Events and job errors as text logs (ERROR level for job errors)."""
        if not events:
            return
        cycles = np.array([e.cycle for e in events], dtype=np.int64)
        text = [f"{e.code} {e.axis + ': ' if e.axis else ''}{e.message}" for e in events]
        level = ["ERROR" if e.error else "INFO" for e in events]
        self.stream.send_columns(
            f"{self.machine}/events",
            indexes=_indexes(cycles, self.cycle_s),
            columns=rr.TextLog.columns(text=text, level=level),
        )


def open_stream(path: Path, recording_id: str, machine: str, about: str) -> rr.RecordingStream:
    """A recording stream saving to `path`, with a static description of what it holds."""
    stream = rr.RecordingStream(APP_ID, recording_id=recording_id, send_properties=False)
    stream.save(path)
    stream.log(machine, rr.TextDocument(about, media_type=rr.MediaType.MARKDOWN), static=True)
    return stream


def close_stream(stream: rr.RecordingStream) -> None:
    """Write everything out and close the file."""
    stream.flush()
    stream.disconnect()


def write_capture(
    path: Path,
    recording_id: str,
    machine: str,
    about: str,
    signals: Sequence[str],
    first_cycle: int,
    cycle_s: float,
    data: np.ndarray,
    events: Sequence[Event],
) -> None:
    """One capture as an .rrd file."""
    tmp = path.with_suffix(".part")
    stream = open_stream(tmp, recording_id, machine, about)
    w = RrdWriter(stream, machine, signals, cycle_s)
    w.block(first_cycle, data)
    w.events(events)
    close_stream(stream)
    tmp.replace(path)
