"""The flight recorder: what every machine did in the seconds before something went wrong.

Two tiers, both bounded. The full-rate tier is the machine's sample ring itself (every
signal, every cycle, the last 16 s, which the worker writes anyway). The long tier is kept
here: the machine's main signals (per axis the command, actual value, lag and velocity or
speed; the channel's state and path feed), one sample in `decimation` cycles, for `minutes`.
Its memory: channels × minutes·60 / (decimation · cycle_s) × 8 bytes per machine, 17 × 30 000
× 8 B = 4.1 MB for the demo lathe at the defaults (5 min at 100 Hz).

On every job error the recorder copies `before_s` of the main signals at full rate from the
ring when it hears of the error, the `after_s` that follow as they are written (every 20 ms
while a window is open: a fast simulation laps the ring in well under a second), then saves
the window as a trace of the library (source 'flight', the error as its trigger, the events
of the window with it) and links the job error's history entry to it. Where the ring was
lapped before the error was heard (fast, on a loaded machine), the history says it was not
saved. Errors within a window already being saved share its trace. Each
machine keeps its newest `keep` such traces; older ones are deleted. On demand it saves the
last seconds: from the ring at full rate while they fit in it, from the long tier beyond.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
import uuid
from dataclasses import dataclass, field

import numpy as np

from api.flight import FlightRecorderStatus
from api.scope import ChannelInfo, TraceDetail, TraceInfo
from backend.errors import ApiError, Invalid
from backend.services.commands import job_error_model
from backend.services.history import History
from backend.services.machines import MachineProxy, MachineService
from backend.services.traces import Trace, TraceService, param_diff
from backend.workers.link import MachineLink
from backend.workers.protocol import param_snapshot
from backend.workers.ring import RING_CYCLES
from nc_sim.events import EVENT_LOG_LEN, Event
from nc_sim.signals import CHANNEL, Signal

log = logging.getLogger(__name__)

# how often the long tier is fed and pending saves are looked at: the ring holds 16 s, and
# fewer, longer reads cost the gateway less (an open window is looked at every 20 ms)
PERIOD_S = 1.0
# while a window is open (a fast simulation runs through the ring's 16 s in a quarter
# second): the machines with one, and they alone, are looked at this often
PENDING_PERIOD_S = 0.02
BY = "flight recorder"  # whom its traces count for in the library
RING_MARGIN = 500  # cycles of the ring left alone: the worker may be writing them
_MAIN = ("speed_cmd_rpm", "speed_act_rpm", "pos_cmd_", "pos_act_", "lag_", "vel_cmd_", "vel_act_")
_CHANNEL_MAIN = (f"{CHANNEL}.state", f"{CHANNEL}.path_feed_mm_min")


def main_signals(signals: list[Signal]) -> list[Signal]:
    """The signals the recorder keeps: per axis command, actual value, lag and velocity or
    speed; the channel's state and path feed."""
    return [
        s for s in signals if s.name in _CHANNEL_MAIN or s.name.split(".", 1)[-1].startswith(_MAIN)
    ]


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


@dataclass
class _Pending:
    """A window to save once the machine has run past its end, and what of it is copied
    already: a fast simulation runs through the ring in seconds, so the window is copied
    as it comes (when the error is heard, then at each look), not only at its end."""

    epoch: int
    trigger: Event
    first: int
    last: int
    errors: list[Event] = field(default_factory=list)
    seen_unix: float = 0.0  # when the error was heard: its wall clock
    parts: list[np.ndarray] = field(default_factory=list)  # copied samples, in order
    got_first: int = 0  # the cycle of the first copied sample
    next_cycle: int = 0  # the next cycle to copy (0: none copied yet)

    def gather(self, link: MachineLink, signals: list[Signal]) -> None:
        """Copy what the ring holds of the window and was not copied yet. Samples the ring
        lost before they were copied leave the trace starting after them (never a gap)."""
        head = link.cycle
        lo = max(self.next_cycle or self.first, head - RING_CYCLES + RING_MARGIN)
        hi = min(self.last, head)
        if hi < lo:
            return
        block, got = link.samples(signals, lo, hi, 1)
        if not block.shape[1]:
            return
        if got != self.next_cycle:  # the first copy, or older samples were lost: start here
            self.parts, self.got_first = [], got
        self.parts.append(block.copy())
        self.next_cycle = got + block.shape[1]


