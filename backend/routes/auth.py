"""What answers without a session: health, logging in and out, one-time links; and who am I
and the telemetry websocket tickets (with one)."""

from __future__ import annotations

from dataclasses import replace

from fastapi import APIRouter, Request, Response
from fastapi.responses import HTMLResponse, RedirectResponse

from api.auth import (
    CSRF_COOKIE,
    SESSION_COOKIE,
    Action,
    LoginRequest,
    Me,
    Role,
    SharedMachine,
    WsTicket,
)
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import (
    NO_CONTENT,
    SEE_OTHER,
    ApiError,
    NotLoggedIn,
    TooManyAttempts,
    http_status,
    responses,
)
from backend.services.accounts import SESSION_S, User, public_id
from backend.services.audit_log import Entry
from backend.services.auth import Actor

router = APIRouter(tags=["auth"])


def _page(title: str, body: str) -> str:
    """A page of its own for a link that no longer opens anything: the HMI's look, what
    happened and the way on (the HMI itself needs a session)."""
    return f"""<!doctype html><html lang="en"><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1"><title>Inbetrieb</title>
<style>body{{margin:0;font:15px/1.45 system-ui,sans-serif;background:#f3f5f8;color:#1b2430}}
header{{background:#1b2430;color:#fff;padding:10px 16px;font-weight:700;font-size:18px}}
main{{max-width:560px;margin:48px auto;background:#fff;border:1px solid #cfd6de;
border-radius:6px;padding:18px 22px}}h1{{font-size:18px;margin:0 0 10px}}a{{color:#0b63b6}}
</style><header>Inbetrieb</header><main><h1>{title}</h1>{body}</main></html>"""


_LINK_USED = _page(
    "This login link was used already or has expired",
    "<p>A class seat's link logs in once. If your class is still running, ask your "
    "instructor for a new link to your seat. Otherwise <a href='/'>log in</a> with your "
    "name and password.</p>",
)

_SHARE_ENDED = _page(
    "This share link has ended",
    "<p>It expired or was revoked. Ask whoever sent it for a new one.</p>"
    "<p>Have an account on this service? <a href='/'>Log in</a>.</p>",
)


@router.get("/share/{token}", include_in_schema=False)
def share_link(token: str, request: Request, services: ServicesDep) -> Response:
    """A share link: a guest session watching its machine, then the HMI on that machine."""
    found = services.shares.redeem(token[:200])
    address = request.client.host if request.client else "?"
    if found is None:
        failed = Entry("", "", "login_failed", "share link", outcome="expired or revoked")
        services.audit.record_later(replace(failed, address=address))
        return HTMLResponse(_SHARE_ENDED, status_code=http_status(NotLoggedIn))
    link, guest = found
    response = RedirectResponse(f"/#{link.machine}/operate", status_code=SEE_OTHER)
    actor = _start_session(response, request, services, User(guest, Role.OBSERVER))
    what = f"opened share link {link.id} ({link.label or 'no label'}) of {link.machine}"
    services.audit.record_later(
        Entry(actor.name, actor.session, "login", what, link.machine, address=address)
    )
    return response


@router.get("/api/health")
def health() -> dict[str, str]:
    return {"status": "ok"}


def _start_session(
    response: Response, request: Request, services: ServicesDep, user: User
) -> Actor:
    sid, csrf = services.accounts.new_session(user.name)
    secure = request.url.scheme == "https"  # behind a TLS proxy too (its forwarded scheme)
    common = {"max_age": int(SESSION_S), "samesite": "strict", "secure": secure, "path": "/"}
    response.set_cookie(SESSION_COOKIE, sid, httponly=True, **common)  # type: ignore[arg-type]
    response.set_cookie(CSRF_COOKIE, csrf, **common)  # type: ignore[arg-type]
    return Actor(user.name, Role(user.role), public_id("session", sid))


