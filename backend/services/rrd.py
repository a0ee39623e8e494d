"""Rerun recordings (.rrd) of captures and of continuous recording.

Each axis' numeric signals are one entity, `<machine>/<axis>`, a batch of scalars per cycle
named by a static `SeriesLines` (a drive's at `<machine>/<axis>/drive`): one time column per
axis and block instead of one per signal, so a 16-channel recording costs about 9.5 bytes per
sample (float64 values and the shared index). The index is the `sim_time` timeline
(simulated seconds since power-on; the cycle is sim_time / cycle_s). The operating state is
text (`TextLog` at each change, with the state's name) at `<machine>/<axis>/state`; events
and job errors are text logs at `<machine>/events`. Every file opens with a default
blueprint: per axis its speed and lag, and its position (the same entity, its series split
by visibility), the events beside them, the description logged once.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from nc_sim.events import Event
from nc_sim.snapshot import AxisState

APP_ID = "inbetrieb"
_SPEED_LAG = ("vel_", "speed_", "lag_")  # a signal's quantity by its name (nc_sim/signals.py)
_POSITION = ("pos_",)


def _split(signal: str) -> tuple[str, str]:
    """(axis, name) of a signal: `X.drive.torque_nm` -> (`X.drive`, `torque_nm`); a column of
    an imported file without an axis is the machine's own (`signals`)."""
    axis, _, name = signal.rpartition(".")
    return axis or "signals", name


def entity(machine: str, signal: str) -> str:
    """The entity of a signal's axis: `S1.speed_act_rpm` of machine `demo` -> `demo/S1` (a
    drive signal `X.drive.torque_nm` -> `demo/X/drive`)."""
    return f"{machine}/{_split(signal)[0].replace('.', '/')}"


def state_name(code: float) -> str:
    try:
        return AxisState(int(code)).name
    except ValueError:
        return f"STATE_{int(code)}"


def _index(cycles: np.ndarray, cycle_s: float) -> list[rr.TimeColumn]:
    return [rr.TimeColumn("sim_time", duration=cycles * cycle_s)]


def _groups(signals: Sequence[str]) -> dict[str, list[int]]:
    """Each axis entity and the places of its numeric signals in `signals` (states apart)."""
    out: dict[str, list[int]] = {}
    for k, name in enumerate(signals):
        if not name.endswith(".state"):
            out.setdefault(_split(name)[0], []).append(k)
    return out


def blueprint(machine: str, signals: Sequence[str]) -> rrb.Blueprint:
    """Per axis its speed and lag, and its position (other signals in a third), the events
    and the description beside them."""
    views: list[rrb.View] = []
    for axis, places in _groups(signals).items():
        names = [_split(signals[k])[1] for k in places]
        path = entity(machine, signals[places[0]])
        for title, kinds in (("speed and lag", _SPEED_LAG), ("position", _POSITION), ("", ())):
            if kinds:
                shown = [n.startswith(kinds) for n in names]
            else:  # the rest
                shown = [not n.startswith(_SPEED_LAG + _POSITION) for n in names]
            if any(shown):
                views.append(
                    rrb.TimeSeriesView(
                        origin=path,
                        contents=[path],
                        name=f"{axis} {title or 'other'}",
                        overrides={path: rr.SeriesLines.from_fields(visible_series=shown)},
                    )
                )
    side = rrb.Vertical(
        rrb.TextLogView(
            origin=machine,
            contents=[f"{machine}/events", f"{machine}/notes"],
            name="events and notes",
        ),
        rrb.TextDocumentView(origin=machine, contents=[machine], name="about"),
    )
    return rrb.Blueprint(rrb.Horizontal(rrb.Grid(*views), side, column_shares=[3, 1]))


@dataclass
class RrdWriter:
    """Logs blocks of samples of one machine's signals to a recording stream."""

    stream: rr.RecordingStream
    machine: str
    signals: Sequence[str]
    cycle_s: float
    last_state: dict[str, float] = field(default_factory=dict)  # state text only on change
    groups: dict[str, list[int]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.groups = _groups(self.signals)
        for places in self.groups.values():  # the series' names, once
            names = [_split(self.signals[k])[1] for k in places]
            path = entity(self.machine, self.signals[places[0]])
            self.stream.log(path, rr.SeriesLines(names=names), static=True)

    def block(self, first_cycle: int, data: np.ndarray) -> None:
        """Samples of cycles first_cycle … (signals × count), one batch per axis."""
        if data.shape[1] == 0:
            return
        cycles = np.arange(first_cycle, first_cycle + data.shape[1], dtype=np.int64)
        index = _index(cycles, self.cycle_s)
        for places in self.groups.values():
            path = entity(self.machine, self.signals[places[0]])
            values = np.ascontiguousarray(data[places].T)  # cycles × the axis' signals
            self.stream.send_columns(
                path, indexes=index, columns=rr.Scalars.columns(scalars=values)
            )
        for k, name in enumerate(self.signals):
            if name.endswith(".state"):
                self._states(f"{self.machine}/{name.replace('.', '/')}", name, cycles, data[k])

    def _states(self, path: str, name: str, cycles: np.ndarray, y: np.ndarray) -> None:
        prev = np.r_[self.last_state.get(name, np.nan), y[:-1]]
        at = np.flatnonzero(y != prev)
        self.last_state[name] = float(y[-1])
        if at.size:
            self.stream.send_columns(
                path,
                indexes=_index(cycles[at], self.cycle_s),
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
            indexes=_index(cycles, self.cycle_s),
            columns=rr.TextLog.columns(text=text, level=level),
        )


def notes(stream: rr.RecordingStream, machine: str, at: Sequence[tuple[float, str]]) -> None:
    """Logbook entries (sim_time s, text) as text logs at `<machine>/notes`."""
    if at:
        stream.send_columns(
            f"{machine}/notes",
            indexes=[rr.TimeColumn("sim_time", duration=np.array([t for t, _ in at]))],
            columns=rr.TextLog.columns(text=[text for _, text in at], level=["INFO"] * len(at)),
        )


def open_stream(
    path: Path, recording_id: str, machine: str, about: str, signals: Sequence[str]
) -> rr.RecordingStream:
    """A recording stream saving to `path` with its default blueprint, and a static
    description of what it holds."""
    stream = rr.RecordingStream(APP_ID, recording_id=recording_id, send_properties=False)
    stream.save(path, default_blueprint=blueprint(machine, signals))
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
    logbook: Sequence[tuple[float, str]] = (),
) -> None:
    """One capture as an .rrd file (with the logbook's notes of its time: sim_time, text)."""
    tmp = path.with_suffix(".part")
    stream = open_stream(tmp, recording_id, machine, about, signals)
    w = RrdWriter(stream, machine, signals, cycle_s)
    w.block(first_cycle, data)
    w.events(events)
    notes(stream, machine, logbook)
    close_stream(stream)
    tmp.replace(path)
