"""Every route's body limit over real HTTP: enforced while the body streams in and before it
is parsed, a small one for the routes open without credentials, 413 naming the limit."""

from __future__ import annotations

import re
import socket
from collections.abc import Iterator
from pathlib import Path

import httpx

from backend.bodies import CSV_BODY_BYTES, DEFAULT_BODY_BYTES, OPEN_BODY_BYTES
from tests.backend.server import Server


def peak_rss_bytes(pid: int) -> int:
    status = Path(f"/proc/{pid}/status").read_text()
    return int(re.search(r"VmHWM:\s+(\d+) kB", status)[1]) * 1024  # type: ignore[index]


def reset_peak_rss(pid: int) -> int:
    """Peak RSS counts from now on; the RSS now."""
    Path(f"/proc/{pid}/clear_refs").write_text("5")
    return peak_rss_bytes(pid)


def megabytes(total: int, block: bytes) -> Iterator[bytes]:
    """`total` bytes of `block` repeated, sent chunked (no Content-Length: the service must
    count them itself)."""
    for _ in range(total // len(block)):
        yield block


def refused_for_size(r: httpx.Response, limit: int) -> bool:
    message = r.json()["detail"]["message"]
    return r.status_code == 413 and message == (
        f"request body larger than this route's limit of {limit} bytes"
    )


def raw_post(srv: Server, path: str, length: int, auth: bool) -> bytes:
    """A POST declaring `length` bytes of which only a few are sent: the first bytes of
    the answer."""
    with socket.create_connection(("127.0.0.1", srv.port), timeout=30) as raw:
        head = f"POST {path} HTTP/1.1\r\nHost: 127.0.0.1:{srv.port}\r\n"
        head += "Content-Type: application/json\r\n" + (srv.auth_header if auth else "")
        raw.sendall(f"{head}Content-Length: {length}\r\n\r\n[1,".encode())
        answer = b""
        while b"}}" not in answer and (part := raw.recv(4096)):  # the error body's end
            answer += part
        return answer


def test_an_anonymous_20_mb_login_is_refused_after_4_kib_and_costs_no_memory(
    srv: Server,
) -> None:
    """The probe's reproduction: a JSON array of 10 million numbers as a login. Parsed
    whole it cost the gateway ~290 MB; refused while it streams in, nearly nothing."""
    assert srv.proc is not None
    before = reset_peak_rss(srv.proc.pid)
    body = megabytes(20_000_000, b'{"name":[' + b"1," * 4000 + b'1],"password":"x"}')
    with httpx.Client(base_url=srv.base, timeout=60) as anonymous:
        r = anonymous.post(
            "/api/auth/login", content=body, headers={"content-type": "application/json"}
        )
    assert refused_for_size(r, OPEN_BODY_BYTES)
    assert peak_rss_bytes(srv.proc.pid) - before < 8 * 1024 * 1024
    # declared: refused before the body is read, in the same words
    answer = raw_post(srv, "/api/auth/login", 20_000_000, auth=False)
    assert answer.startswith(b"HTTP/1.1 413") and b"limit of 4096 bytes" in answer


def test_a_route_without_uploads_takes_64_kib(srv: Server, mid: str) -> None:
    big = {"action": "take", "client": "x", "session": "y" * (DEFAULT_BODY_BYTES + 1)}
    r = srv.http.post(f"/api/machines/{mid}/control", json=big)
    assert refused_for_size(r, DEFAULT_BODY_BYTES)
    assert srv.http.get(f"/api/machines/{mid}/control").status_code == 200  # still answers
    answer = raw_post(srv, f"/api/machines/{mid}/commands", 10**12, auth=True)
    assert answer.startswith(b"HTTP/1.1 413")  # a terabyte declared (over a program's limit)


def test_a_csv_over_the_limit_is_413_and_never_held_whole(srv: Server) -> None:
    """The largest upload route (64 MiB): three times that sent chunked is refused once the
    limit is passed, the gateway's peak memory far below what reading it whole would take."""
    assert srv.proc is not None
    before = reset_peak_rss(srv.proc.pid)
    r = srv.http.post(
        "/api/traces/import", content=megabytes(3 * CSV_BODY_BYTES, b"1,2\n" * 262_144)
    )
    assert refused_for_size(r, CSV_BODY_BYTES)
    # read whole (as before) the 192 MiB body alone would have raised the peak by that
    assert peak_rss_bytes(srv.proc.pid) - before < 1.5 * CSV_BODY_BYTES
    answer = raw_post(srv, "/api/traces/import", 3 * CSV_BODY_BYTES, auth=True)
    assert answer.startswith(b"HTTP/1.1 413")
