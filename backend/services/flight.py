"""The flight recorder: what every machine did in the seconds before something went wrong.

Two tiers, both bounded. The full-rate tier is the machine's sample ring itself (every
signal, every cycle, the last 16 s, which the worker writes anyway). The long tier is kept
here: the machine's main signals (per axis the command, actual value, lag and velocity or
speed; the channel's state and path feed), one sample in `decimation` cycles, for `minutes`.
Its memory: channels × minutes·60 / (decimation · cycle_s) × 8 bytes per machine, 17 × 30 000
× 8 B = 4.1 MB for the demo lathe at the defaults (5 min at 100 Hz).

On every job error the machine's worker copies `before_s` of the main signals at full rate
from its ring in the cycle it steps past the error, then the `after_s` that follow as it
steps them, and pushes the window once the machine has run past its end
(backend/workers/flight.py): nothing of it is lost however fast the simulation runs or
however long the gateway is short of CPU. The recorder saves the window as a trace of the
library (source 'flight', the error as its trigger, the events of the window with it) and
links the job error's history entry to it; where the library refuses it (full), the history
says it was not saved. Errors within an open window share its trace. Each machine keeps
its newest `keep` such traces; older ones are deleted. On demand it saves the last seconds:
from the ring at full rate while they fit in it, from the long tier beyond.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
import uuid
from dataclasses import dataclass

import numpy as np

from api.flight import FlightRecorderStatus
from api.scope import ChannelInfo, TraceDetail, TraceInfo
from backend.errors import ApiError, Invalid
from backend.services.commands import job_error_model
from backend.services.history import History
from backend.services.machines import MachineProxy, MachineService
from backend.services.traces import Trace, TraceService, param_diff
from backend.workers.flight import FlightWindow, main_signals
from backend.workers.protocol import param_snapshot
from backend.workers.ring import RING_CYCLES
from nc_sim.events import EVENT_LOG_LEN, Event
from nc_sim.signals import Signal

log = logging.getLogger(__name__)

PERIOD_S = 1.0  # how often the long tier is fed (the ring holds 16 s: fewer, longer reads)
BY = "flight recorder"  # whom its traces count for in the library
RING_MARGIN = 500  # cycles of the ring left alone: the worker may be writing them


@dataclass
class _Tape:
    """One machine's long tier: a ring of decimated samples of its main signals."""

    epoch: int
    signals: list[Signal]
    data: np.ndarray  # channels × slots
    next_cycle: int  # the next cycle to take (a multiple of the decimation)
    count: int = 0  # samples taken in all (the newest is at (count - 1) % slots)

    def take(self, block: np.ndarray, first: int, decimation: int) -> None:
        slots = self.data.shape[1]
        n = block.shape[1]
        at = (self.count + np.arange(n)) % slots
        self.data[:, at] = block
        self.count += n
        self.next_cycle = first + n * decimation

    def last(self, samples: int) -> tuple[np.ndarray, int]:
        """The newest `samples` (fewer if it holds fewer), and how many."""
        n = min(samples, self.count, self.data.shape[1])
        at = (self.count - n + np.arange(n)) % self.data.shape[1]
        return self.data[:, at], n


