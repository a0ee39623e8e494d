"""A machine's sample ring: every cycle's kernel record, written by its worker, read by the
gateway without asking the worker.

Locally the ring is a file in shared memory (/dev/shm) that both processes map: the worker's
kernel writes its records straight into it and then publishes the newest cycle in the header;
the gateway reads rows and checks afterwards that the worker did not overwrite them meanwhile
(a seqlock without the lock: x86 keeps the worker's stores in order). A gateway that reaches
a worker without shared memory (a Ray actor on another node) keeps a ring of its own, filled
with the rows the worker sends (`since` on its side, `put` on the gateway's); both answer the
same `read`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from nc_sim.signals import Signal, signal_rows

RING_CYCLES = 1 << 14  # 16.4 s at 1 kHz
MAX_WRITE = 2000  # cycles a worker writes at most before publishing them
R_COLS = 24  # kernel record columns (nc_sim.kernel.layout.R_COLS; checked by the worker)
_HEADER = 4  # int64: newest cycle, ring cycles, slots, columns


def shm_dir() -> Path:
    """Where rings live: shared memory when the system has it."""
    base = Path("/dev/shm")
    return base if base.is_dir() and os.access(base, os.W_OK) else Path("/tmp")


class SampleRing:
    """The rows of cycles 1..head; cycle c lives in row c % cycles."""

    def __init__(self, header: np.ndarray, rows: np.ndarray, path: Path | None) -> None:
        self._header = header
        self.rows: np.ndarray = rows
        self.cycles = int(rows.shape[0])
        self.path = path

    @classmethod
    def create(cls, path: Path | None, slots: int, cycles: int = RING_CYCLES) -> SampleRing:
        """A new ring: a shared file at `path`, or private memory when None."""
        count = _HEADER * 8 + cycles * slots * R_COLS * 8
        if path is None:
            buf: np.ndarray = np.zeros(count, np.uint8)
        else:
            buf = np.memmap(path, np.uint8, "w+", shape=(count,))
        ring = cls._view(buf, slots, cycles, path)
        ring._header[1:] = (cycles, slots, R_COLS)
        return ring

    @classmethod
    def attach(cls, path: Path) -> SampleRing:
        """Map a worker's ring read-only."""
        buf = np.memmap(path, np.uint8, "r")
        header = np.frombuffer(buf, np.int64, _HEADER)
        cycles, slots, cols = (int(x) for x in header[1:])
        if cols != R_COLS:
            raise ValueError(f"{path}: {cols} record columns, expected {R_COLS}")
        return cls._view(buf, slots, cycles, path)

    @classmethod
    def _view(cls, buf: np.ndarray, slots: int, cycles: int, path: Path | None) -> SampleRing:
        header = np.frombuffer(buf, np.int64, _HEADER)
        rows = np.frombuffer(buf, np.float64, cycles * slots * R_COLS, _HEADER * 8)
        return cls(header, rows.reshape(cycles, slots, R_COLS), path)

    @property
    def head(self) -> int:
        """The newest cycle whose row is complete."""
        return int(self._header[0])

    def publish(self, head: int) -> None:
        """Rows up to `head` are written (worker side, after writing them)."""
        self._header[0] = head

    def put(self, first: int, rows: np.ndarray) -> None:
        """Copy rows of cycles first.. in and publish them (a gateway's own ring)."""
        n = rows.shape[0]
        idx = np.arange(first, first + n) % self.cycles
        self.rows[idx] = rows
        self.publish(first + n - 1)

    def since(self, first: int, max_cycles: int) -> tuple[int, np.ndarray]:
        """A copy of the rows of cycles first..head (the newest `max_cycles` when there are
        more) and the cycle of the first row: later than asked when the writer may have
        overwritten older ones meanwhile (read from another thread than the writer's)."""
        head = self.head
        first = max(first, self.oldest(head), head - max_cycles + 1)
        rows: np.ndarray = self.rows[np.arange(first, head + 1) % self.cycles]
        safe = self.oldest(self.head)
        if safe > first:
            rows, first = rows[safe - first :], safe
        return first, rows

    def oldest(self, head: int) -> int:
        """The oldest cycle still safe to read while the writer may be writing past head."""
        return max(1, head - self.cycles + 1 + MAX_WRITE)

    def read(
        self, signals: list[Signal], first: int, last: int, stride: int
    ) -> tuple[np.ndarray, int]:
        """Samples of cycles first, first+stride, ... ≤ last as signals × count.

        Returns the data and the first cycle actually present (later than `first` when the
        ring no longer holds the older cycles; nothing once it is closed)."""
        rows = self.rows  # a close meanwhile (the machine rebuilt) leaves this view mapped
        if not len(rows):
            return np.zeros((len(signals), 0)), first
        first = self._skip_to(first, self.oldest(self.head), stride)
        idx = np.arange(first, last + 1, stride)
        data = signal_rows(signals, rows, idx % self.cycles)
        safe = self._skip_to(first, self.oldest(self.head), stride)  # overwritten meanwhile?
        if safe > first:
            k = (safe - first) // stride
            data, first = data[:, k:], safe
        return data, first

    def peaks(self, signals: list[Signal], first: int, last: int) -> np.ndarray | None:
        """Per signal, its sample of the largest magnitude (sign kept) among cycles
        first..last, every cycle (None when the ring holds none of them): what a display
        that shows a value now and then must not miss in between."""
        rows = self.rows  # as in `read`
        first = max(first, self.oldest(self.head))
        if first > last or not len(rows):
            return None
        data = signal_rows(signals, rows, np.arange(first, last + 1) % self.cycles)
        at = np.abs(data).argmax(axis=1)
        peak: np.ndarray = data[np.arange(len(signals)), at]
        return peak

    @staticmethod
    def _skip_to(first: int, oldest: int, stride: int) -> int:
        if first >= oldest:
            return first
        return first + math.ceil((oldest - first) / stride) * stride

    def close(self) -> None:
        """Drop the mapping (the file stays until its owner removes it). A read from another
        thread that began before keeps its view mapped; one after it reads nothing."""
        self.rows = self.rows[:0]
