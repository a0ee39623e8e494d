"""API tokens for scripts: each user lists, creates and revokes their own; an admin anyone's.
A revoked token is refused from the next request, and its websockets close within seconds."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.auth import Action, TokenCreate, TokenCreated, TokenInfo
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import CREATED, NO_CONTENT, Forbidden, NotFound, responses
from backend.services.accounts import TokenEntry, public_id
from backend.services.audit_log import Entry
from backend.services.auth import authorize

router = APIRouter(prefix="/api/auth/tokens", tags=["auth"])


def token_info(t: TokenEntry) -> TokenInfo:
    return TokenInfo(
        id=t.id, user=t.user, label=t.label, created_unix=t.created, last_used_unix=t.last_used
    )


@router.get("", dependencies=[permit(Action.OBSERVE)], responses=responses(Forbidden))
def list_tokens(services: ServicesDep, actor: ActorDep, all: bool = False) -> list[TokenInfo]:
    """The requesting user's API tokens; everyone's with `all=true` (admins)."""
    if all:
        authorize(actor, Action.USERS)
    return [token_info(t) for t in services.accounts.tokens(None if all else actor.name)]


@router.post("", status_code=CREATED, dependencies=[permit(Action.TOKENS)])
def create_token(req: TokenCreate, services: ServicesDep, actor: ActorDep) -> TokenCreated:
    """A new API token of the requesting user, shown this once."""
    token = services.accounts.new_token(actor.name, req.label)
    info = token_info(services.accounts.token(public_id("token", token)))
    services.audit.record(
        Entry(
            actor.name,
            actor.session,
            "token",
            f"created API token {info.id}",
            detail={"token": info.id, "user": actor.name, "label": req.label},
        )
    )
    return TokenCreated(token=token, info=info)


@router.delete(
    "/{tid}",
    status_code=NO_CONTENT,
    response_class=Response,
    dependencies=[permit(Action.TOKENS)],
    responses=responses(Forbidden, NotFound),
)
def revoke_token(tid: str, services: ServicesDep, actor: ActorDep) -> Response:
    """Revoke an API token (one's own; an admin anyone's)."""
    attempt = Entry(actor.name, actor.session, "token", f"revoke API token {tid}")
    token = services.accounts.token(tid)  # none: 404, not recorded as a refusal
    with services.audit.refusals(attempt):  # another's token, and no admin
        if token.user != actor.name:
            authorize(actor, Action.USERS)
    services.accounts.revoke_token(tid)
    services.sessions.poke()  # its websockets and control go now
    services.audit.record(
        Entry(
            actor.name,
            actor.session,
            "token",
            f"revoked API token {tid}",
            detail={"token": tid, "user": token.user, "label": token.label},
        )
    )
    return Response(status_code=NO_CONTENT)
