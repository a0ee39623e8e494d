"""The instructor's console: every seat of a running class as a grid frame, built from the
status the seats' workers push (the console watches every seat, so they push), a few times a
second, to each console's websocket. Building a frame also takes the seats' check results in
(first passes saved at once, seat time now and then).

Each axis line also carries the peak lag and speed of every cycle since the previous frame,
read from the sample ring its worker writes (what the status shows is one cycle out of a
hundred: a runaway that trips between two frames would leave no trace).

A slow console never holds the others up: each has a one-frame mailbox, a newer frame
replaces one it has not sent yet. A frame is encoded once for all consoles of its class.
"""

from __future__ import annotations

import asyncio
import logging
import time
from dataclasses import dataclass, field

from api.classes import AxisLine, GridFrame, SeatFrame
from backend.services.classes import Classes
from backend.services.machines import MachineProxy
from backend.services.peaks import PeakReader, Peaks
from backend.services.replay import SeatRecorder
from backend.services.seats import Class, Seat
from backend.services.status import AXIS_KIND

log = logging.getLogger(__name__)

GRID_S = 0.25  # a frame every quarter second: the grid's sparklines move smoothly
SAVE_S = 10.0  # seat time saved this often (first passes at once)


@dataclass(eq=False)  # each open console is itself (kept in a set)
class Console:
    """One open console of a class."""

    class_id: str
    mailbox: asyncio.Queue[str] = field(default_factory=lambda: asyncio.Queue(maxsize=1))

    def offer(self, frame: str) -> None:
        """Leave the newest frame (replacing one not taken yet)."""
        if self.mailbox.full():
            self.mailbox.get_nowait()
        self.mailbox.put_nowait(frame)


def seat_frame(
    c: Class, seat: Seat, m: MachineProxy | None, classes: Classes, peaks: Peaks
) -> SeatFrame:
    """One seat now, from its machine's newest pushed status, with the `peaks` of its axes
    since the previous frame (an axis without: its status values)."""
    progress, score = classes.score(seat)
    st = m.link.status if m is not None else None
    holder = m.control.holder if m is not None else None
    axes: list[AxisLine] = []
    error, code, channel, status_unix = None, None, "—", None
    mode = "gone" if m is None else (m.link.pacing.mode if m.link.pacing is not None else "run")
    if st is not None:
        snap = st.snapshot
        axes = [
            AxisLine(
                name=a.display_name or a.name,
                kind=AXIS_KIND[a.kind],
                state=a.state,
                lag=a.lag,
                speed=a.vel_act,
                lag_peak=peaks.get(a.name, (a.lag, a.vel_act))[0],
                speed_peak=peaks.get(a.name, (a.lag, a.vel_act))[1],
            )
            for a in snap.axes
        ]
        channel = snap.channel.state.name
        if snap.job_errors:  # the first is the cause: a later "reset first" is not
            first = min(snap.job_errors, key=lambda e: e.cycle)
            error, code = first.message, first.code
        p = st.pacing
        mode = p.mode
        status_unix = p.t0_unix + p.cycle * p.cycle_s if p.mode == "run" else None
    return SeatFrame(
        n=seat.n,
        machine=seat.machine,
        student=seat.student,
        channel=channel,
        mode=mode,
        frozen=seat.frozen,
        axes=axes,
        error=error,
        error_code=code,
        control=holder.user if holder is not None else None,
        progress=progress,
        score=score,
        faults=len(m.link.faults) if m is not None else 0,
        seat_time_s=seat.seat_time_s,
        stage=seat.stage,
        total_score=score + sum(d.score for d in seat.done),
        hand=seat.hand,
        joined=seat.joined_unix is not None,
        idle_s=_idle_s(seat, m),
        status_unix=status_unix,
    )


def _idle_s(seat: Seat, m: MachineProxy | None) -> float | None:
    """Seconds since the seat's student last sent a command (since they joined when none)."""
    if seat.joined_unix is None:
        return None
    last = m.last_command.get(seat.user) if m is not None else None
    if last is None:  # none heard since they joined, or since the service started
        last = max(seat.joined_unix, m.since_unix if m is not None else 0.0)
    return max(0.0, time.time() - last)


