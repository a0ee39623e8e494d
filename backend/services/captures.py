"""A machine's scope in the gateway: the setup as the client asked it, and the completed
captures (records with the parameter lists of their time) kept until saved to the library."""

from __future__ import annotations

import threading
import time
import uuid
from collections import deque
from dataclasses import dataclass

from backend.workers.protocol import ParamSnapshot
from nc_sim.scope import Record

RECENT_CAPTURES = 16  # completed captures kept in memory until saved to the library


@dataclass
class Capture:
    """A completed scope record with what the machine was at the time."""

    id: str
    record: Record
    params: ParamSnapshot
    created_unix: float


class Captures:
    """One machine's recent captures (newest last) and its scope setup."""

    def __init__(self) -> None:
        self.setup: object | None = None  # the ScopeSetupModel as the client asked
        # whose it is while armed: (user, role, session) and when they armed it
        self.owner: tuple[str, str, str] | None = None
        self.armed_unix: float | None = None
        self._recent: deque[Capture] = deque(maxlen=RECENT_CAPTURES)
        self._lock = threading.Lock()

    def add(self, records: list[tuple[Record, ParamSnapshot]]) -> None:
        """Records the worker completed (each gets an id)."""
        with self._lock:
            for rec, params in records:
                self._recent.append(Capture(uuid.uuid4().hex[:12], rec, params, time.time()))

    def recent(self) -> list[Capture]:
        """The recent captures, oldest first."""
        with self._lock:
            return list(self._recent)

    def find(self, cid: str) -> Capture | None:
        return next((c for c in self.recent() if c.id == cid), None)
