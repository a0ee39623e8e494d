"""The local transport's wire: a write-behind end (the worker's) never waits for a reader that
is busy, delivers every message in order once the reader reads, and holds at most
MAX_UNSENT before it waits after all."""

from __future__ import annotations

import socket
import threading

from backend.workers.wire import MAX_UNSENT, Wire

PAYLOAD = b"x" * 100_000


def test_a_write_behind_flush_returns_while_the_reader_is_busy_and_loses_nothing() -> None:
    a, b = socket.socketpair()
    writer, reader = Wire(a, write_behind=True), Wire(b)

    def write() -> None:  # 5 MB: far more than a socket pair buffers, less than MAX_UNSENT
        for i in range(50):
            writer.queue((i, PAYLOAD))
            writer.flush()

    t = threading.Thread(target=write, daemon=True)
    t.start()
    t.join(5.0)
    assert not t.is_alive()  # nobody read meanwhile: a write that waits would still wait
    got: list[object] = []
    while len(got) < 50:
        writer.wait(0.01)  # the writer's loop waiting: it writes what the socket takes
        got += reader.take()
    assert [m[0] for m in got] == list(range(50))  # type: ignore[index]
    assert all(m[1] == PAYLOAD for m in got)  # type: ignore[index]
    a.close()
    b.close()


def test_a_write_behind_end_waits_for_the_reader_beyond_its_bound() -> None:
    a, b = socket.socketpair()
    writer, reader = Wire(a, write_behind=True), Wire(b)
    n = (2 * MAX_UNSENT) // len(PAYLOAD)
    got: list[object] = []
    done = threading.Event()

    def read() -> None:
        while len(got) < n:
            reader.wait(0.05)
            got.extend(reader.take())
        done.set()

    for i in range(n):
        writer.queue((i, PAYLOAD))
    # one flush of twice the bound: it must hand everything to the socket (waiting for the
    # reader), so the writer's memory stays bounded
    t = threading.Thread(target=read, daemon=True)
    t.start()
    writer.flush()
    assert writer._unsent == bytearray()
    assert done.wait(10.0)
    assert [m[0] for m in got] == list(range(n))  # type: ignore[index]
    a.close()
    b.close()