class FlightRecorder:
    """Every machine's flight recorder (one thread for all)."""

    def __init__(
        self,
        machines: MachineService,
        traces: TraceService,
        history: History,
        before_s: float,
        after_s: float,
        minutes: float,
        decimation: int,
        keep: int,
    ) -> None:
        self.machines, self.traces, self.history = machines, traces, history
        self.before_s, self.after_s = before_s, after_s
        self.minutes, self.decimation, self.keep = minutes, decimation, keep
        self.saved = 0  # traces saved automatically
        self._tapes: dict[str, _Tape] = {}
        self._pending: dict[str, list[_Pending]] = {}
        self._lock = threading.Lock()
        self._feeding = threading.Lock()  # one feed at a time: the thread's, or a save's
        self._stop = threading.Event()
        self._wake = threading.Event()  # a window opened (or the recorder stops): look now
        self._thread = threading.Thread(target=self._run, name="flight-recorder", daemon=True)
        machines.event_takers.append(self.events)

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
    def events(self, mid: str, epoch: int, events: list[Event]) -> None:
        """A machine's new events (its worker's push thread): each job error opens a window
        to save, or joins the one still open."""
        errors = [e for e in events if e.error]
        if not errors:
            return
        proxy = self.machines.find(mid)
        if proxy is None:
            return
        before = round(self.before_s / proxy.link.cycle_s)
        after = round(self.after_s / proxy.link.cycle_s)
        now = time.time()
        with self._lock:
            pending = self._pending.setdefault(mid, [])
            for e in errors:
                open_ = next((p for p in pending if p.epoch == epoch and e.cycle <= p.last), None)
                if open_ is None:
                    first = max(1, e.cycle - before)
                    pending.append(_Pending(epoch, e, first, e.cycle + after, [e], now))
                else:
                    open_.errors.append(e)
            if proxy.link.epoch == epoch and proxy.link.ring is not None:
                signals = main_signals(proxy.link.signals)
                for p in pending:  # the seconds before, while the ring still holds them
                    if p.epoch == epoch:
                        p.gather(proxy.link, signals)
        self._wake.set()

    # --- the thread --------------------------------------------------------------------------
    def _run(self) -> None:
        last_full = 0.0
        while True:
            self._wake.wait(PENDING_PERIOD_S if any(self._pending.values()) else PERIOD_S)
            self._wake.clear()
            if self._stop.is_set():
                return
            proxies = self.machines.proxies()
            if time.monotonic() - last_full < PERIOD_S:  # a quick look: open windows only
                for proxy in [p for p in proxies if self._pending.get(p.id)]:
                    with contextlib.suppress(Exception):  # the full look says what fails
                        self._due(proxy)
                continue
            last_full = time.monotonic()
            with self._lock:  # a deleted machine's tier goes with it
                live = {p.id for p in proxies}
                for mid in [mid for mid in self._tapes if mid not in live]:
                    del self._tapes[mid]
                for mid in [mid for mid in self._pending if mid not in live]:
                    del self._pending[mid]
            for proxy in proxies:
                try:
                    self._feed(proxy)
                    self._due(proxy)
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

    def _due(self, m: MachineProxy) -> None:
        head, epoch = m.link.cycle, m.link.epoch
        with self._lock:
            pending = self._pending.get(m.id, [])
            if m.link.ring is not None:
                signals = main_signals(m.link.signals)
                for p in pending:
                    if p.epoch == epoch:
                        p.gather(m.link, signals)
            due = [p for p in pending if p.epoch != epoch or p.last <= head]
            self._pending[m.id] = [p for p in pending if p not in due]
        for p in due:
            if p.epoch != epoch:  # powered on again before its window ended: lost with it
                continue
            try:
                info = self._save(m, p)
            except ApiError as e:  # the library is full: say so in the history
                self.history.flight_failed(m, p.trigger, str(e))
                continue
            self.saved += 1
            self.history.link_trace(m.id, epoch, p.errors, info.id)
            self._forget_old(m.id)

    # --- saving --------------------------------------------------------------------------------
    def _save(self, m: MachineProxy, p: _Pending) -> TraceInfo:
        e = p.trigger
        signals = main_signals(m.link.signals)
        if not p.parts:
            raise Invalid("the sample ring had run past the error before it could be copied")
        data = np.concatenate(p.parts, axis=1)
        what = f"job error {e.code}{' ' + e.axis if e.axis else ''}"
        stamp = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(p.seen_unix))
        trace = self._trace(m, signals, data, p.got_first, m.link.cycle_s, e.cycle, what)
        trace.detail.name = f"{what} at {stamp}"
        trace.detail.notes = f"saved by the flight recorder: {e.message}"
        return self.traces.add(trace, BY)

    def save_last(self, m: MachineProxy, seconds: float, by: str) -> TraceInfo:
        """The last `seconds` as a trace in the library: at full rate while the sample ring
        holds them, decimated from the long tier beyond, which first takes the cycles since
        its last feed (a second ago at most, longer while a job error's window is saved), so
        the trace ends now (422 while it holds nothing yet)."""
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
    ) -> Trace:
        """A trace of samples `first`.. in cycles of `cycle_s` (the machine's, or a multiple
        of it for decimated samples: the events' cycles are counted in the same)."""
        per = max(1, round(cycle_s / m.link.cycle_s))
        last = first + data.shape[1] - 1
        events = [
            e for e in m.link.recent_events(EVENT_LOG_LEN) if first * per <= e.cycle <= last * per
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
