"""Limits of the HTTP layer itself, before a request reaches the application: how long a client
may take to send its request head, how long its URL and headers may be, and how long a
websocket client may go without reading.

uvicorn waits for a request head without a deadline, and its httptools parser gathers a URL
and headers of any length: 200 half-sent handshakes held 200 connections open for good, and
a 20 KB `?signals=` URL hung the websocket handshake instead of being answered. Here a head
not complete within `header_timeout_s` gets 408, a URL over MAX_URL_BYTES 414 and headers over
MAX_HEADER_BYTES 431, each closing the connection.

A websocket client that reads nothing answers no ping: uvicorn's keepalive closed it with 1011
("internal error") and told the application only that the connection was lost. Here it is
closed with 1008 (policy: the client does not read), and the application is told so. A text
message that is not UTF-8 is closed with 1007 as before, logged as one line, not a traceback.
"""

from __future__ import annotations

import asyncio
from typing import Any

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol
from uvicorn.protocols.websockets.websockets_sansio_impl import WebSocketsSansIOProtocol

from backend.errors import HEADERS_TOO_LARGE, REQUEST_TIMEOUT, URI_TOO_LONG

MAX_URL_BYTES = 8 * 1024  # a telemetry URL with every signal of a large machine fits
MAX_HEADER_BYTES = 32 * 1024  # names and values of one request's headers together

_REASONS = {
    REQUEST_TIMEOUT: b"Request Timeout",
    URI_TOO_LONG: b"URI Too Long",
    HEADERS_TOO_LARGE: b"Request Header Fields Too Large",
}


CLOSE_NOT_READING = 1008  # websocket close code (RFC 6455 7.4.1): policy violation


class _Refused(Exception):
    """Stops the parser: the request is answered with `status` (see `send_400_response`)."""


def bounded_http(header_timeout_s: float) -> type[HttpToolsProtocol]:
    """uvicorn's httptools protocol with the limits above (`Config(http=...)`)."""

    class BoundedHttp(HttpToolsProtocol):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            self.url_bytes = self.header_bytes = 0
            self.head_timer: asyncio.TimerHandle | None = None
            self.refusal: tuple[int, str] | None = None

        def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
            super().connection_made(transport)
            self._arm()  # the first request's head is due from now

        def connection_lost(self, exc: Exception | None) -> None:
            self._disarm()
            super().connection_lost(exc)

        def on_message_begin(self) -> None:
            super().on_message_begin()
            self.url_bytes = self.header_bytes = 0
            self._arm()

        def on_url(self, url: bytes) -> None:
            self.url_bytes += len(url)
            if self.url_bytes > MAX_URL_BYTES:
                self._refuse(URI_TOO_LONG, f"URL longer than {MAX_URL_BYTES} bytes")
            super().on_url(url)

        def on_header(self, name: bytes, value: bytes) -> None:
            self.header_bytes += len(name) + len(value)
            if self.header_bytes > MAX_HEADER_BYTES:
                self._refuse(HEADERS_TOO_LARGE, f"headers longer than {MAX_HEADER_BYTES} bytes")
            super().on_header(name, value)

        def on_headers_complete(self) -> None:
            self._disarm()
            super().on_headers_complete()

        def send_400_response(self, msg: str) -> None:
            """The parser stopped: our refusal if it was one, else uvicorn's 400."""
            if self.refusal is None:
                super().send_400_response(msg)
            else:
                self._answer(*self.refusal)

        def _refuse(self, status: int, why: str) -> None:
            self.refusal = (status, why)
            raise _Refused(why)  # the parser stops and calls send_400_response

        def _arm(self) -> None:
            self._disarm()
            self.head_timer = self.loop.call_later(header_timeout_s, self._too_slow)

        def _disarm(self) -> None:
            if self.head_timer is not None:
                self.head_timer.cancel()
                self.head_timer = None

        def _too_slow(self) -> None:
            self.head_timer = None
            if not self.transport.is_closing():
                why = f"request head not complete within {header_timeout_s:g} s"
                self._answer(REQUEST_TIMEOUT, why)

        def _answer(self, status: int, why: str) -> None:
            body = why.encode()
            head = [b"HTTP/1.1 %d %s\r\n" % (status, _REASONS[status])]
            head += [n + b": " + v + b"\r\n" for n, v in self.server_state.default_headers]
            head.append(b"content-type: text/plain; charset=utf-8\r\n")
            head.append(b"content-length: %d\r\nconnection: close\r\n\r\n" % len(body))
            self.transport.write(b"".join(head) + body)
            self.transport.close()

    return BoundedHttp


class KeepaliveWebSocket(WebSocketsSansIOProtocol):
    """uvicorn's websocket protocol, with a missed pong closing as policy (1008)."""

    def keepalive_timeout(self) -> None:
        self.pong_timer = None
        self.pending_ping_payload = None
        if self.close_sent or self.transport.is_closing():
            return
        why = "client does not read (no pong in time)"
        # the application hears the reason first (the lost connection's 1005 comes after)
        self.queue.put_nowait({"type": "websocket.disconnect", "code": CLOSE_NOT_READING})
        self.conn.fail(CLOSE_NOT_READING, why)
        self.transport.write(b"".join(self.conn.data_to_send()))
        self.close_sent = True
        self.transport.close()

    def send_receive_event_to_app(self) -> None:
        """A text message that is not UTF-8: closed with 1007 and one line in the log."""
        if self.curr_msg_data_type == "text" and not self.close_sent:
            data = b"".join(self.frames)
            try:
                data.decode()
            except UnicodeDecodeError as e:
                self.frames = []
                self.logger.warning("websocket client sent text that is not UTF-8 (%s)", e)
                self.conn.send_close(1007)
                self.handle_parser_exception()
                return
        super().send_receive_event_to_app()
