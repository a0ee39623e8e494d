"""Running the service under uvicorn on a listening socket we prepare ourselves."""

from __future__ import annotations

import socket
from collections.abc import Mapping

import uvicorn

from api.telemetry import MAX_MESSAGE_BYTES
from backend.main import create_app
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


def serve(host: str, port: int, overrides: Mapping[str, object]) -> None:
    """Start the service and block until it is stopped (SIGINT/SIGTERM)."""
    settings = Settings.model_validate(dict(overrides))
    sock = listening_socket(host, port, settings.send_buffer_bytes)
    # client websocket messages are small; larger ones are refused (1009) while they stream in
    # no per-message compression: binary frames of float samples barely compress, and
    # deflating every frame for every viewer cost the gateway a quarter of its CPU
    config = uvicorn.Config(
        create_app(settings),
        log_level="warning",
        ws_max_size=MAX_MESSAGE_BYTES,
        ws_per_message_deflate=False,
    )
    print(f"Inbetrieb at http://{host}:{port}  (API docs at /docs)", flush=True)
    uvicorn.Server(config).run(sockets=[sock])
