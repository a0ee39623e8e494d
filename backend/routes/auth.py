"""What answers without a session: health, logging in and out, who am I, one-time links."""

from __future__ import annotations

from fastapi import APIRouter, Request, Response
from fastapi.responses import HTMLResponse, RedirectResponse

from api.auth import CSRF_COOKIE, SESSION_COOKIE, LoginRequest, Me
from backend.deps import ActorDep, ServicesDep
from backend.errors import ApiError, responses
from backend.services.accounts import SESSION_S

router = APIRouter(tags=["auth"])

_LINK_USED = """<!doctype html><meta charset="utf-8"><title>Inbetrieb</title>
<p>This login link was used already or has expired. <a href="/">Log in</a> with your name
and password, or restart the service for a new link.</p>"""


@router.get("/api/health")
def health() -> dict[str, str]:
    return {"status": "ok"}


def _start_session(response: Response, request: Request, services: ServicesDep, me: Me) -> None:
    sid, csrf = services.accounts.new_session(me.name)
    secure = request.url.scheme == "https"  # behind a TLS proxy too (its forwarded scheme)
    common = {"max_age": int(SESSION_S), "samesite": "strict", "secure": secure, "path": "/"}
    response.set_cookie(SESSION_COOKIE, sid, httponly=True, **common)  # type: ignore[arg-type]
    response.set_cookie(CSRF_COOKIE, csrf, **common)  # type: ignore[arg-type]


@router.post(
    "/api/auth/login",
    responses=responses(401, why={401: "wrong name or password", 429: "too many failed logins"}),
)
def login(body: LoginRequest, request: Request, response: Response, services: ServicesDep) -> Me:
    """Log in: the session and CSRF cookies are set (HttpOnly and SameSite=Strict)."""
    address = request.client.host if request.client else "?"
    accounts = services.accounts
    if accounts.throttled(address):
        raise ApiError(429, {"message": "too many failed logins: wait a minute"})
    me = accounts.check_password(body.name, body.password)
    if me is None:
        accounts.failed(address)
        raise ApiError(401, {"message": "wrong name or password"})
    _start_session(response, request, services, me)
    return me


@router.post("/api/auth/logout", status_code=204, response_class=Response)
def logout(request: Request, services: ServicesDep) -> Response:
    """End this session (the cookies go too)."""
    sid = request.cookies.get(SESSION_COOKIE)
    if sid:
        services.accounts.end_session(sid)
    response = Response(status_code=204)
    response.delete_cookie(SESSION_COOKIE, path="/")
    response.delete_cookie(CSRF_COOKIE, path="/")
    return response


@router.get("/api/auth/me", responses=responses(401))
async def me(actor: ActorDep) -> Me:
    """Who this session (or API token) is."""
    return Me(name=actor.name, role=actor.role)


@router.get("/auth/once", include_in_schema=False)
def once(token: str, request: Request, services: ServicesDep) -> Response:
    """A one-time login link (printed at start on loopback): a session, then the HMI."""
    me = services.accounts.redeem_once(token[:200])
    if me is None:
        return HTMLResponse(_LINK_USED, status_code=401)
    response = RedirectResponse("/", status_code=303)
    _start_session(response, request, services, me)
    return response
