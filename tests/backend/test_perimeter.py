"""The perimeter over real HTTP and websockets: a foreign Host or Origin is refused before a
route runs (and nothing changes), every page carries a CSP that forbids framing and foreign
sources, the API docs come from our own build, and `serve` refuses to listen beyond loopback
without TLS. A request head must come in time and within its size; a websocket client must
read (answer pings) and send UTF-8 text."""

from __future__ import annotations

import asyncio
import os
import re
import socket
import ssl
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
import websockets

from tests.backend.rawws import RawWebSocket
from tests.backend.server import ROOT, Server, free_port

FOREIGN = "http://evil.example"


HEADER_TIMEOUT_S = 1.0  # short here: the tests wait for it
CLIENT_STALL_S = 2.0


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    folder = tmp_path_factory.mktemp("perimeter")
    env = {
        "INBETRIEB_HEADER_TIMEOUT_S": str(HEADER_TIMEOUT_S),
        "INBETRIEB_CLIENT_STALL_S": str(CLIENT_STALL_S),
    }
    with (folder / "log.txt").open("w") as log:
        s = Server(folder / "p.sqlite", env=env).start(stdout=log)
    yield s
    s.close()


def service_log(srv: Server) -> str:
    return (srv.db.parent / "log.txt").read_text()


def raw_answer(srv: Server, head: bytes) -> bytes:
    """What the service answers to these bytes sent as they are (up to its close)."""
    with socket.create_connection(("127.0.0.1", srv.port), timeout=30) as raw:
        raw.sendall(head)
        answer = b""
        while part := raw.recv(65536):
            answer += part
        return answer


def test_a_request_head_not_sent_in_time_is_answered_408_and_closed(srv: Server) -> None:
    """Half-sent heads held connections open for good (200 of them after 15 s)."""
    answer = raw_answer(srv, b"GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n")
    assert answer.startswith(b"HTTP/1.1 408 ")
    assert f"within {HEADER_TIMEOUT_S:g} s".encode() in answer


def test_a_url_or_headers_too_long_are_answered_at_once(srv: Server, mid: str) -> None:
    """A 20 KB `?signals=` URL hung the websocket handshake; now 414, and 431 for headers."""
    signals = ",".join(["X.pos_act_mm"] * 1700)  # 20 KB
    upgrade = (
        b"Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
        b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
    )
    path = f"/api/machines/{mid}/telemetry?signals={signals}"
    head = f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{srv.port}\r\n{srv.auth_header}".encode()
    answer = raw_answer(srv, head + upgrade + b"\r\n")
    assert answer.startswith(b"HTTP/1.1 414 ") and b"URL longer than 8192 bytes" in answer
    filler = b"".join(b"X-Filler-%d: %s\r\n" % (i, b"a" * 1000) for i in range(40))  # 40 KB
    answer = raw_answer(srv, b"GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n" + filler)
    assert answer.startswith(b"HTTP/1.1 431 ")
    assert srv.http.get("/api/health").status_code == 200  # and the service goes on


def test_a_websocket_client_that_reads_nothing_is_closed_as_not_reading(
    srv: Server, mid: str
) -> None:
    """Its buffers can take megabytes before a send of ours would stall: the missed pong
    finds it first, within the stall time, closed with 1008 and counted as dropped."""
    dropped = srv.http.get("/api/service/status").json()["telemetry"]["clients_dropped"]
    path = f"/api/machines/{mid}/telemetry?signals=X.pos_act_mm"
    with RawWebSocket("127.0.0.1", srv.port, path, srv.auth_header, rcvbuf=4 << 20) as ws:
        time.sleep(2 * CLIENT_STALL_S)  # reads nothing (answers no ping) for a while
        assert ws.close_code() == 1008
    # counted once the hub has let the connection go, a moment after its close frame
    deadline = time.monotonic() + 10.0
    while (
        now := srv.http.get("/api/service/status").json()["telemetry"]["clients_dropped"]
    ) == dropped:
        assert time.monotonic() < deadline, "the dropped client was not counted"
        time.sleep(0.05)
    assert now == dropped + 1


