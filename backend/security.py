"""The service's perimeter: which Host names it answers, which Origins may change state, and
the headers that keep other sites from framing or scripting its pages.

- **Host**: only the names the service is reached by (loopback, the address it binds, and
  `--allowed-host`); anything else is refused, so a DNS-rebinding page cannot talk to it.
- **Origin**: a state-changing request (anything but GET/HEAD/OPTIONS) and every websocket
  must come from this service's own origin when a browser sends one (`Origin`, or
  `Sec-Fetch-Site: cross-site`): another site's "simple" cross-site POST is refused before
  it reaches a route. Scripts and tools send no Origin and pass.
- **Headers**: a Content-Security-Policy with `frame-ancestors 'none'` and no third-party
  sources on every page (a route that sets its own policy keeps it), no framing, no MIME
  sniffing, no referrer.
"""

from __future__ import annotations

import ipaddress
from collections.abc import Iterable

from starlette.datastructures import Headers
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from backend.errors import ApiError, BadRequest, Forbidden, answer

SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")

# 'wasm-unsafe-eval': compiling WebAssembly (none of our pages needs eval of script text);
# inline styles: uPlot and Preact set element styles
CSP = (
    "default-src 'self'; script-src 'self' 'wasm-unsafe-eval'; "
    "style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; font-src 'self' data:; "
    "connect-src 'self'; worker-src 'self' blob:; object-src 'none'; base-uri 'none'; "
    "form-action 'self'; frame-ancestors 'none'"
)
HEADERS: tuple[tuple[bytes, bytes], ...] = (
    (b"x-frame-options", b"DENY"),
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"no-referrer"),
    (b"cross-origin-opener-policy", b"same-origin"),
)


def is_loopback(host: str) -> bool:
    """True for a loopback address or `localhost`."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def is_wildcard(host: str) -> bool:
    """True for an address that binds every interface (0.0.0.0, ::)."""
    try:
        return ipaddress.ip_address(host.strip("[]")).is_unspecified
    except ValueError:
        return False


def host_names(bind_host: str, allowed: Iterable[str]) -> frozenset[str]:
    """The Host names (without port, lower case) the service answers."""
    names = {*LOOPBACK_NAMES, *(a.strip().lower() for a in allowed if a.strip())}
    if not is_wildcard(bind_host):
        names.add(bind_host.lower())
    return frozenset(n.strip("[]") for n in names)


def _hostname(host_header: str) -> str:
    """The name part of a Host header: `[::1]:8000` -> `::1`, `a.b:80` -> `a.b`."""
    h = host_header.strip().lower()
    if h.startswith("["):
        return h[1 : h.find("]")] if "]" in h else ""
    return h.rsplit(":", 1)[0] if h.count(":") == 1 else h


class Perimeter:
    """ASGI middleware: Host and Origin checks, security headers."""

    def __init__(self, app: ASGIApp, hosts: frozenset[str]) -> None:
        self.app = app
        self.hosts = hosts

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        kind = scope["type"]
        if kind not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = Headers(scope=scope)
        host = headers.get("host", "")
        why: ApiError | None = None
        if _hostname(host) not in self.hosts:
            why = BadRequest(f"Host {host!r} is not a name of this service")
        elif kind == "websocket" or scope["method"] not in SAFE_METHODS:
            why = self._cross_site(scope, headers, host)
        if why is not None:
            await self._refuse(scope, receive, send, why)
            return
        if kind == "websocket":
            await self.app(scope, receive, send)
            return

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                raw = list(message.get("headers", []))
                present = {k.lower() for k, _ in raw}
                if b"content-security-policy" not in present:
                    raw.append((b"content-security-policy", CSP.encode()))
                raw += [h for h in HEADERS if h[0] not in present]
                message = {**message, "headers": raw}
            await send(message)

        await self.app(scope, receive, with_headers)

    @staticmethod
    def _cross_site(scope: Scope, headers: Headers, host: str) -> Forbidden | None:
        origin = headers.get("origin")
        if origin is not None:
            scheme = {"ws": "http", "wss": "https"}.get(scope["scheme"], scope["scheme"])
            if origin.lower() != f"{scheme}://{host}".lower():
                return Forbidden(f"requests from {origin} may not change anything here")
        if headers.get("sec-fetch-site") == "cross-site":
            return Forbidden("cross-site requests may not change anything here")
        return None

    @staticmethod
    async def _refuse(scope: Scope, receive: Receive, send: Send, e: ApiError) -> None:
        if scope["type"] == "websocket":
            # closing before accepting: the client gets an HTTP 403
            await send({"type": "websocket.close", "code": 1008, "reason": str(e)[:120]})
            return
        await answer(e)(scope, receive, send)
