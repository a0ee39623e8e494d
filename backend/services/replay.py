"""The debrief's replay: every running class seat's main signals recorded once a second of
wall time while its clock runs (each axis' position, and the lag and speed of the largest
magnitude in that second, a spindle's speed so), kept in
the store in chunks with the seat's exercise and seat time; played back with the seat's
history placed on the same clock (a history entry's wall time → seat time by the samples)."""

from __future__ import annotations

import bisect
import json
import threading
import time
import zlib
from dataclasses import dataclass, field

from api.replay import ReplayMark, SeatReplay
from backend.services.history import History
from backend.services.machine_log import HistoryFilter
from backend.services.machines import MachineProxy
from backend.services.peaks import Peaks
from backend.services.status import AXIS_KIND
from backend.services.store import Store

SCHEMA = """
CREATE TABLE IF NOT EXISTS seat_recordings (  -- backend/services/replay.py
    class TEXT NOT NULL,
    n INTEGER NOT NULL,
    stage INTEGER NOT NULL,        -- the exercise of the lesson plan
    t0_s REAL NOT NULL,            -- seat time of the chunk's first sample
    data BLOB NOT NULL             -- zlib'd JSON {"signals": [...], "rows": [[wall, seat_t, v...]]}
);
CREATE INDEX IF NOT EXISTS seat_recordings_seat ON seat_recordings (class, n, stage, t0_s);
"""
SAMPLE_S = 1.0  # a sample a second: the debrief's overview, not a scope
CHUNK_ROWS = 120  # two minutes a row in the store
MAX_MARKS = 2000  # history entries placed on one exercise's timeline


@dataclass
class _Tape:
    """One seat's samples not yet stored (one exercise, one set of signals)."""

    stage: int
    signals: list[str]
    units: list[str]
    rows: list[list[float | None]] = field(default_factory=list)
    last_wall: float = 0.0
    last_seat_s: float = -1.0


def _signals(
    m: MachineProxy, peaks: Peaks
) -> tuple[list[str], list[str], list[float | None]] | None:
    """The machine's main signals: names, units, values; positions as its newest pushed
    status has them, lag and speed the peaks since the last sample (`peaks`, where the ring
    has them)."""
    st = m.link.status
    if st is None:
        return None
    names: list[str] = []
    units: list[str] = []
    values: list[float | None] = []
    for a in st.snapshot.axes:
        name = a.display_name or a.name
        pos = "°" if a.pos_unit == "deg" else a.pos_unit
        lag, speed = peaks.get(a.name, (a.lag, a.vel_act))
        if AXIS_KIND[a.kind] == "spindle":
            names.append(f"{name}.speed")
            units.append(a.vel_unit)
            values.append(round(speed, 3))
            continue
        names += [f"{name}.pos", f"{name}.lag", f"{name}.speed"]
        units += [pos, pos, a.vel_unit]
        values += [round(a.pos_act, 4), round(lag, 5), round(speed, 2)]
    return names, units, values


@dataclass
class Sample:
    """One sample of a seat as read back: when, on its clock, and each signal's value."""

    wall_unix: float
    seat_t_s: float
    values: list[float | None]