@router.post(
    "/api/auth/login",
    responses=responses(
        NotLoggedIn,
        why={NotLoggedIn: "wrong name or password", TooManyAttempts: "too many failed logins"},
    ),
)
def login(body: LoginRequest, request: Request, response: Response, services: ServicesDep) -> Me:
    """Log in: the session and CSRF cookies are set (HttpOnly and SameSite=Strict)."""
    address = request.client.host if request.client else "?"
    accounts = services.accounts

    def refused(e: ApiError) -> ApiError:
        services.audit.record_later(
            Entry(body.name, "", "login_failed", "login", outcome=str(e), address=address)
        )
        return e

    if accounts.throttled(address):
        raise refused(TooManyAttempts("too many failed logins: wait a minute"))
    user = accounts.check_password(body.name, body.password)
    if user is None:
        accounts.failed(address)
        raise refused(NotLoggedIn("wrong name or password"))
    actor = _start_session(response, request, services, user)
    services.audit.record_later(
        Entry(actor.name, actor.session, "login", "login with password", address=address)
    )
    return actor.me


@router.post("/api/auth/logout", status_code=NO_CONTENT, response_class=Response)
def logout(request: Request, services: ServicesDep) -> Response:
    """End this session (the cookies go too)."""
    sid = request.cookies.get(SESSION_COOKIE)
    session = services.accounts.session(sid) if sid else None
    if sid:
        services.classes.forget_result(sid)  # an ended seat's result shows no more
    if sid and session is not None:
        services.accounts.end_session(sid)
        key = public_id("session", sid)
        services.control.end_session(key, f"{session.user.name} logged out")
        services.sessions.poke()  # its websockets close now
        services.audit.record_later(Entry(session.user.name, key, "logout", "logout"))
    response = Response(status_code=NO_CONTENT)
    response.delete_cookie(SESSION_COOKIE, path="/")
    response.delete_cookie(CSRF_COOKIE, path="/")
    return response


@router.get("/api/auth/me", dependencies=[permit(Action.OBSERVE)], responses=responses(NotLoggedIn))
async def me(actor: ActorDep, services: ServicesDep) -> Me:
    """Who this session (or API token) is; a guest also what link they came through."""
    found = actor.me
    guest = services.shares.guest(actor.name) if actor.guest else None
    if guest is not None:
        found.share = SharedMachine(
            machine=guest.machine, label=guest.label, expires_unix=guest.expires
        )
    return found


@router.post(
    "/api/auth/ws-ticket", dependencies=[permit(Action.OBSERVE)], responses=responses(NotLoggedIn)
)
async def ws_ticket(actor: ActorDep, services: ServicesDep) -> WsTicket:
    """A ticket that opens one websocket as this session (and browser tab) within
    `expires_in_s`, once: `/api/machines/{mid}/telemetry?ticket=...` or (instructors) the
    console's `/api/classes/{cid}/grid?ticket=...`. Browsers cannot send
    headers on a websocket, and the session cookie alone is refused there."""
    lifetime_s = services.settings.ws_ticket_s
    ticket = services.accounts.issue_ws_ticket(actor, lifetime_s)
    return WsTicket(ticket=ticket, expires_in_s=lifetime_s)


@router.get("/auth/once", include_in_schema=False)
def once(token: str, request: Request, services: ServicesDep) -> Response:
    """A one-time login link (printed at start on loopback): a session, then the HMI."""
    user = services.accounts.redeem_once(token[:200])
    address = request.client.host if request.client else "?"
    if user is None:
        sid = request.cookies.get(SESSION_COOKIE)
        if sid and services.accounts.session(sid) is not None:  # clicked again, still in
            return RedirectResponse("/", status_code=SEE_OTHER)
        services.audit.record_later(
            Entry(
                "", "", "login_failed", "one-time link", outcome="used or expired", address=address
            )
        )
        return HTMLResponse(_LINK_USED, status_code=http_status(NotLoggedIn))
    response = RedirectResponse("/", status_code=SEE_OTHER)
    actor = _start_session(response, request, services, user)
    services.classes.joined(user.name)  # a seat's first login starts its clock
    services.audit.record_later(
        Entry(actor.name, actor.session, "login", "login with a one-time link", address=address)
    )
    return response
