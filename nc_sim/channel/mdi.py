"""MDI in the channel: blocks typed by the operator (or sent by the PLC's external command
channel) run on the same path, with the same synchronisation, as a program's blocks.

Their modal words (G00-G03, G17-G19, G90/G91, F) carry over from one MDI block to the next;
a reset or a program start sets them back. While MDI blocks run the channel is RUNNING; when
the last is done it returns to the state it had (IDLE, READY with a loaded program, ERROR).
A job error ends the MDI blocks still queued; the channel then also returns (MDI leaves no
program in error behind).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from nc_sim.channel.modal import Modal
from nc_sim.snapshot import ChannelState


@dataclass
class MdiBlock:
    """One MDI block: its number, its text, the actions it started."""

    id: int
    text: str
    actions: list[int] = field(default_factory=list)


class MdiQueue:
    """The MDI blocks not yet done, and the modal state they leave for the next."""

    def __init__(self) -> None:
        self.blocks: deque[MdiBlock] = deque()
        self.modal = Modal()
        self.return_to = ChannelState.IDLE

    def add(self, block_id: int, text: str) -> None:
        """A block the channel took."""
        self.blocks.append(MdiBlock(block_id, text))

    def started(self, block_id: int, action_id: int) -> None:
        """An action of block `block_id` started (the block is done when it is)."""
        for b in self.blocks:
            if b.id == block_id:
                b.actions.append(action_id)
                return

    def finished(self, running: Callable[[MdiBlock], bool]) -> list[MdiBlock]:
        """Take the blocks at the head that no longer run, in order."""
        done = []
        while self.blocks and not running(self.blocks[0]):
            done.append(self.blocks.popleft())
        return done

    def drop_from(self, block_id: int) -> list[MdiBlock]:
        """Drop block `block_id` and those queued behind it (a job error of that block); the
        dropped ones, in order."""
        dropped: list[MdiBlock] = []
        while self.blocks and self.blocks[-1].id >= block_id:
            dropped.insert(0, self.blocks.pop())
        return dropped

    def clear(self) -> None:
        """Drop every block (stop, reset, job error)."""
        self.blocks.clear()

    def reset_modal(self) -> None:
        """Back to G00 G17 G90 without a feed (reset, program start)."""
        self.modal = Modal(home_position=self.modal.home_position)
