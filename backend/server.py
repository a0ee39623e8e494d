"""Running the service under uvicorn on a listening socket we prepare ourselves."""

from __future__ import annotations

import contextlib
import signal
import socket
import sys

import uvicorn

from api.telemetry import MAX_MESSAGE_BYTES
from backend import logs
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


def exposure_problem(settings: Settings) -> str | None:
    """Why serving as `settings` say would be unsafe, or None."""
    host = settings.host
    if (settings.tls_cert is None) != (settings.tls_key is None):
        return "--tls-cert and --tls-key go together"
    if is_loopback(host):
        return None
    if settings.tls_cert is None and settings.behind_proxy is None:
        return (
            f"refusing to serve on {host} without TLS: beyond loopback, give a certificate "
            "(--tls-cert FILE --tls-key FILE) or run behind a proxy that terminates TLS "
            "(--behind-proxy ITS_ADDRESS)"
        )
    if is_wildcard(host) and not settings.allowed_hosts:
        return (
            f"{host} answers on every interface: name the host names clients use with "
            "--allowed-host NAME (a request for any other Host is refused)"
        )
    return None


def serve(settings: Settings) -> int:
    """Start the service and block until it is stopped (SIGINT/SIGTERM); 2 when the
    exposure asked for is unsafe (nothing started)."""
    problem = exposure_problem(settings)
    if problem:
        print(f"inbetrieb serve: {problem}", file=sys.stderr)
        return 2
    host, port = settings.host, settings.port
    sock = listening_socket(host, port, settings.send_buffer_bytes)
    # client websocket messages are small; larger ones are refused (1009) while they stream in
    # no per-message compression: binary frames of float samples barely compress, and
    # deflating every frame for every viewer cost the gateway a quarter of its CPU
    logs.configure(settings.log_format, settings.log_level)
    config = uvicorn.Config(
        create_app(settings),
        log_config=None,  # ours (backend/logs.py), with the request's id and actor
        log_level=settings.log_level,
        access_log=False,  # ours has the id and the actor
        ws_max_size=MAX_MESSAGE_BYTES,
        ws_per_message_deflate=False,
        http=bounded_http(settings.header_timeout_s),
        ws=KeepaliveWebSocket,
        # a websocket client that reads nothing answers no ping either: it is closed (1008)
        # within client_stall_s, however large its buffers are
        ws_ping_interval=settings.client_stall_s / 2,
        ws_ping_timeout=settings.client_stall_s / 2,
        # forwarded headers (client address, scheme) count only from the one proxy named
        proxy_headers=settings.behind_proxy is not None,
        forwarded_allow_ips=settings.behind_proxy,
        ssl_certfile=settings.tls_cert,
        ssl_keyfile=settings.tls_key,
    )
    scheme = "https" if settings.https else "http"
    print(f"Inbetrieb at {scheme}://{host}:{port}  (API docs at /docs)", flush=True)
    # uvicorn raises the signal that stopped it again once it has stopped in order: Ctrl-C
    # as KeyboardInterrupt, SIGTERM (docker stop, systemd, kill) to the handler it found,
    # this one, not the default that would end the process by the signal (exit 143 in a
    # container); both are the end, no error
    signal.signal(signal.SIGTERM, lambda *_: None)
    with contextlib.suppress(KeyboardInterrupt):
        uvicorn.Server(config).run(sockets=[sock])
    print("Inbetrieb stopped", flush=True)
    return 0