class SeatRecorder:
    """Samples running seats (ConsoleHub's tick calls `sample`), stores them in chunks."""

    def __init__(self, store: Store, history: History) -> None:
        self.store = store
        self.history = history
        store.script(SCHEMA)
        self._lock = threading.Lock()
        self._tapes: dict[tuple[str, int], _Tape] = {}
        self._peaks: dict[tuple[str, int], Peaks] = {}  # since the seat's last sample

    def take(self, class_id: str, n: int, peaks: Peaks) -> None:
        """A seat's peaks since the last look (the console reads the ring for the grid and
        passes them here): the next sample has the largest of them."""
        with self._lock:
            have = self._peaks.setdefault((class_id, n), {})
            for axis, (lag, speed) in peaks.items():
                old_lag, old_speed = have.get(axis, (0.0, 0.0))
                have[axis] = (
                    lag if abs(lag) >= abs(old_lag) else old_lag,
                    speed if abs(speed) >= abs(old_speed) else old_speed,
                )

    def sample(
        self,
        class_id: str,
        n: int,
        stage: int,
        seat_t_s: float,
        m: MachineProxy,
        last: bool = False,
    ) -> None:
        """A sample of the seat's machine when a second has passed and its clock ran (`last`:
        now, whenever the one before was: its machine is about to go or power on afresh)."""
        now = time.time()
        key = (class_id, n)
        with self._lock:
            tape = self._tapes.get(key)
            same = tape is not None and tape.stage == stage
            if (
                same
                and tape is not None
                and (seat_t_s <= tape.last_seat_s or (not last and now - tape.last_wall < SAMPLE_S))
            ):
                return
            got = _signals(m, self._peaks.pop(key, {}))
            if got is None:
                return
            names, units, values = got
            if tape is None or tape.stage != stage or tape.signals != names:
                if tape is not None:
                    self._store(class_id, n, tape)
                tape = self._tapes[key] = _Tape(stage, names, units)
            tape.rows.append([round(now, 3), round(seat_t_s, 3), *values])
            tape.last_wall, tape.last_seat_s = now, seat_t_s
            if len(tape.rows) >= CHUNK_ROWS:
                self._store(class_id, n, tape)

    def _store(self, class_id: str, n: int, tape: _Tape) -> None:
        if not tape.rows:
            return
        chunk = {"signals": tape.signals, "units": tape.units, "rows": tape.rows}
        data = zlib.compress(json.dumps(chunk).encode())
        self.store.run(
            "INSERT INTO seat_recordings VALUES (?, ?, ?, ?, ?)",
            (class_id, n, tape.stage, tape.rows[0][1], data),
        )
        tape.rows = []

    def flush(self, class_id: str | None = None) -> None:
        """Store what is not stored yet (a class's seats, or every seat)."""
        with self._lock:
            for (cid, n), tape in self._tapes.items():
                if class_id is None or cid == class_id:
                    self._store(cid, n, tape)

    def forget(self, class_id: str) -> None:
        """A class deleted: its recordings go."""
        with self._lock:
            for key in [k for k in self._tapes if k[0] == class_id]:
                del self._tapes[key]
        self.store.run("DELETE FROM seat_recordings WHERE class = ?", (class_id,))

    def replay(self, class_id: str, n: int, stage: int, exercise: str, machine: str) -> SeatReplay:
        """The seat's recording in one exercise with its history on the same clock."""
        self.flush(class_id)
        samples: list[Sample] = []
        signals: list[str] = []
        units: list[str] = []
        for stored in self.store.query(
            "SELECT data FROM seat_recordings WHERE class = ? AND n = ? AND stage = ? "
            "ORDER BY t0_s, rowid",
            (class_id, n, stage),
        ):
            chunk = json.loads(zlib.decompress(stored["data"]))
            for name, unit in zip(chunk["signals"], chunk["units"], strict=True):
                if name not in signals:
                    signals.append(name)
                    units.append(unit)
            index = [signals.index(name) for name in chunk["signals"]]
            for wall, seat_t, *got in chunk["rows"]:
                values: list[float | None] = [None] * len(signals)
                for i, v in zip(index, got, strict=True):
                    values[i] = v
                samples.append(Sample(wall, seat_t, values))
        for sample in samples:  # signals named in later chunks only: earlier samples lack them
            sample.values.extend([None] * (len(signals) - len(sample.values)))
        marks = self._marks(machine, samples)
        return SeatReplay(
            class_id=class_id,
            seat=n,
            stage=stage,
            exercise=exercise,
            sample_s=SAMPLE_S,
            signals=signals,
            units=units,
            t_s=[x.seat_t_s for x in samples],
            values=[[x.values[i] for x in samples] for i in range(len(signals))],
            marks=marks,
        )

    def _marks(self, machine: str, samples: list[Sample]) -> list[ReplayMark]:
        """The machine's history between the first and the last sample (a sample's span
        either side), each at the seat time its wall time falls on."""
        if not samples:
            return []
        walls = [x.wall_unix for x in samples]
        seats = [x.seat_t_s for x in samples]
        f = HistoryFilter(since_unix=walls[0] - SAMPLE_S, until_unix=walls[-1] + SAMPLE_S)
        entries, _total = self.history.page(machine, f, MAX_MARKS)
        return [
            ReplayMark(seat_t_s=round(_seat_time(walls, seats, e.time_unix), 3), entry=e)
            for e in reversed(entries)
        ]


def _seat_time(walls: list[float], seats: list[float], wall: float) -> float:
    """The seat time at a wall time, between the samples around it (a paused clock: the
    sample's seat time until it runs again)."""
    i = bisect.bisect_right(walls, wall)
    if i == 0:
        return seats[0]
    if i == len(walls):
        return seats[-1]
    w0, w1, s0, s1 = walls[i - 1], walls[i], seats[i - 1], seats[i]
    return s0 + min(s1 - s0, wall - w0) if w1 > w0 else s0
