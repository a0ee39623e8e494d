"""Who is asking: every request to the API, the telemetry websockets and the Rerun viewer
needs an API token (`Authorization: Bearer`) or a login session (cookie), checked before the
request reaches a route (so even a malformed request of a stranger gets only 401), and a
state-changing request on a session must echo the session's CSRF token.

A websocket cannot send headers from a browser and a cookie alone would let any page the
browser shows open one, so a websocket needs an API token or a one-time ticket its page
fetched with the session (`POST /api/auth/ws-ticket`, as Moonraker does); the session cookie
alone is refused.

Open without either: health, logging in, one-time login links, an ended class seat's
result (by the cookie of the session the end took away), and the static pages (the HMI
shows its login screen; the docs describe the API).
"""

from __future__ import annotations

import secrets
from dataclasses import replace

from starlette.requests import HTTPConnection
from starlette.types import ASGIApp, Receive, Scope, Send

from api.auth import CLIENT_HEADER, CSRF_HEADER, SESSION_COOKIE
from backend.errors import Forbidden, NotLoggedIn, answer
from backend.security import SAFE_METHODS
from backend.services.accounts import Accounts, public_id
from backend.services.auth import Actor
from backend.services.shares import PREFIX as GUEST_PREFIX

# an ended class's seat result: its login has gone, the old session cookie names the seat
OPEN_PATHS = frozenset(
    {"/api/health", "/api/auth/login", "/api/auth/logout", "/api/auth/seat-result"}
)
GUARDED_PREFIXES = ("/api/", "/rerun", "/metrics")


def guarded(path: str) -> bool:
    """Whether this path needs a token or a session."""
    return path.startswith(GUARDED_PREFIXES) and path not in OPEN_PATHS


def identify(accounts: Accounts, conn: HTTPConnection) -> Actor | NotLoggedIn | Forbidden:
    """The actor behind a request, or the refusal saying why there is none."""
    kind = conn.scope["type"]
    # a browser tab's id: websockets cannot send headers, so they name it in the query
    client = (conn.headers.get(CLIENT_HEADER) or conn.query_params.get("client") or "")[:64]
    ticket = conn.query_params.get("ticket")
    if ticket is not None and (kind == "websocket" or conn.scope["method"] == "GET"):
        actor = accounts.redeem_ticket(ticket, kind, conn.scope["path"])
        if actor is None:
            return NotLoggedIn("unknown, used or expired ticket")
        return actor if actor.client or not client else replace(actor, client=client)
    auth = conn.headers.get("authorization", "")
    if auth[:7].lower() == "bearer ":
        token = auth[7:].strip()
        user = accounts.token_user(token)
        if user is None:
            return NotLoggedIn("unknown or revoked API token")
        return Actor(user.name, user.role, public_id("token", token), client)
    if kind == "websocket":
        return NotLoggedIn("a websocket needs a ticket (POST /api/auth/ws-ticket) or an API token")
    sid = conn.cookies.get(SESSION_COOKIE)
    session = accounts.session(sid) if sid else None
    if session is None or not sid:
        return NotLoggedIn("the session has ended: log in again" if sid else "not logged in")
    if conn.scope["method"] not in SAFE_METHODS:
        sent = conn.headers.get(CSRF_HEADER, "")
        if not secrets.compare_digest(sent.encode(), session.csrf.encode()):
            return Forbidden(f"missing or wrong {CSRF_HEADER} header")
    user = session.user
    return Actor(user.name, user.role, public_id("session", sid), client)


class Authentication:
    """ASGI middleware: the actor in `scope["state"]["actor"]`, or a refusal."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket") or not guarded(scope["path"]):
            await self.app(scope, receive, send)
            return
        conn = HTTPConnection(scope)
        services = scope["app"].state.services
        found = identify(services.accounts, conn)
        if isinstance(found, Actor):
            guest = services.shares.guest(found.name)
            if guest is not None:  # a share link's: its machine only, watching
                found = replace(found, seat=guest.machine, guest=True)
            elif found.name.startswith(GUEST_PREFIX):  # its link expired or was revoked
                found = NotLoggedIn("the share link has expired or was revoked")
        if isinstance(found, Actor):
            seat = services.classes.seat_of(found.name)  # a student sees their seat only
            if seat:  # and the machine their instructor presents, watching
                found = replace(found, seat=seat, watches=services.classes.presented_to(seat))
            scope.setdefault("state", {})["actor"] = found
            await self.app(scope, receive, send)
            return
        if scope["type"] == "websocket":  # closed before the accept: an HTTP 403 for the client
            await send({"type": "websocket.close", "code": 1008, "reason": str(found)})
            return
        headers = {"www-authenticate": "Bearer"} if isinstance(found, NotLoggedIn) else None
        await answer(found, headers)(scope, receive, send)
