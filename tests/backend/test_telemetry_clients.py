"""Telemetry clients that misbehave: each is refused or disconnected with a proper close code,
the server's memory for it stays bounded, and every other client keeps receiving frames.

One service for the module with a 1 s stall limit (`INBETRIEB_CLIENT_STALL_S`); each test
watches its own demo machine, paused and stepped, so nothing depends on how fast it runs.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager, suppress
from typing import Any

import httpx
import pytest
from websockets.sync.client import ClientConnection, connect

from api.telemetry import MAX_MESSAGE_BYTES, decode_frame
from tests.backend.rawws import RawWebSocket
from tests.backend.server import Server

STALL_S = 1.0


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    env = {"INBETRIEB_CLIENT_STALL_S": str(STALL_S)}
    s = Server(tmp_path_factory.mktemp("clients") / "c.sqlite", env=env).start()
    yield s
    s.close()


@pytest.fixture
def mid(srv: Server, mid: str) -> str:
    """The test's own machine, paused: it moves only when the test steps it."""
    srv.pace(mid, mode="pause")
    return mid


def _telemetry(srv: Server) -> dict[str, Any]:
    data: dict[str, Any] = srv.http.get("/api/service/status").json()["telemetry"]
    return data


@contextmanager
def _watching(srv: Server, mid: str) -> Iterator[ClientConnection]:
    """A well-behaved client subscribed to one signal: it reads all the time, also while the
    test does something else (websockets' default stops reading after 16 messages not taken:
    no pong then, and the server drops it as not reading once the test takes over a second)."""
    with connect(
        f"{srv.ws_base}/api/machines/{mid}/telemetry?signals=X.pos_act_mm",
        max_queue=None,
        **srv.ws_auth,
    ) as ws:
        while json.loads(ws.recv(timeout=10))["type"] != "subscribed":
            pass
        yield ws


def _still_receives(srv: Server, mid: str, ws: ClientConnection) -> None:
    """The client gets the frames of cycles stepped from now on."""
    after = srv.step(mid, 50)["cycle"]
    while True:
        msg = ws.recv(timeout=10)
        if isinstance(msg, bytes):
            header, _ = decode_frame(msg)
            if header.first_cycle + (header.count - 1) * header.stride >= after:
                return


def _raw(srv: Server, mid: str, query: str = "", rcvbuf: int = 4096) -> RawWebSocket:
    raw = RawWebSocket(
        "127.0.0.1", srv.port, f"/api/machines/{mid}/telemetry{query}", srv.auth_header, rcvbuf
    )
    raw.sock.settimeout(30)
    return raw


def test_an_absurd_rate_is_refused_and_telemetry_goes_on(srv: Server, mid: str) -> None:
    """max_rate_hz 1e-16 once made a stride of 10^19 cycles that killed the hub for all."""
    with (
        _watching(srv, mid) as other,
        connect(f"{srv.ws_base}/api/machines/{mid}/telemetry", **srv.ws_auth) as bad,
    ):
        bad.send(json.dumps({"type": "subscribe", "signals": ["X.lag_mm"], "max_rate_hz": 1e-16}))
        while (reply := json.loads(bad.recv(timeout=10)))["type"] != "error":
            pass
        assert "max_rate_hz" in reply["message"] and "0.1" in reply["message"]
        bad.send(json.dumps({"type": "subscribe", "signals": ["X.lag_mm"], "max_rate_hz": 0.1}))
        while (reply := json.loads(bad.recv(timeout=10)))["type"] != "subscribed":
            pass
        assert reply["stride"] == 10_000  # 1 kHz to 0.1 Hz
        _still_receives(srv, mid, other)
    assert _telemetry(srv)["restarts"] == 0


@pytest.mark.parametrize(
    ("payload", "opcode", "code"),
    [
        (b"\x00\x01binary", 2, 1003),  # binary messages are not part of the protocol
        (b"[" * 100_000, 1, 1009),  # over MAX_MESSAGE_BYTES
        (b"[" * 50_000 + b"]" * 50_000, 1, 1009),
        (b'{"type": "subscribe", "signals": ' + b"[" * 5000 + b"]" * 5000 + b"}", 1, 1007),
    ],
    ids=["binary", "unterminated-huge", "nested-huge", "nested-deep"],
)
def test_a_bad_message_closes_that_client_with_its_code(
    srv: Server, mid: str, payload: bytes, opcode: int, code: int
) -> None:
    assert (len(payload) > MAX_MESSAGE_BYTES) == (code == 1009)
    # a server closing with our bytes still unread resets the connection and drops what its
    # kernel had not sent yet (its close frame too): so the client reads while it sends, and
    # its receive buffer takes all the server sends at once (this client is not a slow one)
    with (
        _watching(srv, mid) as other,
        ThreadPoolExecutor(1) as pool,
        _raw(srv, mid, rcvbuf=1 << 20) as raw,
    ):
        sending = pool.submit(raw.send, payload, opcode)
        assert raw.close_code() == code
        with suppress(OSError):  # the server stopped reading the rest of a huge payload
            sending.result()
        _still_receives(srv, mid, other)


def test_a_client_that_sends_but_never_reads_is_disconnected(srv: Server, mid: str) -> None:
    """Every message earns a reply the client never reads: the replies waiting for it are
    bounded, and the client is closed with 1008 (policy) long before it could fill memory."""
    dropped = _telemetry(srv)["clients_dropped"]
    msg = json.dumps({"type": "subscribe", "signals": ["X.nonsense"] * 200}).encode()
    with _watching(srv, mid) as other:
        with _raw(srv, mid) as raw:
            sent = 0
            with suppress(OSError):  # the server closed the connection while we still sent
                while sent < 5000:  # 5000 replies of ~2 kB if nobody stopped it
                    raw.send(msg)
                    sent += 1
            assert sent < 5000 or raw.close_code() == 1008
        assert _telemetry(srv)["clients_dropped"] == dropped + 1
        _still_receives(srv, mid, other)


def test_a_client_that_stops_reading_is_disconnected_after_the_stall_limit(
    srv: Server, mid: str
) -> None:
    """Every cycle of every signal, never read: its send blocks on the full socket. The
    stalled send ends the connection (1008) while a reading client keeps its frames."""
    every = [s["name"] for s in srv.http.get(f"/api/machines/{mid}/signals").json()]
    dropped = _telemetry(srv)["clients_dropped"]
    with _watching(srv, mid) as other:
        clients = srv.http.get("/api/service/status").json()["clients"]
        with _raw(srv, mid, "?signals=" + ",".join(every)) as raw:
            with ThreadPoolExecutor(1) as pool:  # keep the machine going until the server gives up
                stepping = pool.submit(_step_until_dropped, srv, mid, dropped)
                while not stepping.done():
                    _still_receives(srv, mid, other)  # the reader is served all along
                stepping.result()
            assert srv.http.get("/api/service/status").json()["clients"] == clients
            with suppress(TimeoutError, ConnectionError):  # else the close handshake timed out
                assert raw.close_code() == 1008


def _step_until_dropped(srv: Server, mid: str, dropped: int) -> None:
    with httpx.Client(base_url=srv.base, timeout=10, headers=srv.auth) as http:  # this thread's
        for _ in range(10_000):
            http.post(f"/api/machines/{mid}/simulation/step", json={"cycles": 100})
            status = http.get("/api/service/status").json()
            if status["telemetry"]["clients_dropped"] > dropped:
                return
    raise AssertionError("the stalled client was never disconnected")