class FlightRecorder:
    """Every machine's flight recorder (one thread for all)."""

    def __init__(
        self,
        machines: MachineService,
        traces: TraceService,
        history: History,
        minutes: float,
        decimation: int,
        keep: int,
    ) -> None:
        """The windows around job errors as long as `machines.flight_s` says (its workers
        copy them), the long tier `minutes` long, one sample in `decimation` cycles."""
        self.machines, self.traces, self.history = machines, traces, history
        self.before_s, self.after_s = machines.flight_s or (0.0, 0.0)
        self.minutes, self.decimation, self.keep = minutes, decimation, keep
        self.saved = 0  # traces saved automatically
        self._tapes: dict[str, _Tape] = {}
        # windows pushed, to save: (machine, its epoch then, the window)
        self._windows: list[tuple[str, int, FlightWindow]] = []
        self._lock = threading.Lock()
        self._feeding = threading.Lock()  # one feed at a time: the thread's, or a save's
        self._stop = threading.Event()
        self._wake = threading.Event()  # a window came (or the recorder stops): save it now
        self._thread = threading.Thread(target=self._run, name="flight-recorder", daemon=True)
        machines.on_flights = self.windows

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        self._thread.join(timeout=5.0)

    def status(self, m: MachineProxy) -> FlightRecorderStatus:
        """What the recorder keeps of the machine."""
        with self._lock:
            tape = self._tapes.get(m.id)
            held = min(tape.count, tape.data.shape[1]) if tape is not None else 0
            nbytes = tape.data.nbytes if tape is not None else 0
        cycle_s = m.link.cycle_s
        full = min(m.link.cycle, RING_CYCLES - RING_MARGIN) * cycle_s
        return FlightRecorderStatus(
            before_s=self.before_s,
            after_s=self.after_s,
            full_rate_s=full,
            held_s=max(full, held * self.decimation * cycle_s),
            reach_s=self.minutes * 60.0,
            decimation=self.decimation,
            bytes=nbytes,
            keep=self.keep,
        )

    # --- job errors ----------------------------------------------------------------------
    def windows(self, mid: str, epoch: int, windows: list[FlightWindow]) -> None:
        """A machine's completed job error windows (its worker's push thread): saved on the
        recorder's thread (a save writes files)."""
        with self._lock:
            self._windows += [(mid, epoch, w) for w in windows]
        self._wake.set()

    # --- the thread --------------------------------------------------------------------------
    def _run(self) -> None:
        next_feed = time.monotonic()
        while not self._stop.is_set():
            with self._lock:
                windows, self._windows = self._windows, []
            for mid, epoch, window in windows:
                proxy = self.machines.find(mid)
                if proxy is None:  # deleted meanwhile
                    continue
                try:
                    self._keep(proxy, epoch, window)
                except Exception:  # one machine's failure must not stop the others' recorder
                    log.exception("flight recorder of %s", mid)
            if time.monotonic() >= next_feed:
                next_feed = time.monotonic() + PERIOD_S
                self._feed_all()
            self._wake.wait(max(0.0, next_feed - time.monotonic()))
            self._wake.clear()

    def _feed_all(self) -> None:
        proxies = self.machines.proxies()
        with self._lock:  # a deleted machine's tier goes with it
            live = {p.id for p in proxies}
            for mid in [mid for mid in self._tapes if mid not in live]:
                del self._tapes[mid]
        for proxy in proxies:
            try:
                self._feed(proxy)
            except Exception:  # one machine's failure must not stop the others' recorder
                log.exception("flight recorder of %s", proxy.id)

    def _feed(self, m: MachineProxy) -> None:
        """Take the cycles the machine ran since the last feed into its long tier (those the
        ring still holds)."""
        with self._feeding:
            self._feed_now(m)

    def _feed_now(self, m: MachineProxy) -> None:
        link = m.link
        if link.ring is None or link.info is None:
            return
        with self._lock:
            tape = self._tapes.get(m.id)
            if tape is None or tape.epoch != link.epoch:
                signals = main_signals(link.signals)
                slots = max(1, round(self.minutes * 60 / (self.decimation * link.cycle_s)))
                tape = _Tape(link.epoch, signals, np.zeros((len(signals), slots)), 0)
                self._tapes[m.id] = tape
        head = link.cycle
        first = max(tape.next_cycle, head - RING_CYCLES + RING_MARGIN)
        first += -first % self.decimation
        if head < first:
            return
        block, got = link.samples(tape.signals, first, head, self.decimation)
        with self._lock:
            if tape.epoch == link.epoch:
                tape.take(block, got, self.decimation)

    def _keep(self, m: MachineProxy, epoch: int, w: FlightWindow) -> None:
        """Save a window and link its errors' history entries to it."""
        try:
            info = self._save(m, w)
        except ApiError as e:  # the library is full: say so in the history
            self.history.flight_failed(m, w.trigger, str(e))
            return
        self.saved += 1
        self.history.link_trace(m.id, epoch, w.errors, info.id)
        self._forget_old(m.id)

    # --- saving --------------------------------------------------------------------------------
    def _save(self, m: MachineProxy, w: FlightWindow) -> TraceInfo:
        e = w.trigger
        what = f"job error {e.code}{' ' + e.axis if e.axis else ''}"
        stamp = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(w.seen_unix))
        trace = self._trace(
            m, w.signals, w.data, w.first_cycle, m.link.cycle_s, e.cycle, what, w.events
        )
        trace.detail.name = f"{what} at {stamp}"
        trace.detail.notes = f"saved by the flight recorder: {e.message}"
        return self.traces.add(trace, BY)

    def save_last(self, m: MachineProxy, seconds: float, by: str) -> TraceInfo:
        """The last `seconds` as a trace in the library: at full rate while the sample ring
        holds them, decimated from the long tier beyond, which first takes the cycles since
        its last feed (about a second ago), so the trace ends now (422 while it holds
        nothing yet)."""
        link = m.link
        head, cycle_s = link.cycle, link.cycle_s
        span = round(seconds / cycle_s)
        stamp = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
        name = f"last {seconds:g} s at {stamp}"
        if span <= RING_CYCLES - RING_MARGIN:
            signals = main_signals(link.signals)
            data, first = link.samples(signals, max(1, head - span + 1), head, 1)
            trace = self._trace(m, signals, data, first, cycle_s, None, "on demand")
        else:
            self._feed(m)
            with self._lock:
                tape = self._tapes.get(m.id)
                if tape is None or tape.epoch != link.epoch or not tape.count:
                    raise Invalid("the flight recorder holds nothing of this machine yet")
                data, n = tape.last(round(span / self.decimation))
                signals, next_cycle = tape.signals, tape.next_cycle
            first = next_cycle // self.decimation - n  # in the trace's own, coarser cycles
            trace = self._trace(
                m, signals, data.copy(), first, cycle_s * self.decimation, None, "on demand"
            )
            name += f" (1 in {self.decimation} cycles)"
        trace.detail.name = name
        trace.detail.notes = f"saved from the flight recorder by {by}"
        return self.traces.add(trace, by)

    def _trace(
        self,
        m: MachineProxy,
        signals: list[Signal],
        data: np.ndarray,
        first: int,
        cycle_s: float,
        trigger_cycle: int | None,
        trigger: str,
        events: list[Event] | None = None,
    ) -> Trace:
        """A trace of samples `first`.. in cycles of `cycle_s` (the machine's, or a multiple
        of it for decimated samples: the events' cycles are counted in the same), with the
        `events` of its span (None: those the gateway's copy of the machine's log holds)."""
        per = max(1, round(cycle_s / m.link.cycle_s))
        last = first + data.shape[1] - 1
        if events is None:
            events = [
                e
                for e in m.link.recent_events(EVENT_LOG_LEN)
                if first * per <= e.cycle <= last * per
            ]
        with m.lock:
            params = param_diff(param_snapshot(m.cfg))
        detail = TraceDetail(
            id=uuid.uuid4().hex[:12],
            machine=m.id,
            machine_name=m.name,
            name="",
            notes="",
            source="flight",
            stored=False,
            trigger=trigger,
            forced=False,
            created_unix=time.time(),
            first_cycle=first,
            trigger_cycle=trigger_cycle,
            count=int(data.shape[1]),
            cycle_s=cycle_s,
            channels=[ChannelInfo(name=s.name, unit=s.unit, kind=s.kind) for s in signals],
            params_changed=len(params),
            params=params,
            events=[
                job_error_model(e).model_copy(update={"cycle": e.cycle // per}) for e in events
            ],
        )
        return Trace(detail, data)

    def _forget_old(self, mid: str) -> None:
        """Keep the machine's newest `keep` traces of the recorder (a renamed one stays)."""
        mine = [
            t
            for t in self.traces.library(mid)
            if t.source == "flight" and t.name.startswith("job error")
        ]
        for t in mine[self.keep :]:  # the library lists newest first
            with contextlib.suppress(ApiError):  # deleted meanwhile
                self.traces.delete(t.id)