class ConsoleHub:
    """Builds every running class's frame and hands it to its open consoles."""

    def __init__(self, classes: Classes, recorder: SeatRecorder) -> None:
        self.classes = classes
        self.recorder = recorder  # the debrief's replay: samples every running seat
        self.consoles: set[Console] = set()
        self._task: asyncio.Task[None] | None = None
        self._saved = time.monotonic()
        self.frames = 0
        self.restarts = 0
        self._watched: set[str] = set()
        self._peaks = PeakReader(GRID_S)
        self._seat_peaks: dict[str, Peaks] = {}  # machine -> its peaks of the newest tick

    def open(self, class_id: str) -> Console:
        console = Console(class_id)
        self.consoles.add(console)
        return console

    def close(self, console: Console) -> None:
        self.consoles.discard(console)

    def watch(self) -> None:
        """Every seat of a running class pushes its status (the checks and the grid need
        it), whether or not anybody has its HMI open."""
        for c in self.classes.all():
            if c.ended_unix is not None:
                continue
            for seat in c.seats:
                m = self.classes.proxy(seat)
                if m is not None and seat.machine not in self._watched:
                    self._watched.add(seat.machine)
                    m.link.watch(True)

    def unwatch(self, c: Class) -> None:
        for seat in c.seats:
            self._watched.discard(seat.machine)
            self._seat_peaks.pop(seat.machine, None)

    def record_last(self, c: Class, seats: list[Seat]) -> None:
        """The seats' last samples before their machines go or power on afresh (the class
        ends, a seat moves on): what happened since the newest sample stays in the replay."""
        for seat in seats:
            m = self.classes.proxy(seat)
            if m is not None:
                self.classes.update(seat, m)
                self.recorder.take(c.id, seat.n, self._peaks.peaks(m))
                self.recorder.sample(c.id, seat.n, seat.stage, seat.seat_time_s, m, last=True)

    def frame(self, c: Class) -> GridFrame:
        seats = []
        for s in c.seats:
            m = self.classes.proxy(s)
            peaks = self._seat_peaks.get(m.id, {}) if m is not None else {}
            seats.append(seat_frame(c, s, m, self.classes, peaks))
        return GridFrame(
            class_id=c.id, ended=c.ended_unix is not None, t_unix=time.time(), seats=seats
        )

    def tick(self, wanted: set[str]) -> list[tuple[str, str]]:
        """Take every seat's status in, then build the frames of the classes `wanted`:
        (class, the frame as JSON)."""
        self.watch()
        due = time.monotonic() - self._saved >= SAVE_S
        if due:
            self._saved = time.monotonic()
        frames = []
        for c in self.classes.all():
            if c.ended_unix is not None:
                if c.id in wanted:  # ended elsewhere: its consoles hear it and close the grid
                    ended = GridFrame(class_id=c.id, ended=True, t_unix=time.time(), seats=[])
                    frames.append((c.id, ended.model_dump_json()))
                continue
            for seat in c.seats:
                m = self.classes.proxy(seat)
                if m is None:
                    continue
                if self.classes.update(seat, m) or due:
                    self.classes.save(seat)
                # one read of the ring a tick serves the grid and the replay alike
                peaks = self._seat_peaks[m.id] = self._peaks.peaks(m)
                self.recorder.take(c.id, seat.n, peaks)
                if seat.joined_unix is not None or seat.seat_time_s > 0:
                    self.recorder.sample(c.id, seat.n, seat.stage, seat.seat_time_s, m)
            if c.id in wanted:
                frames.append((c.id, self.frame(c).model_dump_json()))
        return frames

    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self._supervise(), name="console")

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
        self.classes.save_running()
        self.recorder.flush()

    async def _supervise(self) -> None:
        next_at = time.monotonic()
        while True:
            try:
                while True:
                    # a frame every GRID_S whatever building one took (not GRID_S between)
                    next_at = max(next_at + GRID_S, time.monotonic())
                    await asyncio.sleep(next_at - time.monotonic())
                    # SQLite writes and 50 seats' frames: off the event loop
                    wanted = {k.class_id for k in self.consoles}
                    for cid, frame in await asyncio.to_thread(self.tick, wanted):
                        for console in [k for k in self.consoles if k.class_id == cid]:
                            console.offer(frame)
                        self.frames += 1
            except Exception:
                self.restarts += 1
                log.exception("instructor console failed; restarting it")
