"""Running the service under uvicorn on a listening socket we prepare ourselves."""

from __future__ import annotations

import contextlib
import socket
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import uvicorn

from api.telemetry import MAX_MESSAGE_BYTES
from backend.http_limits import KeepaliveWebSocket, bounded_http
from backend.main import create_app
from backend.security import is_loopback, is_wildcard
from backend.settings import Settings


def listening_socket(host: str, port: int, send_buffer_bytes: int) -> socket.socket:
    """A bound socket whose accepted connections have a bounded kernel send buffer.

    Linux lets a send buffer grow to megabytes; a telemetry client that stops reading would
    then receive seconds-old frames later. With a bounded buffer its sender blocks within
    a fraction of a second, the hub skips it and later sends it fresh, decimated data.
    """
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, send_buffer_bytes)  # inherited
    sock.bind((host, port))
    sock.set_inheritable(True)
    return sock


@dataclass(frozen=True)
class Exposure:
    """How the service may be reached beyond this computer."""

    tls_cert: Path | None = None  # with tls_key: uvicorn speaks HTTPS itself
    tls_key: Path | None = None
    proxy: str | None = None  # the address of the one proxy whose forwarded headers count

    def problem(self, host: str, allowed_hosts: list[str]) -> str | None:
        """Why serving on `host` would be unsafe, or None."""
        if (self.tls_cert is None) != (self.tls_key is None):
            return "--tls-cert and --tls-key go together"
        if is_loopback(host):
            return None
        if self.tls_cert is None and self.proxy is None:
            return (
                f"refusing to serve on {host} without TLS: beyond loopback, give a certificate "
                "(--tls-cert FILE --tls-key FILE) or run behind a proxy that terminates TLS "
                "(--behind-proxy ITS_ADDRESS)"
            )
        if is_wildcard(host) and not allowed_hosts:
            return (
                f"{host} answers on every interface: name the host names clients use with "
                "--allowed-host NAME (a request for any other Host is refused)"
            )
        return None


def serve(host: str, port: int, overrides: Mapping[str, object], exposure: Exposure) -> int:
    """Start the service and block until it is stopped (SIGINT/SIGTERM); 2 when the
    exposure asked for is unsafe (nothing started)."""
    https = exposure.tls_cert is not None
    settings = Settings.model_validate({**overrides, "host": host, "port": port, "https": https})
    problem = exposure.problem(host, settings.allowed_hosts)
    if problem:
        print(f"inbetrieb serve: {problem}", file=sys.stderr)
        return 2
    sock = listening_socket(host, port, settings.send_buffer_bytes)
    # client websocket messages are small; larger ones are refused (1009) while they stream in
    # no per-message compression: binary frames of float samples barely compress, and
    # deflating every frame for every viewer cost the gateway a quarter of its CPU
    config = uvicorn.Config(
        create_app(settings),
        log_level="warning",
        ws_max_size=MAX_MESSAGE_BYTES,
        ws_per_message_deflate=False,
        http=bounded_http(settings.header_timeout_s),
        ws=KeepaliveWebSocket,
        # a websocket client that reads nothing answers no ping either: it is closed (1008)
        # within client_stall_s, however large its buffers are
        ws_ping_interval=settings.client_stall_s / 2,
        ws_ping_timeout=settings.client_stall_s / 2,
        # forwarded headers (client address, scheme) count only from the one proxy named
        proxy_headers=exposure.proxy is not None,
        forwarded_allow_ips=exposure.proxy,
        ssl_certfile=exposure.tls_cert,
        ssl_keyfile=exposure.tls_key,
    )
    scheme = "https" if https else "http"
    print(f"Inbetrieb at {scheme}://{host}:{port}  (API docs at /docs)", flush=True)
    # uvicorn raises Ctrl-C again once it has stopped in order: that is the end, no error
    with contextlib.suppress(KeyboardInterrupt):
        uvicorn.Server(config).run(sockets=[sock])
    print("Inbetrieb stopped", flush=True)
    return 0
