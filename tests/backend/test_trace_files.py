"""The trace library's files: the samples are on disk, whole and synced, before the row that
points at them is committed; a failed save leaves neither a row nor a file behind; the library
and each user stay within their disk quota, derived files included."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from backend.errors import ApiError
from backend.services.machines import MachineService
from backend.services.store import Store
from backend.services.trace_csv import from_csv
from backend.services.traces import TraceService
from backend.workers.pool import WorkerPool


@pytest.fixture
def library(tmp_path: Path) -> TraceService:
    store = Store(tmp_path / "t.sqlite")
    no_workers = WorkerPool(1, 0.002)  # never started: the library needs no machine
    return TraceService(store, tmp_path / "traces", MachineService(store, no_workers))


def test_the_row_is_committed_after_the_file_is_synced_in_place(
    library: TraceService, monkeypatch: pytest.MonkeyPatch
) -> None:
    trace = from_csv("cycle,a,b\n1,2,3\n2,3,4\n3,5,6\n")
    synced: list[int] = []
    real_fsync = os.fsync

    def fsync(fd: int) -> None:
        synced.append(fd)
        real_fsync(fd)

    seen: dict[str, Any] = {}
    real_add = library.store.add_trace

    def add_trace(tid: str, *args: Any) -> None:
        path = library.dir / f"{tid}.npy"
        seen["data"], seen["synced"] = np.load(path), len(synced)
        real_add(tid, *args)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(library.store, "add_trace", add_trace)
    info = library.add(trace, "tester")
    assert seen["data"].tolist() == [[2, 3, 5], [3, 4, 6]]  # whole at its name
    assert seen["synced"] >= 2  # the file and its directory, before the row
    assert [p.name for p in library.dir.iterdir()] == [f"{info.id}.npy"]  # no temp file


def test_a_failed_save_leaves_no_file_and_no_row(
    library: TraceService, monkeypatch: pytest.MonkeyPatch
) -> None:
    def full_disk(*_args: Any) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(library.store, "add_trace", full_disk)
    with pytest.raises(OSError):
        library.add(from_csv("cycle,a\n1,2\n2,3\n"), "tester")
    assert list(library.dir.iterdir()) == [] and library.library() == []

    def half_written(f: Any, _data: Any) -> None:
        f.write(b"\x93NUMPY")
        raise OSError(28, "No space left on device")

    monkeypatch.undo()
    monkeypatch.setattr(np, "save", half_written)
    with pytest.raises(OSError):
        library.add(from_csv("cycle,a\n1,2\n2,3\n"), "tester")
    assert list(library.dir.iterdir()) == [] and library.library() == []


def csv_of_mb(mb: float) -> str:
    """A CSV whose samples take `mb` MB as float64 (one channel besides the cycle)."""
    rows = int(mb * 1_000_000 / 8)
    return "cycle,a\n" + "".join(f"{k},{k}\n" for k in range(1, rows + 1))


def test_each_user_and_the_library_stay_within_their_quota(tmp_path: Path) -> None:
    """The probe imported 64 MB CSVs without end. Here the library holds 2.5 MB and a user
    1.5 MB: a user's second 1 MB trace is refused (507, naming them and their use), another
    user's still fits, then the library is full for everyone; deleting makes room."""
    store = Store(tmp_path / "q.sqlite")
    machines = MachineService(store, WorkerPool(1, 0.002))
    library = TraceService(store, tmp_path / "traces", machines, 2.5, 1.5)
    first = library.add(from_csv(csv_of_mb(1.0)), "olga")
    with pytest.raises(ApiError) as refused:
        library.add(from_csv(csv_of_mb(1.0)), "olga")
    assert refused.value.status == 507
    assert "olga's traces use 1.0 MB of their 1.5 MB" in refused.value.detail["message"]
    library.add(from_csv(csv_of_mb(1.0)), "otto")
    with pytest.raises(ApiError) as full:
        library.add(from_csv(csv_of_mb(0.6)), "ida")
    assert full.value.status == 507
    assert "the trace library uses 2.0 MB of its 2.5 MB" in full.value.detail["message"]
    assert library.used_mb() == pytest.approx(2.0, abs=0.01)  # 2 × 1 MB of samples (+ headers)
    library.delete(first.id)
    library.add(from_csv(csv_of_mb(0.6)), "ida")


def test_a_trace_s_rerun_recording_counts_for_the_library(tmp_path: Path) -> None:
    """The probe's first .rrd download added 115 MB beside a 37 MB import, uncounted."""
    store = Store(tmp_path / "r.sqlite")
    machines = MachineService(store, WorkerPool(1, 0.002))
    library = TraceService(store, tmp_path / "traces", machines, 100.0, 100.0)
    a = library.add(from_csv(csv_of_mb(0.5)), "olga")
    before = library.used_mb("olga")
    rrd = library.rrd_path(a.id)
    assert library.used_mb("olga") == pytest.approx(before + rrd.stat().st_size / 1e6)
    b = library.add(from_csv(csv_of_mb(0.05)), "otto")
    library.quota_mb = library.used_mb() + 0.01  # full but for 10 kB
    with pytest.raises(ApiError) as full:
        library.rrd_path(b.id)  # its recording needs about its 50 kB of samples
    assert full.value.status == 507 and "Rerun recording" in full.value.detail["message"]
    assert library.rrd_path(a.id) == rrd  # made before: served as it is
