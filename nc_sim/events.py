"""Typed events, and a bounded log read by cursor: the machine's events and the outcomes of
its commands.

An `Event` is one job error or information event with its facts as fields (the M function,
the gear stage), so no reader ever parses its message: the message is for people.

Every entry gets a sequence number, counting from 0 and never reused, so a reader keeps the
sequence number of the next entry it wants (its cursor) and asks for what came since. The log
keeps only the newest `maxlen` entries; a reader that fell further behind learns how many it
missed instead of getting wrong entries. Appending and reading the tail cost O(1) and
O(entries read), never O(log length), so readers holding the machine lock never scan it.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from itertools import islice
from typing import Generic, Protocol, TypeVar

from nc_sim.errors import Code, is_error

T = TypeVar("T")

EVENT_LOG_LEN = 10_000  # events kept per machine (a few MB at most)
OUTCOME_LOG_LEN = 1_000  # outcomes of submitted commands kept per machine


@dataclass(frozen=True, kw_only=True)
class Event:
    """One job error or event of a machine: its place in the event log, when, where, what."""

    seq: int  # sequence number the machine's EventLog gave it (from 0 per power-on)
    cycle: int  # cycle in which it happened
    t_s: float  # simulated time, s
    axis: str  # axis or spindle, "" for the channel
    code: int  # nc_sim.errors.Code: a job error (≥ 60000) or an event number
    message: str  # in the operator's words; never parsed
    m: int | None = None  # the M function it concerns (M3, M19 in position, M41 output, ...)
    gear: int | None = None  # the gear stage 1..6 it concerns (gear change started, changed)
    line: int | None = None  # the program line (from 1) it concerns: a program error, a block
    column: int | None = None  # the column (from 1) of a program error
    signal: str | None = None  # the PLC signal or HLI unit it concerns (ROTMOD, feedhold, ...)
    value: float | None = None  # the position reached (in position), the value written
    block: int | None = None  # the MDI block it concerns (Accepted.block_id): done, dropped

    @property
    def error(self) -> bool:
        """True for a job error, false for an information event."""
        return is_error(self.code)


class Log(Protocol):
    """Records an event of a machine (its code, the axis, the detail, the M function, gear
    stage and program line it concerns) and returns it: what the parts of a machine log with."""

    def __call__(
        self,
        code: Code,
        axis: str = "",
        detail: str = "",
        *,
        m: int | None = None,
        gear: int | None = None,
        line: int | None = None,
        column: int | None = None,
        signal: str | None = None,
        value: float | None = None,
        block: int | None = None,
    ) -> Event: ...


@dataclass(frozen=True)
class LogRead(Generic[T]):
    """What a reader got from `EventLog.since`."""

    entries: list[T]  # oldest first
    first_seq: int  # sequence number of entries[0] (= cursor when nothing was dropped)
    cursor: int  # where to continue: the sequence number after the last entry
    dropped: int  # entries after the old cursor the log no longer held


class EventLog(Generic[T]):
    """The newest `maxlen` entries of an append-only sequence, numbered from 0.

    Reads like a sequence of the entries it holds (len, iteration, `log[-1]`) for code that
    only looks at the recent past; readers that must see every entry use `since(cursor)`.
    """

    def __init__(self, maxlen: int = EVENT_LOG_LEN) -> None:
        if maxlen < 1:
            raise ValueError(f"an event log holds at least one entry, not {maxlen}")
        self._entries: deque[T] = deque(maxlen=maxlen)
        self._next_seq = 0

    @property
    def maxlen(self) -> int:
        """Entries kept at most."""
        return self._entries.maxlen or 0

    @property
    def cursor(self) -> int:
        """Sequence number of the next entry (= entries appended so far): a reader that
        starts here sees only what comes after now."""
        return self._next_seq

    @property
    def first_seq(self) -> int:
        """Sequence number of the oldest entry held."""
        return self._next_seq - len(self._entries)

    def append(self, entry: T) -> int:
        """Add an entry (dropping the oldest when full); returns its sequence number."""
        self._entries.append(entry)
        self._next_seq += 1
        return self._next_seq - 1

    def since(self, cursor: int) -> LogRead[T]:
        """Entries with sequence numbers ≥ cursor that are still held, oldest first."""
        first = self.first_seq
        start = max(cursor, first)
        count = self._next_seq - start
        if count <= 0:
            return LogRead([], self._next_seq, self._next_seq, 0)
        entries = list(islice(reversed(self._entries), count))  # from the new end: O(count)
        entries.reverse()
        return LogRead(entries, start, self._next_seq, start - cursor if cursor < first else 0)

    def tail(self, n: int) -> list[T]:
        """The newest n entries (fewer when the log holds fewer), oldest first."""
        return self.since(self._next_seq - max(0, n)).entries

    def __len__(self) -> int:
        return len(self._entries)

    def __iter__(self) -> Iterator[T]:
        return iter(self._entries)

    def __reversed__(self) -> Iterator[T]:
        return reversed(self._entries)

    def __getitem__(self, index: int) -> T:
        """An entry by position among those held (`log[-1]` is the newest)."""
        return self._entries[index]

    def __bool__(self) -> bool:
        return bool(self._entries)