def test_text_that_is_not_utf8_closes_with_1007_and_one_log_line(srv: Server, mid: str) -> None:
    path = f"/api/machines/{mid}/telemetry"
    with RawWebSocket("127.0.0.1", srv.port, path, srv.auth_header, rcvbuf=1 << 20) as ws:
        ws.send(b'{"type": "\xff\xfe"}')
        assert ws.close_code() == 1007
    log = service_log(srv)
    assert "not UTF-8" in log and "Traceback" not in log


def test_a_request_for_a_foreign_host_name_is_refused(srv: Server) -> None:
    """DNS rebinding: the page's own name reaches our address; we answer only our names."""
    r = srv.http.get("/api/machines", headers={"Host": "evil.example"})
    assert r.status_code == 400
    assert "evil.example" in r.json()["detail"]["message"]
    for name in (f"127.0.0.1:{srv.port}", f"localhost:{srv.port}"):
        assert srv.http.get("/api/machines", headers={"Host": name}).status_code == 200


def test_a_cross_site_command_is_refused_and_changes_nothing(srv: Server, mid: str) -> None:
    """Another site's page POSTing to us (a "simple" request needs no preflight)."""
    spin = {"type": "mdi", "block": "M3 S500"}
    url = f"/api/machines/{mid}/commands"
    r = srv.http.post(url, json=spin, headers={"Origin": FOREIGN})
    assert r.status_code == 403 and FOREIGN in r.json()["detail"]["message"]
    lst = "getriebe[0].kv 1\n"
    r = srv.http.post(
        f"/api/machines/{mid}/parameters/import?scope=axis&target=X",
        content=lst,
        headers={"Origin": FOREIGN, "Content-Type": "text/plain"},
    )
    assert r.status_code == 403
    r = srv.http.post(url, json=spin, headers={"Sec-Fetch-Site": "cross-site"})
    assert r.status_code == 403
    r = srv.http.post(url, json=spin, headers={"Origin": "null"})  # a sandboxed frame
    assert r.status_code == 403
    s1 = srv.axis("S1", mid)
    assert s1["vel_cmd"] == 0.0 and s1["state"] == "STANDSTILL"
    x = srv.http.get(f"/api/machines/{mid}/parameters?scope=axis&target=X").json()
    assert all(p["value"] != 1 for p in x if p["name"] == "getriebe[0].kv")
    # the service's own page and a script without Origin may
    own = srv.http.post(url, json=spin, headers={"Origin": srv.base})
    assert own.status_code == 200, own.text
    assert srv.command(mid, {"type": "spindle", "m": 5}).status_code == 200


def test_a_websocket_from_a_foreign_origin_is_refused(srv: Server, mid: str) -> None:
    url = f"{srv.ws_base}/api/machines/{mid}/telemetry"

    async def connect(origin: str) -> str:
        try:
            async with websockets.connect(url, origin=origin, **srv.ws_auth) as ws:  # type: ignore[arg-type]
                return str(await asyncio.wait_for(ws.recv(), 10))
        except websockets.InvalidStatus as e:
            return f"refused {e.response.status_code}"

    assert asyncio.run(connect(FOREIGN)) == "refused 403"
    assert '"hello"' in asyncio.run(connect(srv.base))


def test_every_page_forbids_framing_and_foreign_sources(srv: Server) -> None:
    for path in ("/", "/docs", "/api/health", "/api/machines/none/status"):
        r = srv.http.get(path)
        csp = r.headers["content-security-policy"]
        assert "frame-ancestors 'none'" in csp, path
        assert "default-src 'self'" in csp and "http" not in csp, path  # no foreign source
        assert r.headers["x-frame-options"] == "DENY"
        assert r.headers["x-content-type-options"] == "nosniff"


