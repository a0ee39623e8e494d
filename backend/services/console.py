"""The instructor's console: every seat of a running class as a grid frame, built from the
status the seats' workers push (the console watches every seat, so they push), a few times a
second, to each console's websocket. Building a frame also takes the seats' check results in
(first passes saved at once, seat time now and then).

A slow console never holds the others up: each has a one-frame mailbox, a newer frame
replaces one it has not sent yet.
"""

from __future__ import annotations

import asyncio
import logging
import time
from dataclasses import dataclass, field

from api.classes import AxisLine, GridFrame, SeatFrame
from backend.services.classes import Class, Classes, Seat
from backend.services.machines import MachineProxy
from backend.workers.protocol import Watch

log = logging.getLogger(__name__)

GRID_S = 0.25  # a frame every quarter second: the grid's sparklines move smoothly
SAVE_S = 10.0  # seat time saved this often (first passes at once)


@dataclass(eq=False)  # each open console is itself (kept in a set)
class Console:
    """One open console of a class."""

    class_id: str
    mailbox: asyncio.Queue[GridFrame] = field(default_factory=lambda: asyncio.Queue(maxsize=1))

    def offer(self, frame: GridFrame) -> None:
        """Leave the newest frame (replacing one not taken yet)."""
        if self.mailbox.full():
            self.mailbox.get_nowait()
        self.mailbox.put_nowait(frame)


def seat_frame(c: Class, seat: Seat, m: MachineProxy | None, classes: Classes) -> SeatFrame:
    """One seat now, from its machine's newest pushed status."""
    progress, score = classes.score(c, seat)
    st = m.status if m is not None else None
    holder = m.control.holder if m is not None else None
    axes: list[AxisLine] = []
    error, code, channel, status_unix = None, None, "—", None
    mode = "gone" if m is None else (m.pacing.mode if m.pacing is not None else "run")
    if st is not None:
        snap = st.snapshot
        axes = [
            AxisLine(name=a.display_name or a.name, state=a.state, lag=a.lag, speed=a.vel_act)
            for a in snap.axes
        ]
        channel = snap.channel.state.name
        if snap.job_errors:
            newest = snap.job_errors[-1]
            error, code = newest.message, newest.code
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
        faults=len(m.faults) if m is not None else 0,
        seat_time_s=seat.seat_time_s,
        status_unix=status_unix,
    )


class ConsoleHub:
    """Builds every running class's frame and hands it to its open consoles."""

    def __init__(self, classes: Classes) -> None:
        self.classes = classes
        self.consoles: set[Console] = set()
        self._task: asyncio.Task[None] | None = None
        self._saved = time.monotonic()
        self.frames = 0
        self.restarts = 0
        self._watched: set[str] = set()

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
                    m.watchers += 1
                    if m.watchers == 1:
                        m.post(Watch(m.id, True))

    def unwatch(self, c: Class) -> None:
        for seat in c.seats:
            self._watched.discard(seat.machine)

    def frame(self, c: Class) -> GridFrame:
        seats = [seat_frame(c, s, self.classes.proxy(s), self.classes) for s in c.seats]
        return GridFrame(
            class_id=c.id, ended=c.ended_unix is not None, t_unix=time.time(), seats=seats
        )

    def tick(self, wanted: set[str]) -> list[GridFrame]:
        """Take every seat's status in, then build the frames of the classes `wanted`."""
        self.watch()
        due = time.monotonic() - self._saved >= SAVE_S
        if due:
            self._saved = time.monotonic()
        frames = []
        for c in self.classes.all():
            if c.ended_unix is not None:
                continue
            for seat in c.seats:
                m = self.classes.proxy(seat)
                if m is not None and (self.classes.update(seat, m) or due):
                    self.classes.save(seat)
            if c.id in wanted:
                frames.append(self.frame(c))
        return frames

    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self._supervise(), name="console")

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()

    async def _supervise(self) -> None:
        while True:
            try:
                while True:
                    await asyncio.sleep(GRID_S)
                    # SQLite writes and 50 seats' frames: off the event loop
                    wanted = {k.class_id for k in self.consoles}
                    for frame in await asyncio.to_thread(self.tick, wanted):
                        for console in [k for k in self.consoles if k.class_id == frame.class_id]:
                            console.offer(frame)
                        self.frames += 1
            except Exception:
                self.restarts += 1
                log.exception("instructor console failed; restarting it")
