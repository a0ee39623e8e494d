"""NC programs interpreted in a worker loop's spare time, never in one go.

A program may run up to `MAX_PROGRAM_BLOCKS` blocks (repetitions included): seconds of
interpretation. Done at once it froze every machine of the worker, an emergency stop to a
neighbour's included. So a program load, or a cycle start that must interpret from new
positions, is interpreted a few blocks at a time while the loop waits for its next deadline
(at most INTERPRET_SHARE of each period), with a look for requests between the slices. Its
reply waits, and so do the machine's later commands (they must find the program loaded),
except an emergency stop, which never waits.
"""

from __future__ import annotations

import gc
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from backend.workers.host import MachineHost
from backend.workers.protocol import Submit
from nc_sim.channel import canon
from nc_sim.channel.words import ProgramError
from nc_sim.commands import CycleStart, ProgramLoad
from nc_sim.machine.channel_ops import Interpretation
from nc_sim.snapshot import ChannelState

SLICE_S = 0.0002  # interpreting this long at most before the loop looks for requests
# of each loop period at most: a worker's loop runs with real-time priority, and Linux stops
# such a thread for 50 ms when it keeps a core busy for more than 95 % of a second
INTERPRET_SHARE = 0.7
BLOCKS_PER_LOOK = 4  # blocks between looks at the clock (a block takes about 40 µs)

Pending = tuple[int, Submit, float]  # (request, the submit, when it was sent)


@dataclass
class _Job:
    host: MachineHost
    job: Interpretation
    sink: canon.ListSink
    steps: Iterator[None]
    waiting: deque[Pending] = field(default_factory=deque)  # the submit first, then later ones
    result: list[canon.Call] | ProgramError | None = None


def interpretation_needed(host: MachineHost, submit: Submit) -> Interpretation | None:
    """The interpretation `submit` would do at once, if it would do one."""
    cmd, machine = submit.cmd, host.machine
    if isinstance(cmd, ProgramLoad):
        text = cmd.text
    elif isinstance(cmd, CycleStart) and machine.channel.state is ChannelState.READY:
        program = machine.channel.progress.program
        if program is None or machine.channel.progress.mdi:
            return None
        text = program.text
    else:
        return None
    if machine.ops.interpreted(text):
        return None
    return machine.ops.interpretation(text)


class Interpreting:
    """The programs being interpreted, and the commands waiting for them."""

    def __init__(self) -> None:
        self.jobs: dict[str, _Job] = {}  # by machine

    def busy(self, mid: str) -> bool:
        """The machine waits for an interpretation: its commands queue behind it."""
        return mid in self.jobs

    def __bool__(self) -> bool:
        return bool(self.jobs)

    def working(self) -> bool:
        """An interpretation has steps left."""
        return any(j.result is None for j in self.jobs.values())

    def start(self, host: MachineHost, job: Interpretation, pending: Pending) -> None:
        """Interpret in slices; `pending` is answered when it is done."""
        sink = canon.ListSink()
        self.jobs[host.id] = _Job(host, job, sink, job.steps(sink), deque([pending]))

    def hold(self, mid: str, pending: Pending) -> None:
        """A later command of a machine that waits: carried out after the interpretation."""
        self.jobs[mid].waiting.append(pending)

    def step(self, until_mono: float) -> None:
        """Interpret until `until_mono` (monotonic time) or every program is done.

        A long program makes a hundred thousand objects that live on: Python's cyclic
        collector would scan them all in one go every so often, a pause of 15-35 ms. So it
        does not run during a slice, and what the slice left alive is frozen out of its reach
        (freed as usual once nothing refers to it, only never scanned for cycles)."""
        gc.disable()
        try:
            self._step(until_mono)
        finally:
            gc.freeze()
            gc.enable()

    def _step(self, until_mono: float) -> None:
        for job in self.jobs.values():
            try:
                while job.result is None:
                    if time.monotonic() >= until_mono:
                        return
                    for _ in range(BLOCKS_PER_LOOK):
                        next(job.steps)
            except StopIteration:
                job.result = job.sink.calls
            except ProgramError as e:
                job.result = e

    def finish(
        self, alive: Callable[[MachineHost], bool]
    ) -> list[tuple[MachineHost, deque[Pending]]]:
        """The machines whose interpretation ended, each primed with its result, with their
        waiting commands in order (`alive`: the worker still holds this machine)."""
        done = []
        for mid, job in list(self.jobs.items()):
            if job.result is None:
                continue
            del self.jobs[mid]
            if alive(job.host):
                job.host.machine.ops.prime(job.job, job.result)
            done.append((job.host, job.waiting))
        return done
