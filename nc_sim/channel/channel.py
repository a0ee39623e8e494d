"""The NC channel: program state, the walk through a program's steps, its path.

States (nc_sim/snapshot.py ChannelState): IDLE (no program) -> READY (loaded) -> RUNNING on
cycle start -> HELD on feedhold, BLOCK_END at each block end in single block, back to READY at
the program end (M30/M02) or on stop, ERROR when a job error stops it (a reset clears it).
Steps that need the path at rest (dwell, synchronised spindle functions, M functions, homing,
program end) wait until every queued element has run; the others go along with the path.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from nc_sim.channel import canon
from nc_sim.channel.execution import Execution, Step, describe
from nc_sim.channel.geometry import Element
from nc_sim.channel.host import ChannelHost
from nc_sim.channel.mdi import MdiBlock, MdiQueue
from nc_sim.channel.modal import Modal
from nc_sim.channel.path import MAX_WINDOW, Path
from nc_sim.channel.state import ChannelProgress, LoadedProgram
from nc_sim.events import Event
from nc_sim.snapshot import ChannelState
from nc_sim.units import per_minute, per_second


@dataclass
class _Wait:
    action_id: int | None = None
    until_cycle: int | None = None
    what: str = ""
    block: int = 0  # the MDI block waiting


class Channel:
    """One channel: a path over its axes and the program running on it."""

    def __init__(
        self,
        path: Path,
        host: ChannelHost,
        axes: tuple[str, ...],
        interpret: Callable[[str], list[canon.Call]],
        cycle_s: float,
        lookahead: int,
        rotary_axes: frozenset[str] = frozenset(),
    ) -> None:
        self.path = path
        self.host = host
        self.axes = axes
        self.rotary_axes = rotary_axes  # degrees: F is over the linear axes (C alone: °/min)
        self.interpret = interpret  # text -> calls from the axes' positions now (raises)
        self.cycle_s = cycle_s
        self.lookahead = max(1, min(lookahead, MAX_WINDOW))
        self.progress = ChannelProgress()
        self.ex: Execution | None = None
        self.wait: _Wait | None = None
        self.last_key: tuple[int, int] | None = None  # (MDI block, line) of the last step
        self.step_granted = False  # single block: cycle start lets one more block run
        self.filling = True  # topping the window up (until full, then again at half)
        self.modal: tuple[int, int, bool, float | None] = (0, 17, True, None)
        self.feed_scale = per_second(1.0)  # F (mm/min) -> mm/s, times the override
        self.override = 1.0
        self.mdi = MdiQueue()
        self.feedhold = False  # the channel's HLI feedhold (the machine sets it)
        self.aborted_with: Event | None = None  # the job error of the last abort
        self._submitting: int | None = None  # the MDI block `run_mdi` is starting

    # --- commands -------------------------------------------------------------------------
    def load(self, name: str, text: str) -> None:
        """Keep an interpreted-without-error program (the caller checked it)."""
        self.progress.program = LoadedProgram(name, text)
        self.progress.error = None
        self.progress.state = ChannelState.READY
        self.progress.block_line = None

    @property
    def state(self) -> ChannelState:
        return self.progress.state

    @property
    def braking(self) -> bool:
        """A stopped program's path is still braking (cycle start must wait)."""
        return self.ex is None and self.path.count > 0

    def start(self) -> None:
        """Cycle start from READY: interpret from where the axes are now and run."""
        assert self.progress.program is not None
        calls = self.interpret(self.progress.program.text)
        self.mdi.reset_modal()
        self.ex = self._execution(calls)
        self.wait = None
        self.last_key = None
        self.step_granted = True
        self.progress.blocks_done = 0
        self.progress.error = None
        self.progress.state = ChannelState.RUNNING
        self._held_if_feedhold()
        self.pump()

    def _execution(self, calls: list[canon.Call]) -> Execution:
        return Execution(
            calls,
            self.axes,
            self.host.sync_of,
            self.host.new_action_id,
            self.rotary_axes,
            path_limits=self.host.path_limits,
        )

    def _held_if_feedhold(self) -> None:
        """A start with feedhold on waits in HELD until feedhold is released."""
        if self.feedhold:
            self.progress.state = ChannelState.HELD

    def mdi_modal(self) -> Modal:
        """The modal state the next MDI block starts from (after the blocks queued, else
        from where the axes are now)."""
        if not self.progress.mdi:
            self.mdi.modal.position = dict(
                zip(self.axes, self.path.position().tolist(), strict=True)
            )
        return self.mdi.modal

    def run_mdi(self, block_id: int, text: str, calls: list[canon.Call]) -> Event | None:
        """Queue an interpreted MDI block behind those running (the caller checked that no
        program runs); the job error when it ended in one at once."""
        if not self.progress.mdi:
            self.mdi.return_to = self.progress.state
            modal = self.mdi.modal
            self.ex = self._execution([])
            self.ex.feed_mm_min, self.ex.plane = modal.feed_mm_min, modal.plane
            self.ex.acceleration_weight = dict(modal.acceleration_weight)
            self.ex.ramp_time_weight = dict(modal.ramp_time_weight)
            self.ex.vector_limit = modal.vector_limit
            self.ex.parallel_manual = modal.parallel_manual
            self.wait = None
            self.last_key = None
            self.step_granted = True
            self.progress.mdi = True
            self.progress.state = ChannelState.RUNNING
            self._held_if_feedhold()
        assert self.ex is not None
        self.ex.mdi_blocks.append((block_id, calls))
        self.mdi.add(block_id, text)
        self.aborted_with = None
        self._submitting = block_id  # failing now, it is refused to its sender, not dropped
        try:
            self.pump()
        finally:
            self._submitting = None
        return self.aborted_with

    def resume(self) -> None:
        """Cycle start in HELD or BLOCK_END."""
        if self.progress.state is ChannelState.HELD:
            self.progress.state = ChannelState.RUNNING
            self.replan()
        elif self.progress.state is ChannelState.BLOCK_END:
            self.progress.state = ChannelState.RUNNING
            self.step_granted = True
            if self.path.count:
                self.host.path_moving(self.path.current.line if self.path.current else None)
                self.replan()
        self.pump()

    def hold(self) -> None:
        """Feedhold: brake on the path and wait. A thread or a tap runs to its end first (it
        cannot stop in the material), then the channel holds."""
        if self.progress.state is ChannelState.RUNNING:
            self.progress.state = ChannelState.HELD
            if self.path.count and not self._coupled():
                self.path.hold(self.host.hold_limits(self.path.current))

    def _coupled(self) -> bool:
        """The path runs a spindle-coupled element (G33, G63)."""
        e = self.path.current
        return e is not None and e.coupling is not None

    def set_single_block(self, on: bool) -> None:
        """Single block on or off; on during a run, the path stops at the end of the block
        it is in (the blocks queued behind it wait for cycle start)."""
        self.progress.single_block = on
        if self.path.count:
            self.step_granted = False
            self.replan()

    def stop(self) -> None:
        """Brake on the path and rewind (the path ends where it stopped); a thread or a tap
        is left, its axes and spindle braking on their own."""
        if self._coupled():
            self.path.abandon()
            self.host.path_left()
        elif self.path.count and self.path.at_rest():  # held already: give the axes back now
            self.path.finish()
            self.host.path_moving(None)
        elif self.path.count:  # once at rest, the axes are given back (on_path_events)
            self.path.hold(self.host.hold_limits(self.path.current))
        self._rewind(ChannelState.READY)

    def abort(self, error: Event | None) -> None:
        """A job error or reset ends the program; the axes keep braking on their own."""
        if self.path.count or not self.path.at_rest():
            self.path.abandon()
        self.host.path_left()
        self.aborted_with = error
        if error is not None and self.progress.mdi:
            self._dropped(list(self.mdi.blocks), error)
            self._rewind(ChannelState.READY)  # MDI leaves no program in error
            return
        line = self.progress.block_line
        self._rewind(ChannelState.ERROR if error is not None else ChannelState.READY)
        if error is not None and error.line is None and line is not None:
            error = replace(error, line=line)  # the program line it stopped in
        self.progress.error = error
        if error is None and self.progress.program is None:
            self.progress.state = ChannelState.IDLE

    def reset(self) -> None:
        """CNC reset: the program or the MDI blocks end, an error is cleared, the modal words
        go back to G00 G17 G90 without F."""
        self.mdi.return_to = ChannelState.READY
        if self.state is not ChannelState.IDLE or self.path.count:
            self.abort(None)
        self.mdi.reset_modal()

    def _rewind(self, state: ChannelState) -> None:
        program_ran = self.ex is not None and not self.progress.mdi
        self.ex = None
        self.wait = None
        self.progress.waiting_for = None
        if self.progress.mdi:  # back to where the channel was before the MDI blocks
            self.progress.mdi = False
            self.mdi.clear()
            self.progress.block_line = None
            state = self.mdi.return_to
        elif program_ran:  # MDI goes on with the modal words the program left
            md = self.mdi.modal
            md.motion, md.plane, md.absolute, md.feed_mm_min = self.modal
        self.progress.state = state if self.progress.program else ChannelState.IDLE

    # --- the cycle boundary ---------------------------------------------------------------
    def on_path_events(self) -> None:
        """After EV_BLOCK / EV_PLAN_DONE of the channel slot: actions bound to passed
        elements start, the next blocks are queued."""
        if self.ex is None:  # stopped: braking on the path, no block runs any more
            self.path.sync()
            if self.path.count and self.path.at_rest():
                self.path.finish()
                self.host.path_moving(None)
            return
        for e in self.path.sync():
            self._passed(e)
            if self.progress.single_block:
                self.step_granted = False  # that block is done: the next waits
        if (
            self.progress.single_block
            and self.progress.state is ChannelState.RUNNING
            and self.path.count
            and self.path.at_rest()
            and not self.path.done()
            and not self.step_granted
        ):
            self.progress.state = ChannelState.BLOCK_END
            self.host.path_moving(None)
            return
        if self.path.count and self.path.done():
            for e in list(self.path.queue):
                self._passed(e)
            self.path.finish()
            self.host.path_moving(None)
        elif self.path.current is not None:
            self.host.path_moving(self.path.current.line)
            self._at(self.path.current.line)
            self.modal = self.path.current.modal
        self.pump()

    def _passed(self, e: Element) -> None:
        self.progress.blocks_done += 1
        for call, aid in e.actions:
            self._start(call, aid, e.block_id)

    def _at(self, line: int) -> None:
        """The program line the channel is at (none shown for MDI)."""
        self.progress.block_line = None if self.progress.mdi else line

    def pump(self) -> None:
        """Queue and start what may go now; plan again when the window changed."""
        changed = False
        while self.progress.state is ChannelState.RUNNING and self.ex is not None:
            if self.wait is not None and not self._wait_over():
                break
            self.wait = None
            self.progress.waiting_for = None
            if not self.ex.steps:
                if not self.ex.more(list(self.path.position())):
                    break
                continue
            step = self.ex.steps[0]
            key = (step.block, step.line)
            if self.progress.single_block and key != self.last_key:
                if not self.path.done() and self.path.count:
                    break
                if not self.step_granted:
                    self.progress.state = ChannelState.BLOCK_END
                    break
                self.step_granted = False
            self.last_key = key
            if step.element is not None:
                current = self.path.current
                if current is not None and current.coupling is not None:
                    break  # nothing joins a coupled element: it runs alone, then the rest
                if step.element.coupling is not None and self.path.count:
                    if self.path.done():  # it starts from rest, after the path before it
                        self.on_path_events()
                        return
                    break
                if step.element.coupling is not None and not self.host.path_in_position():
                    # exact stop first: the cut must not start while an axis still settles
                    self.progress.waiting_for = "exact stop of the axes"
                    break
                # top the window up in batches: each new element means a new plan
                if self.path.count <= self.lookahead // 2:
                    self.filling = True
                if self.path.count >= self.lookahead or not self.filling:
                    self.filling = False
                    break
                err = self.host.check_element(step.element)
                if err is None and step.element.coupling is not None:
                    err = self.host.start_coupling(step.element)
                if err is not None:
                    self._fail(err, step.block)
                    return
                if self.progress.single_block:
                    step.element.exact_stop = True
                self.ex.steps.popleft()
                if not self.path.count:
                    self._at(step.element.line)
                    self.modal = step.element.modal
                    self.host.path_moving(step.element.line)
                self.path.append(step.element)
                changed = True
                continue
            rest = step.rest or step.waits_for is not None or step.dwell_s > 0
            if rest and self.path.count:
                if self.path.done():
                    self.on_path_events()
                    return
                self.progress.waiting_for = None
                break
            self.ex.steps.popleft()
            if not self._act(step):
                return
        if changed:
            self.replan()
        if self.progress.mdi:
            self._mdi_progress()

    def _mdi_progress(self) -> None:
        """Report the MDI blocks that are done; when all are, the channel returns."""
        for b in self.mdi.finished(self._mdi_running):
            self.host.block_done(b.id, b.text)
        ex = self.ex
        if (
            ex is not None
            and not self.mdi.blocks
            and not ex.steps
            and not ex.mdi_blocks
            and self.wait is None
            and not self.path.count
        ):
            self._rewind(ChannelState.READY)

    def _mdi_running(self, b: MdiBlock) -> bool:
        ex = self.ex
        if ex is None:
            return False
        return (
            any(bid == b.id for bid, _calls in ex.mdi_blocks)
            or (ex.block == b.id and ex.pc < len(ex.calls))
            or any(st.block == b.id for st in ex.steps)
            or any(e.block_id == b.id for e in self.path.queue)
            or (self.wait is not None and self.wait.block == b.id)
            or any(self.host.busy(aid) for aid in b.actions)
        )

    def _act(self, step: Step) -> bool:
        assert self.ex is not None
        self._at(step.line)
        if step.dwell_s > 0:
            until = self.host.cycle + max(1, round(step.dwell_s / self.cycle_s))
            self.wait = _Wait(until_cycle=until, what=f"dwell {step.dwell_s:g} s", block=step.block)
        if step.waits_for is not None:
            what = f"synchronisation of line {step.line}"
            self.wait = _Wait(step.waits_for, what=what, block=step.block)
        call = step.call
        if call is None:
            return True
        if isinstance(call, canon.ProgramEnd):
            self.host.program_end(call)
            self._rewind(ChannelState.READY)
            return False
        aid = step.action_id or self.ex.new_id()
        if not step.rest and step.waits_for is None and self.path.count:
            self.path.queue[-1].actions.append((call, aid))  # when the path gets there
            return True
        if not self._start(call, aid, step.block):
            return False
        if step.wait:
            self.wait = _Wait(aid, what=describe(call, self.host.spindle_name), block=step.block)
        return True

    def _start(self, call: canon.Call, aid: int, block: int) -> bool:
        """Start an action (of MDI block `block`); on a job error the program stops (False)."""
        if block:
            self.mdi.started(block, aid)
        if isinstance(call, canon.SelectPlane):
            self.modal = (self.modal[0], call.plane, self.modal[2], self.modal[3])
            return True
        if isinstance(call, canon.ManualMode):
            self.host.manual_mode(call.g == 201)
            return True
        err = self.host.start_action(call, aid)
        if err is not None:
            self._fail(err, block)
            return False
        return True

    def _fail(self, err: Event, block: int) -> None:
        """A job error of a block: a program stops; of an MDI block, that block and those
        queued behind it are dropped, the ones before it run to their end."""
        if not (self.progress.mdi and block and self.ex is not None):
            self.abort(err)
            return
        self.aborted_with = err
        self.ex.steps.clear()
        self.ex.mdi_blocks.clear()
        self.ex.pc = len(self.ex.calls)
        self.ex.late.clear()
        self._dropped(self.mdi.drop_from(block), err)

    def _dropped(self, blocks: list[MdiBlock], err: Event) -> None:
        """Tell which MDI blocks a job error ended (not the one being submitted: its sender
        gets the error as the refusal)."""
        for b in blocks:
            if b.id != self._submitting:
                self.host.block_dropped(b.id, b.text, err)

    def _wait_over(self) -> bool:
        w = self.wait
        assert w is not None
        self.progress.waiting_for = w.what
        if w.until_cycle is not None and self.host.cycle < w.until_cycle:
            return False
        return not (w.action_id is not None and self.host.busy(w.action_id))

    def next_wakeup(self) -> int | None:
        """A dwell's end: the cycle at which the channel must look again."""
        if self.wait is not None and self.wait.until_cycle is not None:
            return self.wait.until_cycle
        return None

    def replan(self) -> None:
        """Plan the window again (new blocks, override, feedhold released)."""
        if self.progress.state is ChannelState.HELD or not self.path.count or self.ex is None:
            return  # (held, empty, or stopped and braking)
        if self._coupled():
            return  # the spindle leads, there is no plan
        self.path.replan(
            self.host.dynamics,
            self.feed_scale * self.override,
            self.override,
            first_only=self.progress.single_block,
        )

    # --- status ---------------------------------------------------------------------------
    def path_feed_mm_min(self) -> float:
        return per_minute(self.path.speed)

    def distance_to_go_mm(self) -> float | None:
        return self.path.distance_to_go()
