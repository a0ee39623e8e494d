"""What every viewer of a machine must see as a banner (rebuilt, restored, frozen, a message
of the instructor), numbered per machine so that each viewer gets each once."""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass

from api.telemetry import NoticeKind

KEPT = 16  # a viewer that reconnects sees the newest of these again


@dataclass(frozen=True)
class Notice:
    """Something every viewer of a machine must see (a banner), numbered per machine."""

    seq: int
    kind: NoticeKind
    message: str
    time_unix: float


class Notices:
    """One machine's newest notices."""

    def __init__(self) -> None:
        self._kept: deque[Notice] = deque(maxlen=KEPT)
        self._lock = threading.Lock()

    def add(self, kind: NoticeKind, message: str) -> None:
        with self._lock:
            seq = self._kept[-1].seq + 1 if self._kept else 1
            self._kept.append(Notice(seq, kind, message, time.time()))

    @property
    def newest_seq(self) -> int:
        """The number of the newest notice (0 before the first)."""
        with self._lock:
            return self._kept[-1].seq if self._kept else 0

    def since(self, seq: int) -> list[Notice]:
        """The notices after number `seq`, oldest first."""
        with self._lock:
            return [n for n in self._kept if n.seq > seq]
