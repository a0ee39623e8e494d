"""The channel's program state: the loaded program, where execution is, single block.

Execution itself (block queue, path, synchronisation) lives beside it in the channel package;
this holds what the status shows and what survives between blocks.
"""

from __future__ import annotations

from dataclasses import dataclass

from nc_sim.events import Event
from nc_sim.snapshot import ChannelState


@dataclass
class LoadedProgram:
    """A program the channel accepted: its label and text (it interpreted without error)."""

    name: str
    text: str


@dataclass
class ChannelProgress:
    """Where the channel is: state, program, current block line, what the path waits for."""

    state: ChannelState = ChannelState.IDLE
    program: LoadedProgram | None = None
    block_line: int | None = None
    blocks_done: int = 0
    single_block: bool = False
    mdi: bool = False  # MDI blocks run (the state is RUNNING while they do)
    waiting_for: str | None = None
    error: Event | None = None
