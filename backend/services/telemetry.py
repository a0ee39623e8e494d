"""Telemetry fan-out: every frame period, each subscriber gets the samples of every cycle
since its last frame, as one binary frame, and as JSON the new events, the machine's newest
status (pushed by its worker while somebody watches) and notices such as a rebuild.

Samples come from the machine's sample ring (shared memory its worker writes), events and
status from what the worker pushed: nothing here asks a worker anything.

One hub task builds frames; each subscriber has at most one send in flight. A subscriber still
busy sending when its next frame is due is skipped for that period (it never holds up the loop
or anyone else) and later gets the larger range, decimated when it exceeds
`max_frame_samples`; cycles that left the ring meanwhile are reported as skipped. Subscribers
with the same signals and range share one encoded frame. A subscriber that redraws less often
asks for frames less often (`frame_s`): fewer, larger frames, the same samples.

Every client is bounded: at most `MAX_PENDING_REPLIES` control replies wait for it, and a send
that has not finished within `stall_s` ends the connection (close code 1008), so a client that
sends but never reads cannot grow the server's memory. A client that reads nothing at all is
found sooner by the server's websocket keepalive (no pong within `stall_s`: 1008 as well),
counted as dropped too. The hub task is supervised: a failure
while serving one client closes that client (1011); a failure of the hub itself is logged and
the hub restarts, so no client can stop telemetry for the others.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field

from fastapi import WebSocket

from api.status import TelemetryStatus
from api.telemetry import (
    ErrorMessage,
    EventMessage,
    FrameHeader,
    Hello,
    HistoryMessage,
    NoticeMessage,
    StatusMessage,
    Subscribe,
    Subscribed,
    encode_frame,
)
from backend.services.auth import Actor
from backend.services.commands import job_error_model
from backend.services.history import History
from backend.services.machines import MachineProxy
from backend.services.status import RECENT_EVENTS, status_of
from backend.tasks import cancel
from nc_sim.signals import Signal

log = logging.getLogger(__name__)

MAX_PENDING_REPLIES = 16  # control replies a client may leave unread before it is dropped
# websocket close codes (RFC 6455 7.4.1)
CLOSE_POLICY = 1008  # does not read, or floods us with messages
CLOSE_INTERNAL = 1011  # serving this client failed


@dataclass(frozen=True)
class Built:
    """An encoded frame and where its subscribers continue."""

    frame: bytes
    next_cursor: int


@dataclass(eq=False)
class Subscriber:
    """One websocket watching one machine."""

    ws: WebSocket
    machine: MachineProxy
    actor: Actor
    signals: list[Signal] = field(default_factory=list)
    min_stride: int = 1
    frame_s: float = 0.0  # asked for: a frame at most this often (0: every hub period)
    frame_due: float = 0.0  # event-loop time from which the next frame may go
    cursor: int = 0  # next cycle to send
    event_cursor: int = 0  # sequence number of the next event to send
    epoch: int = 0
    status_seq: int = 0  # the newest pushed status sent
    control_seq: int = -1  # the machine's control state sent with it
    notice_seq: int = 0  # the newest notice sent
    history_cursor: int = 0  # the machine's live history entries sent
    control: list[str] = field(default_factory=list)  # JSON replies, sent before the next frame
    sending: asyncio.Task[None] | None = None
    send_started: float = 0.0  # event-loop time the send in flight began
    busy_periods: int = 0
    closed: bool = False
    dropped: bool = False  # closed by us, and counted

    def subscribe(self, req: Subscribe) -> None:
        """Stream these signals from the current cycle (also after a reconnect; the same
        stream again at another frame period goes on where it was); the reply, `subscribed` or
        `error`, goes out before the next frame."""
        m = self.machine
        unknown = [n for n in req.signals if n not in m.link.signal_by_name]
        if unknown:
            more = f" and {len(unknown) - 10} more" if len(unknown) > 10 else ""
            self.reply(ErrorMessage(message=f"unknown signals: {unknown[:10]}{more}"))
            return
        signals = [m.link.signal_by_name[n] for n in req.signals]
        rate = req.max_rate_hz or math.inf  # bounded by the protocol (api/telemetry.py)
        min_stride = max(1, math.ceil(1.0 / (m.link.cycle_s * rate)))
        self.frame_s, self.frame_due = req.frame_s or 0.0, 0.0
        # the same stream at another frame period goes on without a gap; else from now
        if (signals, min_stride, self.epoch) != (self.signals, self.min_stride, m.link.epoch):
            self.cursor = m.link.cycle + 1
        self.signals, self.min_stride, self.epoch = signals, min_stride, m.link.epoch
        self.reply(
            Subscribed(signals=req.signals, first_cycle=self.cursor - 1, stride=self.min_stride)
        )

    def reply(self, msg: Hello | Subscribed | ErrorMessage) -> None:
        """Queue a JSON control message; the hub is the only sender on the socket."""
        self.control.append(msg.model_dump_json())

    @property
    def flooding(self) -> bool:
        """More replies wait than a reading client ever leaves: it sends but does not read."""
        return len(self.control) > MAX_PENDING_REPLIES


class TelemetryHub:
    """Builds and sends frames for every subscriber."""

    def __init__(
        self,
        frame_s: float,
        max_frame_samples: int,
        stall_s: float = 10.0,
        history: History | None = None,
    ) -> None:
        self.frame_s = frame_s
        self.history = history
        self.max_frame_samples = max_frame_samples
        self.stall_s = stall_s
        self.subscribers: set[Subscriber] = set()
        self.frames_sent = 0
        self.clients_dropped = 0  # closed by us: not reading, flooding, bad messages, failures
        self.restarts = 0  # times the hub task failed and was restarted
        self._task: asyncio.Task[None] | None = None
        # who watches which machine (the control of a machine lapses without its holder)
        self.on_connect: Callable[[Actor, MachineProxy], None] = lambda actor, m: None
        self.on_disconnect: Callable[[Actor, MachineProxy], None] = lambda actor, m: None

    def add(self, ws: WebSocket, m: MachineProxy, actor: Actor) -> Subscriber:
        """A new viewer of `m`: from now on its worker pushes the machine's status."""
        # the newest events first, as event messages: the viewer's log starts filled
        events = max(0, m.link.events.cursor - RECENT_EVENTS)
        sub = Subscriber(
            ws, m, actor, cursor=m.link.cycle + 1, event_cursor=events, epoch=m.link.epoch
        )
        self.on_connect(actor, m)
        sub.notice_seq = max(0, m.notices.newest_seq - 1)  # the newest notice again
        if self.history is not None:  # the older ones the viewer reads by REST
            sub.history_cursor = self.history.newest(m.id)
        self.subscribers.add(sub)
        m.link.watch(True)
        return sub

    def remove(self, sub: Subscriber) -> None:
        if sub in self.subscribers:
            m = sub.machine
            self.on_disconnect(sub.actor, m)
            m.link.watch(False)
        sub.closed = True
        self.subscribers.discard(sub)

    def _detach(self, sub: Subscriber) -> bool:
        """Stop serving a client we close: no more sends, its send in flight cancelled."""
        if sub.closed:
            return False
        self.remove(sub)
        sub.dropped = True
        self.clients_dropped += 1
        if sub.sending is not None:
            sub.sending.cancel()
        return True

    def lost(self, sub: Subscriber, code: int) -> None:
        """The connection ended under us: by the server's keepalive (no pong in time: the
        client reads nothing, 1008) counts as dropped, as a client we close for not reading."""
        if code == CLOSE_POLICY and not sub.dropped:  # a failed send may have closed it first
            sub.dropped = True
            self.clients_dropped += 1
        self.remove(sub)

    async def end(self, sub: Subscriber, code: int, reason: str) -> None:
        """End a client's connection with this close code (from its route handler)."""
        if self._detach(sub):
            await self._close(sub.ws, code, reason)

    def drop(self, sub: Subscriber, code: int, reason: str) -> None:
        """`end` without waiting for the close handshake (from the hub's tick)."""
        if self._detach(sub):
            sub.sending = asyncio.get_running_loop().create_task(self._close(sub.ws, code, reason))

    @staticmethod
    async def _close(ws: WebSocket, code: int, reason: str) -> None:
        with contextlib.suppress(Exception):  # already gone
            await ws.close(code=code, reason=reason[:120])

    def status(self) -> TelemetryStatus:
        return TelemetryStatus(
            frames_sent=self.frames_sent,
            clients_dropped=self.clients_dropped,
            restarts=self.restarts,
        )

    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self._supervise(), name="telemetry-hub")

    async def _supervise(self) -> None:
        """Run the hub; when it fails, log it and start it again after one frame period."""
        while True:
            try:
                await self._run()
            except Exception:
                self.restarts += 1
                log.exception("telemetry hub failed; restarting it")
                await asyncio.sleep(self.frame_s)

    async def stop(self) -> None:
        await cancel(self._task)

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        t0 = loop.time()
        k = 0
        while True:
            k += 1
            delay = t0 + k * self.frame_s - loop.time()
            if delay < 0:  # the event loop was held up: continue from now
                t0, k = loop.time(), 0
            else:
                await asyncio.sleep(delay)
            self.tick()

    def tick(self) -> None:
        """Build and dispatch one period's messages."""
        loop = asyncio.get_running_loop()
        cache: dict[tuple[object, ...], Built] = {}  # frames, shared by equal subscriptions
        texts: dict[tuple[object, ...], str] = {}  # status and events, shared by all viewers
        for sub in list(self.subscribers):
            if sub.flooding:
                self.drop(sub, CLOSE_POLICY, "client sends without reading the replies")
                continue
            if sub.sending is not None and not sub.sending.done():
                sub.busy_periods += 1
                if loop.time() - sub.send_started > self.stall_s:
                    self.drop(sub, CLOSE_POLICY, "client does not read")
                continue
            if sub.machine.deleted:
                self.remove(sub)
                sub.sending = loop.create_task(self._close(sub.ws, 4404, "machine deleted"))
                continue
            try:
                messages = self._messages(sub, cache, texts)
            except Exception:  # one client's failure must not stop the others
                log.exception("telemetry for a client failed; closing it")
                self.drop(sub, CLOSE_INTERNAL, "telemetry failed")
                continue
            if messages:
                sub.send_started = loop.time()
                sub.sending = loop.create_task(self._send(sub, messages))

    def _messages(
        self,
        sub: Subscriber,
        cache: dict[tuple[object, ...], Built],
        texts: dict[tuple[object, ...], str],
    ) -> list[str | bytes]:
        m = sub.machine
        out: list[str | bytes] = list(sub.control)
        sub.control.clear()
        if sub.epoch != m.link.epoch:  # the machine was rebuilt: follow it from cycle 1
            sub.epoch, sub.cursor, sub.event_cursor = m.link.epoch, 1, 0
        out += [
            NoticeMessage(
                seq=n.seq, kind=n.kind, message=n.message, time_unix=n.time_unix
            ).model_dump_json()
            for n in m.notices.since(sub.notice_seq)
        ]
        sub.notice_seq = max(sub.notice_seq, m.notices.newest_seq)
        control = m.control.seq  # a control change goes out at once, not with the next push
        if m.link.status is not None and (sub.status_seq, sub.control_seq) != (
            m.link.status_seq,
            control,
        ):
            sub.status_seq, sub.control_seq = m.link.status_seq, control
            key = ("status", m.id, m.link.epoch, m.link.status_seq, control)
            if key not in texts:
                status = status_of(m, m.link.status, recent_events=False)
                texts[key] = StatusMessage(status=status).model_dump_json()
            out.append(texts[key])
        head = m.link.cycle
        now = asyncio.get_running_loop().time()
        if sub.signals and head >= sub.cursor and now >= sub.frame_due:
            out.append(self._frame(sub, head, cache))
            # half a hub period early: the tick that is nearest the client's period sends
            sub.frame_due = now + sub.frame_s - self.frame_s / 2
        events, first_seq, sub.event_cursor, dropped = m.link.events_since(sub.event_cursor)
        for seq, e in enumerate(events, first_seq):
            missed = dropped if seq == first_seq else 0
            ekey = ("event", m.id, m.link.epoch, seq, missed)  # encoded once for every viewer
            if ekey not in texts:
                msg = EventMessage(seq=seq, missed=missed, event=job_error_model(e))
                texts[ekey] = msg.model_dump_json()
            out.append(texts[ekey])
        if self.history is not None:
            entries, sub.history_cursor = self.history.since(m.id, sub.history_cursor)
            if entries:
                out.append(HistoryMessage(entries=entries).model_dump_json())
        return out

    def _frame(self, sub: Subscriber, head: int, cache: dict[tuple[object, ...], Built]) -> bytes:
        """The frame of cycles cursor..head; advances the cursor."""
        m = sub.machine
        span = head - sub.cursor + 1
        stride = max(sub.min_stride, math.ceil(span / self.max_frame_samples))
        key = (m.id, m.link.epoch, tuple(s.name for s in sub.signals), sub.cursor, head, stride)
        built = cache.get(key)
        if built is None:
            data, start = m.link.samples(sub.signals, sub.cursor, head, stride)
            header = FrameHeader(
                machine=m.id,
                first_cycle=start,
                count=data.shape[1],
                stride=stride,
                cycle_s=m.link.cycle_s,
                t0_unix=m.link.pacing.t0_unix if m.link.pacing else 0.0,
                signals=[s.name for s in sub.signals],
                decimated=stride > sub.min_stride,
                skipped_cycles=start - sub.cursor,
            )
            built = cache[key] = Built(encode_frame(header, data), start + data.shape[1] * stride)
        sub.cursor = built.next_cursor
        return built.frame

    async def _send(self, sub: Subscriber, messages: list[str | bytes]) -> None:
        try:
            for msg in messages:
                if sub.closed:
                    return
                if isinstance(msg, bytes):
                    await sub.ws.send_bytes(msg)
                    self.frames_sent += 1
                else:
                    await sub.ws.send_text(msg)
        except Exception:  # the client went away: its route handler removes it
            sub.closed = True
