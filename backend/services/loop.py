"""The real-time loop: one thread that paces every machine to absolute deadlines.

Each period it wakes at `t0 + i·period`, lets every host step the cycles that are due, and
measures its work. A tick whose work runs past the next deadline is an overrun; the deadlines
it ran over are counted as missed and skipped, and the hosts catch up the cycles at the next
tick (their samples are never lost, only late).

The loop is supervised: a machine whose tick raises is logged and paused (it would fail again
every period), and the loop goes on pacing the others; a failure of the loop itself is logged
and the loop restarts. Its statistics are appended by the loop
thread and copied under a lock by `status`, which request threads call at any time.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable

import numpy as np

from api.status import LoopStatus, OverrunRecord
from backend.services.host import MachineHost

log = logging.getLogger(__name__)


class RealtimeLoop:
    """Steps hosts in real time on a dedicated thread."""

    def __init__(
        self, hosts: Callable[[], Iterable[MachineHost]], period_s: float, fast_share: float = 0.4
    ) -> None:
        self.hosts = hosts
        self.period_s = period_s
        self.fast_budget_s = period_s * fast_share  # for machines running "as fast as possible"
        self.ticks = 0
        self.overruns = 0
        self.missed = 0
        self.host_failures = 0
        self.restarts = 0
        self._stats = threading.Lock()  # the deques below: appended here, copied by status()
        self.work_s: deque[float] = deque(maxlen=5000)
        self.late_s: deque[float] = deque(maxlen=5000)
        self.recent: deque[tuple[float, float, float]] = deque(
            maxlen=20
        )  # overruns: when, late, work
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="realtime-loop", daemon=True)

    def start(self) -> None:
        # The GIL is handed over every 5 ms by default; the loop must not wait that long
        # behind request handling and telemetry encoding.
        sys.setswitchinterval(min(sys.getswitchinterval(), 0.0005))
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)

    def _run(self) -> None:
        """Pace until stopped; should the loop's own code fail, log it and pace on from now."""
        while not self._stop.is_set():
            try:
                self._pace()
            except Exception:
                self.restarts += 1
                log.exception("real-time loop failed; restarting it")

    def _pace(self) -> None:
        t0 = time.monotonic()
        i = 0
        while not self._stop.is_set():
            deadline = t0 + i * self.period_s
            delay = deadline - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            wake = time.monotonic()
            for host in list(self.hosts()):
                self._tick(host, deadline)
            done = time.monotonic()
            i += 1
            next_deadline = t0 + i * self.period_s
            with self._stats:
                self.ticks += 1
                self.work_s.append(done - wake)
                self.late_s.append(wake - deadline)
                if done > next_deadline:
                    self.overruns += 1
                    self.recent.append((time.time(), wake - deadline, done - wake))
                    skip = int((done - next_deadline) / self.period_s)
                    self.missed += skip
                    i += skip

    def _tick(self, host: MachineHost, deadline: float) -> None:
        try:
            host.tick(deadline, self.fast_budget_s)
        except Exception:
            self.host_failures += 1
            log.exception("machine %s failed in the real-time loop; pausing it", host.id)
            host.set_mode("pause")

    def status(self) -> LoopStatus:
        """The loop's figures, from a consistent copy (the loop thread keeps appending)."""
        with self._stats:
            work_s, late_s, recent = list(self.work_s), list(self.late_s), list(self.recent)
            ticks, overruns, missed = self.ticks, self.overruns, self.missed
        work = np.array(work_s) * 1e3 if work_s else np.zeros(1)
        late = np.array(late_s) * 1e3 if late_s else np.zeros(1)
        return LoopStatus(
            period_s=self.period_s,
            ticks=ticks,
            overruns=overruns,
            missed_deadlines=missed,
            work_p50_ms=float(np.percentile(work, 50)),
            work_p99_ms=float(np.percentile(work, 99)),
            work_max_ms=float(work.max()),
            wake_late_p99_ms=float(np.percentile(late, 99)),
            recent_overruns=[
                OverrunRecord(time_unix=t, wake_late_ms=lt * 1e3, work_ms=w * 1e3)
                for t, lt, w in recent
            ],
            host_failures=self.host_failures,
            restarts=self.restarts,
        )