def test_the_api_docs_load_only_from_this_service(srv: Server) -> None:
    page = srv.http.get("/docs")
    assert page.status_code == 200 and "swagger-ui" in page.text
    refs = re.findall(r'(?:src|href)="([^"]+)"', page.text)
    assert refs and all(ref.startswith("/") and not ref.startswith("//") for ref in refs), refs
    for ref in refs:
        asset = srv.http.get(ref)
        assert asset.status_code == 200, ref
        assert "cdn.jsdelivr" not in asset.text and "unpkg.com" not in asset.text
    assert srv.http.get("/openapi.json").json()["info"]["title"] == "Inbetrieb"


def _serve(*args: str, **env: str) -> subprocess.CompletedProcess[str]:
    """`inbetrieb serve` that must refuse: it exits without serving."""
    cmd = [sys.executable, "-m", "backend.cli", "serve", "--port", str(free_port()), *args]
    return subprocess.run(
        cmd, cwd=ROOT, capture_output=True, text=True, timeout=60, env={**os.environ, **env}
    )


def test_serving_beyond_loopback_needs_tls_or_a_proxy(tmp_path: Path) -> None:
    db = ["--db", str(tmp_path / "x.sqlite")]
    plain = _serve("--host", "0.0.0.0", *db)
    assert plain.returncode == 2 and "without TLS" in plain.stderr
    assert "--tls-cert" in plain.stderr and "--behind-proxy" in plain.stderr
    anywhere = _serve("--host", "0.0.0.0", "--behind-proxy", "127.0.0.1", *db)
    assert anywhere.returncode == 2 and "--allowed-host" in anywhere.stderr
    half = _serve("--tls-cert", str(tmp_path / "c.pem"), *db)
    assert half.returncode == 2 and "go together" in half.stderr
    # the same from the environment, as a container or a systemd unit sets it
    plain = _serve(*db, INBETRIEB_HOST="0.0.0.0")
    assert plain.returncode == 2 and "refusing to serve on 0.0.0.0 without TLS" in plain.stderr
    anyone = _serve(*db, INBETRIEB_HOST="0.0.0.0", INBETRIEB_BEHIND_PROXY="*")
    assert anyone.returncode == 2 and "behind_proxy" in anyone.stderr, anyone.stderr
    assert "Traceback" not in anyone.stderr
    named = _serve(
        *db,
        INBETRIEB_HOST="0.0.0.0",
        INBETRIEB_BEHIND_PROXY="10.42.0.0/16",
        INBETRIEB_TLS_CERT=str(tmp_path / "c.pem"),
    )
    assert named.returncode == 2 and "go together" in named.stderr
    assert not (tmp_path / "x.sqlite").exists()  # nothing started


def test_with_a_certificate_it_serves_https(tmp_path: Path) -> None:
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subject = ["-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1"]
    files = ["-keyout", str(key), "-out", str(cert)]
    subprocess.run(
        [
            "openssl",
            "req",
            "-x509",
            "-newkey",
            "rsa:2048",
            "-nodes",
            "-days",
            "1",
            *subject,
            *files,
        ],
        check=True,
        capture_output=True,
    )
    s = Server(tmp_path / "tls.sqlite", "--no-demo", "--tls-cert", str(cert), "--tls-key", str(key))
    s.base = f"https://127.0.0.1:{s.port}"
    trust = ssl.create_default_context(cafile=str(cert))
    s.http = httpx.Client(base_url=s.base, timeout=10, verify=trust)
    out = (tmp_path / "out.txt").open("w")
    try:
        s.start(stdout=out)
        r = s.http.get("/api/health")
        assert r.status_code == 200
        assert r.url.scheme == "https"
        printed = (tmp_path / "out.txt").read_text()
        assert "/auth/once?token=" in printed
        assert f"https://127.0.0.1:{s.port}/auth/once" in printed  # the link speaks TLS too
    finally:
        s.close()
        out.close()
