"""The shared sample ring between a worker and the gateway, and the cleanup of rings that
a killed gateway left behind."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from backend.workers.pool import remove_stale_rings
from backend.workers.ring import MAX_WRITE, R_COLS, SampleRing
from nc_sim.signals import Signal

POS = Signal("X.pos_cmd_mm", "X", 0, 0, 1.0, "mm", "float")  # slot 0, column 0


def write(ring: SampleRing, first: int, last: int) -> None:
    """Cycles first..last with value = cycle in slot 0, column 0, as a worker writes them."""
    for c in range(first, last + 1):
        ring.rows[c % ring.cycles, 0, 0] = float(c)
    ring.publish(last)


def test_the_gateway_reads_what_the_worker_wrote_through_the_file(tmp_path: Path) -> None:
    writer = SampleRing.create(tmp_path / "m.ring", slots=2, cycles=8192)
    reader = SampleRing.attach(tmp_path / "m.ring")
    assert (reader.cycles, reader.rows.shape) == (8192, (8192, 2, R_COLS))
    write(writer, 1, 1000)
    assert reader.head == 1000
    data, first = reader.read([POS], 10, 1000, 10)
    assert first == 10
    np.testing.assert_array_equal(data[0], np.arange(10, 1001, 10, dtype=float))


def test_a_ring_closed_by_a_rebuild_reads_nothing_and_a_read_under_way_finishes(
    tmp_path: Path,
) -> None:
    """The gateway closes the old build's ring when the machine is rebuilt (another thread)
    while telemetry may be reading it: a read that began keeps its view; a read after the
    close reads no samples instead of failing (an IndexError closed the viewer's socket)."""
    writer = SampleRing.create(tmp_path / "m.ring", slots=1, cycles=4096)
    reader = SampleRing.attach(tmp_path / "m.ring")
    write(writer, 1, 3000)
    under_way = reader.rows  # what a read holds from its start
    reader.close()
    assert under_way[2999 % 4096, 0, 0] == 2999.0  # still mapped
    data, first = reader.read([POS], 2000, 3000, 1)
    assert data.shape == (1, 0) and first == 2000
    assert reader.peaks([POS], 2000, 3000) is None


def test_a_reader_that_fell_behind_skips_what_may_be_overwritten(tmp_path: Path) -> None:
    """With the writer at cycle h and writing up to MAX_WRITE more before it publishes, the
    oldest cycle safe to read is h - cycles + 1 + MAX_WRITE."""
    ring = SampleRing.create(tmp_path / "m.ring", slots=1, cycles=4096)
    write(ring, 1, 10_000)
    data, first = ring.read([POS], 1, 10_000, 1)
    oldest = 10_000 - 4096 + 1 + MAX_WRITE
    assert first == oldest
    np.testing.assert_array_equal(data[0], np.arange(oldest, 10_001, dtype=float))
    data, first = ring.read([POS], 1, 10_000, 7)  # on the reader's grid: 1, 8, 15, ...
    assert first >= oldest and (first - 1) % 7 == 0 and first - 7 < oldest


def test_rings_of_a_gateway_that_is_gone_are_removed(tmp_path: Path) -> None:
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    gone = tmp_path / f"inbetrieb-{int(dead.stdout)}-abc123"
    mine = tmp_path / f"inbetrieb-{os.getpid()}-def456"
    for d in (gone, mine):
        d.mkdir()
        (d / "m.1.ring").write_bytes(b"x")
    remove_stale_rings(tmp_path)
    assert not gone.exists() and (mine / "m.1.ring").exists()


LAG = Signal("X.lag_mm", "X", 1, 3, 1.0, "mm", "float")  # slot 1, column 3


def test_peaks_find_a_one_cycle_spike_with_its_sign(tmp_path: Path) -> None:
    """Between two reads of a display, one cycle of -7 among values within ±0.1: the peak
    of every cycle in between is that cycle's value, sign kept."""
    ring = SampleRing.create(tmp_path / "m.ring", slots=2, cycles=4096)
    for c in range(1, 501):
        ring.rows[c % ring.cycles, 1, 3] = 0.1 * np.sin(c / 7)
        ring.rows[c % ring.cycles, 0, 0] = float(c)
    ring.rows[333 % ring.cycles, 1, 3] = -7.0
    ring.publish(500)
    peak = ring.peaks([POS, LAG], 251, 500)
    assert peak is not None
    np.testing.assert_array_equal(peak, [500.0, -7.0])
    assert abs(ring.peaks([LAG], 334, 500)[0]) <= 0.1  # type: ignore[index]
    assert ring.peaks([LAG], 501, 500) is None  # nothing new
