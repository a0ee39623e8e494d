"""Held jogs as the audit sees them: the HMI renews a held jog's start every few hundred
milliseconds, and the audit trail records the start once, not every renewal."""

from __future__ import annotations

import time

RENEWAL_S = 1.0  # the same start again within this is a renewal

Key = tuple[str, str, str]  # (axis, session, client)


class JogLeases:
    """One machine's held jogs: (axis, session, client) -> (direction, feed, when)."""

    def __init__(self) -> None:
        self._held: dict[Key, tuple[int, float | None, float]] = {}

    def start(self, key: Key, direction: int, feed_mm_min: float | None) -> bool:
        """A jog start; True when it renews the same jog within RENEWAL_S (not audited)."""
        now, last = time.monotonic(), self._held.get(key)
        self._held[key] = (direction, feed_mm_min, now)
        return (
            last is not None and last[:2] == (direction, feed_mm_min) and now - last[2] < RENEWAL_S
        )

    def stop(self, key: Key) -> None:
        """The jog ended: the next start is a new one."""
        self._held.pop(key, None)
