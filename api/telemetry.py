"""Live telemetry over a websocket: JSON control messages and binary sample frames.

A binary frame is `b"INBT"`, a little-endian u32 header length, the JSON `FrameHeader` (padded
with spaces so the samples start 8-byte aligned), then `count` float64 samples of each signal
in turn (signal-major). Sample k of a frame belongs to cycle `first_cycle + k * stride`; its
nominal wall time is `t0_unix + cycle * cycle_s`.
"""

from __future__ import annotations

import json
import struct
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, Field

from api.common import JobErrorModel
from api.history import HistoryEntry
from api.status import MachineStatus

MAGIC = b"INBT"
MAX_SIGNALS = 256  # per subscription
MAX_SIGNAL_NAME = 64  # characters
MIN_RATE_HZ = 0.1  # one sample per 10 s: slower rates make no live plot
MAX_RATE_HZ = 1e6  # beyond any cycle rate: every cycle
MAX_FRAME_S = 1.0  # the longest frame period a client may ask for
MAX_MESSAGE_BYTES = 65536  # a client message larger than this closes the connection (1009)


class SignalInfo(BaseModel):
    name: str = Field(description="`<axis>.<signal>`, e.g. S1.speed_act_rpm")
    axis: str
    unit: str
    kind: Literal["float", "bool", "enum"]


class Subscribe(BaseModel):
    """Client → server: which signals to stream (replaces any earlier subscription)."""

    type: Literal["subscribe"] = "subscribe"
    signals: list[Annotated[str, Field(max_length=MAX_SIGNAL_NAME)]] = Field(
        min_length=1, max_length=MAX_SIGNALS
    )
    max_rate_hz: float | None = Field(
        None,
        ge=MIN_RATE_HZ,
        le=MAX_RATE_HZ,
        description="decimate to at most this many samples per second (none: every cycle)",
    )
    frame_s: float | None = Field(
        None,
        ge=0,
        le=MAX_FRAME_S,
        description="a frame at most this often, s: the client's redraw period (none, or "
        "shorter than the service's frame period: every frame period); each frame still "
        "carries every (decimated) sample since the last",
    )


class Hello(BaseModel):
    """Server → client on connect: the machine and every signal it records."""

    type: Literal["hello"] = "hello"
    machine: str
    cycle: int
    cycle_s: float
    signals: list[SignalInfo]


class Subscribed(BaseModel):
    type: Literal["subscribed"] = "subscribed"
    signals: list[str]
    first_cycle: int = Field(description="frames start at the cycle after this one")
    stride: int


class EventMessage(BaseModel):
    type: Literal["event"] = "event"
    seq: int = Field(description="sequence number in the machine's event log (from 0 per run)")
    missed: int = Field(
        0, description="events before this one the bounded log dropped before they were sent"
    )
    event: JobErrorModel


class StatusMessage(BaseModel):
    """Server → client: the machine's status, pushed 20 times a second (10 when its worker
    holds a class of machines) while the client is connected (no polling). Its
    `recent_events` is empty: a viewer gets the newest events as event messages when it
    connects and every new one as it comes."""

    type: Literal["status"] = "status"
    status: MachineStatus


NoticeKind = Literal[
    "rebuilt", "restored", "restarted", "message", "frozen", "resumed", "exercise", "present"
]


class NoticeMessage(BaseModel):
    """Server → client: something every viewer must see, e.g. the machine was rebuilt on
    another worker after its worker died (simulated time restarts at 0)."""

    type: Literal["notice"] = "notice"
    seq: int = Field(description="numbered per machine; a reconnecting client sees it again")
    kind: NoticeKind = Field(
        description="rebuilt after its worker died; restored from a snapshot; the service "
        "restarted (the machine powered on again); a message from the instructor; frozen or "
        "resumed by the instructor; a class seat moved on to its next exercise (powered on "
        "afresh for it); the instructor presents a machine to the class, or stops"
    )
    message: str
    time_unix: float


class HistoryMessage(BaseModel):
    """Server → client: new entries of the machine's history (as `GET .../history` reads
    them), oldest first, as they are written; a client loads the older ones by REST."""

    type: Literal["history"] = "history"
    entries: list[HistoryEntry]


class ErrorMessage(BaseModel):
    type: Literal["error"] = "error"
    message: str


class FrameHeader(BaseModel):
    machine: str
    first_cycle: int
    count: int = Field(description="samples per signal")
    stride: int = Field(description="cycles between samples (1: every cycle)")
    cycle_s: float
    t0_unix: float = Field(description="wall time of cycle 0 in the current run")
    signals: list[str]
    decimated: bool = Field(description="stride > 1 because the client fell behind")
    skipped_cycles: int = Field(description="cycles lost since the previous frame")


def encode_frame(header: FrameHeader, data: np.ndarray) -> bytes:
    """Binary frame of a header and a signals × count float64 array."""
    text = header.model_dump_json().encode()
    pad = (-(8 + len(text))) % 8
    body = np.ascontiguousarray(data, dtype="<f8").tobytes()
    return MAGIC + struct.pack("<I", len(text) + pad) + text + b" " * pad + body


def decode_frame(buf: bytes) -> tuple[FrameHeader, np.ndarray]:
    """Header and signals × count samples of a binary frame."""
    if buf[:4] != MAGIC:
        raise ValueError("not a telemetry frame")
    (n,) = struct.unpack_from("<I", buf, 4)
    header = FrameHeader.model_validate(json.loads(buf[8 : 8 + n]))
    data = np.frombuffer(buf, dtype="<f8", offset=8 + n)
    return header, data.reshape(len(header.signals), header.count)
