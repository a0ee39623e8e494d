"""A re-entrant lock that long work hands over between its slices.

Python's locks are not fair: a thread that releases a lock and takes it again at once usually
wins against the threads waiting for it, so slicing long work alone would not let an
emergency stop in. This lock counts who waits; long work calls `hand_over` between slices
(without holding the lock) and continues only when everyone who was waiting got in.
"""

from __future__ import annotations

import threading
from types import TracebackType

HAND_OVER_TIMEOUT_S = 1.0  # a waiter that never takes the lock cannot stall the work longer


class HandoverLock:
    """`with lock:` like `threading.RLock`, plus `hand_over` for long work."""

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self._state = threading.Condition(threading.Lock())
        self._waiting = 0  # threads inside __enter__ that do not hold the lock yet
        self._entries = 0  # acquisitions so far

    def __enter__(self) -> HandoverLock:
        with self._state:
            self._waiting += 1
        self._lock.acquire()
        with self._state:
            self._waiting -= 1
            self._entries += 1
            self._state.notify_all()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._lock.release()

    def hand_over(self) -> None:
        """Let every thread waiting now take the lock before we take it again (call without
        holding it)."""
        with self._state:
            target = self._entries + self._waiting
            self._state.wait_for(lambda: self._entries >= target, HAND_OVER_TIMEOUT_S)
