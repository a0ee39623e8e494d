"""The trace library's files: the samples are on disk, whole and synced, before the row that
points at them is committed; a failed save leaves neither a row nor a file behind."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

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
    info = library.add(trace)
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
        library.add(from_csv("cycle,a\n1,2\n2,3\n"))
    assert list(library.dir.iterdir()) == [] and library.library() == []

    def half_written(f: Any, _data: Any) -> None:
        f.write(b"\x93NUMPY")
        raise OSError(28, "No space left on device")

    monkeypatch.undo()
    monkeypatch.setattr(np, "save", half_written)
    with pytest.raises(OSError):
        library.add(from_csv("cycle,a\n1,2\n2,3\n"))
    assert list(library.dir.iterdir()) == [] and library.library() == []
