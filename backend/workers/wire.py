"""The local transport's wire: pickled messages, each framed by its length, on a socket pair.

Why our own framing rather than `multiprocessing.Connection.recv`: a reader that takes one
message per call needs the GIL several times per message, and in a busy gateway every
acquisition waits for the thread holding it. With a class of machines a worker pushes
thousands of messages a second and a per-message reader fell behind until the worker
blocked on a full pipe. Here a reader takes whatever bytes are there in one call and
unpickles every complete message at once.
"""

from __future__ import annotations

import contextlib
import logging
import pickle
import select
import socket
import struct
from collections import deque

HEADER = struct.Struct("!I")  # payload length in bytes
# a write-behind wire holds at most this much unwritten before a write waits for the reader:
# a slow reader delays news by a tick or two, never the writer's loop, and a stuck one cannot
# grow the writer's memory without bound
MAX_UNSENT = 8 << 20
CHUNK = 1 << 18  # bytes read per call at most (into a buffer kept: a fresh one costs more)

log = logging.getLogger(__name__)


class Frames:
    """Reassembles messages from a byte stream."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes | memoryview) -> list[bytes]:
        """Add bytes; return the payloads now complete, oldest first."""
        buf = self._buf
        buf += data
        out: list[bytes] = []
        pos = 0
        while len(buf) - pos >= HEADER.size:
            (n,) = HEADER.unpack_from(buf, pos)
            end = pos + HEADER.size + n
            if end > len(buf):
                break
            out.append(bytes(buf[pos + HEADER.size : end]))
            pos = end
        if pos:
            del buf[:pos]
        return out


def frame(message: object) -> bytes:
    """One message as it goes on the wire."""
    payload = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    return HEADER.pack(len(payload)) + payload


class Wire:
    """One end of a socket pair carrying framed messages.

    Reads never block (`take`, `pending`; `wait` waits with a timeout): the worker's loop
    and the gateway's event loop both read only what is there. `queue` holds messages back
    until the next `flush`, so a tick's pushes go in one write. Writes block until written,
    or with `write_behind` (the worker's end) write what the socket takes now and keep the
    rest for the next `flush` or `wait` (up to MAX_UNSENT): a gateway busy for 20 ms must not
    stall a real-time loop for 20 ms.
    """

    def __init__(self, sock: socket.socket, write_behind: bool = False) -> None:
        self.sock = sock
        self.write_behind = write_behind
        self._unsent = bytearray()
        self.closed = False  # the other end closed (or the socket failed)
        self._frames = Frames()
        self._inbox: deque[object] = deque()
        self._chunk = memoryview(bytearray(CHUNK))
        self._outbox: list[bytes] = []

    # --- reading ----------------------------------------------------------------------------
    def wait(self, timeout_s: float) -> bool:
        """Wait up to `timeout_s` for a message (microsecond resolution, unlike a
        `poll`-based wait, which rounds up to whole milliseconds); true when one is there
        or the wire closed."""
        if self._inbox or self.closed:
            return True
        writes = [self.sock] if self._unsent else []
        try:
            readable, writable, _ = select.select([self.sock], writes, [], max(0.0, timeout_s))
        except (OSError, ValueError):
            self.closed = True
            return True
        if writable:
            self.flush()
        if readable:
            self._read(socket.MSG_DONTWAIT)
        return bool(self._inbox) or self.closed

    def take(self, limit: int | None = None) -> list[object]:
        """The messages there now (up to `limit`), without blocking, oldest first."""
        self._read(socket.MSG_DONTWAIT)
        if limit is None or len(self._inbox) <= limit:
            out = list(self._inbox)
            self._inbox.clear()
            return out
        return [self._inbox.popleft() for _ in range(limit)]

    def pending(self) -> bool:
        """A message is there (read without blocking)."""
        if not self._inbox:
            self._read(socket.MSG_DONTWAIT)
        return bool(self._inbox)

    def _read(self, flags: int) -> None:
        try:
            n = self.sock.recv_into(self._chunk, CHUNK, flags)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self.closed = True
            return
        if not n:
            self.closed = True
            return
        for payload in self._frames.feed(self._chunk[:n]):
            try:
                self._inbox.append(pickle.loads(payload))
            except Exception:  # a message we cannot unpickle: a bug, not a closed wire
                log.exception("an unreadable message on the wire (%d bytes)", len(payload))

    # --- writing ----------------------------------------------------------------------------
    def send(self, message: object) -> None:
        """Write the held-back messages and this one now."""
        self._outbox.append(frame(message))
        self.flush()

    def queue(self, message: object) -> None:
        """Hold a message back until the next `flush` (or `send`)."""
        self._outbox.append(frame(message))

    def flush(self) -> None:
        """Write what is held back (write-behind: what the socket takes without waiting)."""
        if self._outbox:
            self._unsent += b"".join(self._outbox)
            self._outbox = []
        if not self._unsent:
            return
        if self.write_behind and len(self._unsent) <= MAX_UNSENT:
            try:
                n = self.sock.send(self._unsent, socket.MSG_DONTWAIT)
            except (BlockingIOError, InterruptedError):
                n = 0
            del self._unsent[:n]
            return
        self.sock.sendall(self._unsent)
        self._unsent.clear()

    def shut(self) -> None:
        """Close this end (the other end reads its end)."""
        self.closed = True
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)
        self.sock.close()
